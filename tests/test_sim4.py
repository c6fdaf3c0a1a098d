"""Fig. sim4's measure (the cup on the table, the grasp at the gripper), its readings and its plot."""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from lasa.base.errors import ConfigError
from lasa.evidence.verdicts import assess, member_frame
from lasa.experiments import sim4
from lasa.experiments.sim4 import analysis, episodes
from lasa.experiments.sim4.episodes import map_geometry, new_cup_positions
from lasa.experiments.sim4.figure import other_share_text
from lasa.method.context_map import extend_task, new_goal_frames

REF = 1


def test_grasp_error_of_the_held_training_grasp_is_the_cup_distance(task):
    """A robot that holds, at the training cup, the grasp the user wants at a new cup is off by the
    cup's distance on the table: y = x by construction (planar5's new cups are translates)."""
    config = sim4.Config(offsets=(0.08, 0.14, 0.2))
    theta = np.linspace(0.0, 1.0, 7)
    for offset, pos in zip(config.offsets, new_cup_positions(task, config), strict=True):
        big = extend_task(task, pos, REF)
        held, wanted = task.target(REF, theta), big.target(np.full(7, 2), theta)
        metres, degrees = episodes.grasp_error(task.robot, held, wanted)
        np.testing.assert_allclose(metres, offset, rtol=5e-3)  # IK tolerance and the spline
        np.testing.assert_allclose(degrees, 0.0, atol=0.5)  # the same approach direction
        # the wanted grasp's site is the new cup's grasp frame (by hand: the reference frame moved)
        frames, _ = new_goal_frames(task, REF, pos)
        at_grid, _ = episodes.grasp_error(task.robot, big.curves[-1], big.curves[-1])
        assert np.all(at_grid == 0.0)
        np.testing.assert_allclose(task.robot.grasp_positions(big.curves[-1]), frames, atol=2e-3)


def test_grasp_error_against_forward_kinematics_by_hand(task):
    arm = task.robot
    q = task.goals[REF]
    p, r = arm.grasp_pose(q)
    q2 = q + np.array([0.0, 0.0, 0.0, 0.0, 0.3])  # the last joint alone: the site turns about the wrist
    p2, r2 = arm.grasp_pose(q2)
    metres, degrees = episodes.grasp_error(arm, q2[None], q[None])
    assert metres[0] == pytest.approx(np.linalg.norm(p2 - p))
    assert degrees[0] == pytest.approx(np.degrees(np.arccos(np.clip(r[:, 2] @ r2[:, 2], -1, 1))))
    assert degrees[0] > 1.0  # the wrist's turn shows


def _rows(n_users: dict[str, int], big: float = 4.0) -> pd.DataFrame:
    """Synthetic sim4 rows under both measures: the headline's slopes differ from the joint ones."""
    rng = np.random.default_rng(0)
    out = []
    for robot, n in n_users.items():
        for d in (0.4, 0.7, 1.0):
            for h, (slope, slope_joint) in {
                "none": (1.0, 1.5),
                "straight_line": (0.11, 1.1),
                "grasp": (0.05, 0.01),
            }.items():
                err = slope * d + 0.01 * rng.normal(size=n)
                out.append(
                    pd.DataFrame(
                        {
                            "robot": robot,
                            "mapping": "without" if h == "none" else "with",
                            "distance": d,
                            "seed": np.arange(n),
                            "error": np.abs(err),
                            "h": h,
                            "assistance": "point",
                            "angle_error_deg": 10.0 * d,
                            "distance_joint": 0.9 * d,
                            "error_joint": slope_joint * 0.9 * d + 0.01 * rng.normal(size=n),
                        }
                    )
                )
    frame = pd.concat(out, ignore_index=True)
    frame.loc[(frame.h == "none") & (frame.distance == 1.0) & (frame.seed == 0), "error"] = big
    return frame


def test_headline_is_the_table_measure_and_joint_space_a_reading():
    frame = _rows({"panda": 8})
    claims = {c.id: c for c in sim4.claims(frame)}
    names = ("sim4.straight_line_linear", "sim4.grasp_linear", "sim4.no_map_training_goal")
    readings = ("", "@joint_space", "@intercept", "@joint_space+intercept")
    assert set(claims) == {name + reading for name in names for reading in readings}
    table, joint = analysis.fits(frame), analysis.fits(frame, "joint_space")
    assert claims["sim4.straight_line_linear"].values["slope"] == pytest.approx(
        table.loc["straight_line", "slope"]
    )
    assert claims["sim4.straight_line_linear@joint_space"].values["slope"] == pytest.approx(
        joint.loc["straight_line", "slope"]
    )
    assert claims["sim4.straight_line_linear"].values["slope"] == pytest.approx(0.11, abs=0.02)
    assert claims["sim4.straight_line_linear@joint_space"].values["slope"] == pytest.approx(1.1, abs=0.02)
    # the vectorized bootstrap gives numbers under the same ids, and the verdicts come out
    boot = sim4.boot_values(frame, np.ones((3, 8)))
    assert set(boot) == set(claims)
    for cid, values in boot.items():
        assert set(values) == set(claims[cid].values)
        for k, v in values.items():
            np.testing.assert_allclose(v, claims[cid].values[k], rtol=1e-9)
    judged = assess(sim4.claims, frame, n_boot=20, fast=sim4.boot_values)
    assert [c.id for c in judged] == [c.id for c in sim4.claims(frame)]


def test_notes_hold_numbers_only():
    frame = _rows({"panda": 8})
    frame.loc[(frame.h == "straight_line") & (frame.distance == 0.4), "error"] = 5.0  # above none there
    notes = [c.note for c in sim4.claims(frame) if c.note]
    assert notes
    allowed = (
        r"Above the no-map error at \d+ of \d+ cups\.",
        r"Mean approach-axis error [\d.]+° at the nearest cup, [\d.]+° at the farthest\.",
    )
    for note in notes:
        assert re.sub("|".join(allowed), "", note).strip() == "", note
    assert any(note.startswith("Above the no-map error at 1 of 3 cups.") for note in notes)


def _drawn_ys(ax) -> np.ndarray:
    """The y of everything drawn in ``ax`` (lines, points, error bars)."""
    ys = [np.asarray(line.get_ydata(), dtype=float) for line in ax.lines]
    for coll in ax.collections:
        offsets = np.asarray(coll.get_offsets(), dtype=float)
        if offsets.size:
            ys.append(offsets[:, 1])
        ys += [
            np.asarray(seg, dtype=float)[:, 1] for seg in getattr(coll, "get_segments", list)() if len(seg)
        ]
    return np.concatenate(ys)


def test_plot_shows_every_point_and_says_its_users():
    frame = _rows({"planar5": 6, "panda": 4}, big=4.0)
    fig = sim4.plot(frame)
    axes = fig.axes
    assert len(axes) == 4  # two panels, each with its panel of episodes
    for ax in axes:
        ys = _drawn_ys(ax)
        assert ax.get_ylim()[0] <= np.nanmin(ys) and ax.get_ylim()[1] >= np.nanmax(ys)
    assert max(ax.get_ylim()[1] for ax in axes) >= 4.0  # the outlier is in view
    title = fig._suptitle.get_text().replace("\n", " ")
    assert "users per point: planar5 6, panda 4" in title
    plt.close(fig)
    one = _rows({"panda": 5})
    fig = sim4.plot(one)
    title = fig._suptitle.get_text().replace("\n", " ")
    n = int(member_frame(one, "point").groupby(["h", "distance"]).seed.nunique().min())
    assert f"near-optimal users, {n} users per point" in title
    # the paper's y = 0.11x is drawn above our lines, in a style of its own
    ax = fig.axes[0]
    paper = next(line for line in ax.lines if line.get_label() == "paper, with the map: y = 0.11x")
    ours = [line for line in ax.lines if line.get_label().startswith(("straight-line", "grasp-to-grasp"))]
    assert ours and all(paper.get_zorder() > line.get_zorder() for line in ours)
    assert all(paper.get_linestyle() != line.get_linestyle() for line in ours)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("98.75% bootstrap interval" in t for t in labels)  # the verdicts' level
    plt.close(fig)


def test_map_geometry_on_planar5(task):
    config = sim4.Config(offsets=(0.08, 0.14, 0.2))
    geo = map_geometry(task, config)
    assert set(geo.index.get_level_values("h")) == {"grasp", "straight_line", "straight_line_ee"}
    # the grasp-to-grasp map is exact at the grasps up to its soft assignment, the gripper's line up
    # to the IK; the joint-space straight line is not
    assert (geo.xs("grasp", level="h").misfit_m < 0.005).all()
    assert (geo.xs("straight_line_ee", level="h").misfit_m < 0.002).all()
    line = geo.xs("straight_line", level="h")
    assert (line.misfit_m > 0.01).all() and line.misfit_m.is_monotonic_increasing
    assert (geo.branch_rad < 0.1).all() and (geo.margin_rad > 0).all()


def test_judged_rows_name_the_measure_then_the_member(model, task):
    from lasa.experiments.sweep import judge

    config = sim4.Config(
        offsets=(0.08, 0.11, 0.14),
        users=2,
        block=2,
        cap=2,
        horizon=6,
        n_boot=10,
        assistance=("point", "grasp_set"),
    )
    frame, outcome, _ = judge(sim4, model, task, task.robot.control, config)
    ids = {(c.id, c.assistance) for c in outcome.claims}
    for name in (
        "straight_line_linear",
        "grasp_linear",
        "no_map_training_goal",
        "straight_line_linear@ee_line",
    ):
        plain, reading = f"sim4.{name}", f"sim4.{name}{'+' if '@' in name else '@'}"
        assert {
            (plain, "point"),
            (f"{reading}joint_space", "point"),
            (f"{reading}grasp_set", "grasp_set"),
            (f"{reading}joint_space+grasp_set", "grasp_set"),
        } <= ids
        assert {
            (f"{reading}intercept", "point"),
            (f"{reading}joint_space+intercept+grasp_set", "grasp_set"),
        } <= ids
    # 4 claims x 2 measures x 2 fits, under each of the 2 members
    assert len(ids) == 32 and all(c.id.count("@") <= 1 for c in outcome.claims)
    assert {"end_goal", "angle_error_deg", "error_joint"} <= set(frame.columns)
    assert set(frame.end_goal) <= {"new", "reference", "other"}


def test_the_identity_and_map_sentences_state_the_committed_numbers():
    """Notebook 07's two result sentences come from lasa, and say what the committed rows hold."""
    frame = pd.read_csv(Path(__file__).resolve().parents[1] / "figures" / "sim4_new_goals.csv")
    for robot, part in frame[frame.assistance == "point"].groupby("robot"):
        said = analysis.identity_sentence(part)
        held = float(re.search(r"held at the training cup, the error is y = ([\d.]+)x", said).group(1))
        assert held == pytest.approx(1.0, abs=0.005)  # y = x by construction
        check = analysis.no_map_check(part)
        stayed = check.loc["without the map, belief ends on the training cup", "share"]
        assert f"over the {100 * stayed:.0f}% of episodes" in said and said.startswith(f"{robot}, ")
    bands = analysis.by_preference(frame[(frame.robot == "panda") & (frame.h == "straight_line")])
    assert set(bands.index.get_level_values("band")) == set(analysis.BANDS)  # every band, for the sentence


def test_origin_fit_by_hand():
    """slope = sum(xy) / sum(x^2), R^2 = 1 - SSE / sum(y^2) (uncentred), against the intercept fit."""
    x = np.array([1.0, 2.0, 3.0])
    assert analysis.fit_form(x, 2.0 * x, "origin") == pytest.approx((2.0, 0.0, 1.0))  # on y = 2x exactly
    # y = (1, 3, 2): sum(xy) = 13, sum(x^2) = 14, sum(y^2) = 14, so slope 13/14 and R^2 = 13^2/14^2;
    # with an intercept: mean (2, 2), Sxy = 1, Sxx = 2, Syy = 2, so y = 0.5x + 1 and R^2 = 1/(2*2)
    y = np.array([1.0, 3.0, 2.0])
    assert analysis.fit_form(x, y, "origin") == pytest.approx((13 / 14, 0.0, 169 / 196))
    assert analysis.fit_form(x, y, "intercept") == pytest.approx((0.5, 1.0, 0.25))
    frame = pd.DataFrame(
        {"h": "none", "distance": np.repeat(x, 2), "error": np.repeat(y, 2) + [-0.1, 0.1] * 3}
    )
    origin, intercept = analysis.fits(frame), analysis.fits(frame, form="intercept")
    assert origin.loc["none"].tolist()[:3] == pytest.approx([13 / 14, 0.0, 169 / 196])  # the cups' means
    assert intercept.loc["none"].tolist()[:3] == pytest.approx([0.5, 1.0, 0.25])
    with pytest.raises(ConfigError, match="form"):
        analysis.fits(frame, form="quadratic")


def test_headline_goes_through_the_origin_and_intercept_keeps_the_old_fit():
    frame = _rows({"panda": 8})
    claims = {c.id: c for c in sim4.claims(frame)}
    for kind, name in (("straight_line", "straight_line_linear"), ("none", "no_map_training_goal")):
        means = frame[frame.h == kind].groupby("distance").error.mean()
        d, m = means.index.to_numpy(), means.to_numpy()
        head, old = claims[f"sim4.{name}"], claims[f"sim4.{name}@intercept"]
        assert head.values["slope"] == pytest.approx((d @ m) / (d @ d))
        assert head.values["r2"] == pytest.approx(1 - ((m - head.values["slope"] * d) ** 2).sum() / (m @ m))
        slope, intercept = np.polyfit(d, m, 1)  # the old fit, by numpy's polynomial fit
        r2 = 1 - ((m - slope * d - intercept) ** 2).sum() / ((m - m.mean()) ** 2).sum()
        assert old.values["slope"] == pytest.approx(slope) and old.values["r2"] == pytest.approx(r2)
        assert f"y = {slope:.3f}x {intercept:+.3f}" in old.measured
        assert f"y = {head.values['slope']:.3f}x, R^2 (uncentred)" in head.measured


def _cups() -> pd.DataFrame:
    """Two cups of the no-map case and one of a map, by hand (see the test's numbers)."""
    rows = [
        ("none", 0.5, [1.0, 2.0, 6.0], ["reference", "other", "reference"]),
        ("none", 1.0, [0.5, 0.7, 3.0], ["other", "reference", "reference"]),
        ("grasp", 0.5, [0.1, 0.3, 0.2], ["new", "new", "other"]),
    ]
    return pd.concat(
        [
            pd.DataFrame(
                {
                    "robot": "panda",
                    "assistance": "point",
                    "h": h,
                    "distance": d,
                    "seed": range(3),
                    "error": err,
                    "end_goal": end,
                }
            )
            for h, d, err, end in rows
        ],
        ignore_index=True,
    )


def test_cup_columns_and_end_shares_by_hand():
    frame = _cups()
    out = analysis.with_cup_columns(frame)
    assert list(out.columns) == [*frame.columns, *episodes.CUP_COLUMNS]
    by_cup = out.groupby(["h", "distance"])[list(episodes.CUP_COLUMNS)].agg(["min", "max"])
    expected = {  # mean, median, share whose belief ends on the other training cup
        ("none", 0.5): (3.0, 2.0, 1 / 3),
        ("none", 1.0): (1.4, 0.7, 1 / 3),
        ("grasp", 0.5): (0.2, 0.2, 1 / 3),
    }
    for key, values in expected.items():
        for col, v in zip(episodes.CUP_COLUMNS, values, strict=True):
            assert by_cup.loc[key, (col, "min")] == pytest.approx(v) == by_cup.loc[key, (col, "max")]
    shares = analysis.end_shares(frame).loc["none"]
    assert shares.loc[1.0, "mean_left"] == pytest.approx(0.5)
    assert shares.loc[1.0, "mean_stayed"] == pytest.approx(1.85)
    assert shares.n.tolist() == [3, 3]


def test_medians_sentence_states_the_table():
    said = analysis.medians_sentence(_cups())
    assert said.startswith("panda, without the map, new cups at 0.50 and 1.00 D")
    assert "the median error is 2.00 and 0.70 D, the mean 3.00 and 1.40 D" in said
    assert "The belief of 33 and 33% of the users ends on the other training cup" in said
    assert "those users end 0.50 D from the wanted grasp on average, the others 1.85 D." in said
    # on the committed paper-scale rows, the numbers of end_shares (not typed ones)
    frame = pd.read_csv(Path(__file__).resolve().parents[1] / "figures" / "sim4_new_goals.csv")
    for _, part in frame[frame.assistance == "point"].groupby("robot"):
        table = analysis.end_shares(part).loc["none"]
        said = analysis.medians_sentence(part)
        assert f"{table['median'].iloc[-1]:.2f} D, the mean" in said
        assert f"and {100 * table.other.iloc[-1]:.0f}% of the users" in said


def test_every_episode_panel_is_labelled_and_the_medians_and_share_are_drawn():
    frame = _rows({"panda": 6}).assign(end_goal="reference")
    frame.loc[(frame.h == "none") & (frame.distance == 1.0) & (frame.seed < 3), "end_goal"] = "other"
    fig = sim4.plot(frame)
    main, side = fig.axes
    assert side.get_title() == "every episode"
    assert "episode" in side.get_ylabel() and "normalised" in side.get_ylabel()
    names = [t.get_text() for t in side.get_legend().get_texts()]
    assert names == ["without the map", "straight-line h (paper)", "grasp-to-grasp h (ours)"]
    labels = [t.get_text() for t in main.get_legend().get_texts()]
    assert "median per cup" in labels
    # the fits' labels are the lines through the origin, no intercept
    none = analysis.fits(frame).loc["none"]
    assert any(t.startswith(f"without the map: y = {none.slope:.2f}x, R²") for t in labels)
    # each cup's median drawn, hollow, at its x (markers moved a little apart per map)
    medians = frame[frame.h == "none"].groupby("distance").error.median()
    hollow = [c for c in main.collections if len(c.get_offsets()) == len(medians)]
    assert any(np.allclose(np.asarray(c.get_offsets())[:, 1], medians.to_numpy()) for c in hollow)
    texts = [t.get_text() for t in main.texts]
    assert other_share_text(frame) in texts
    assert "0% of users at the nearest cup, 50% at the farthest" in other_share_text(frame)
    plt.close(fig)
