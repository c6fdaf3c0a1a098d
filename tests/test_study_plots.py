"""The eating study's figures: the headline's N and the cohort, our statistic, censored bars, alignment's n.

Synthetic tables of 12 participants: every bar's value is set by its group alone, so a bar's
height says which group it is, whatever order seaborn draws in. Unfinished episodes: LA+SA
Dessert of participants 0-2 (both panels) and LA Entree of participant 11 (the cohort only).
"""

from __future__ import annotations

import io

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from lasa.base.conditions import CONDITIONS
from lasa.base.errors import ConfigError
from lasa.experiments.study import plots

matplotlib.use("Agg")

N = 12
TASKS = ("Entree", "Dessert")
PHASES = ("stab", "scoop", "dip")
UNFINISHED = {(p, "LA+SA", "Dessert") for p in (0, 1, 2)} | {(11, "LA", "Entree")}
# (participant, condition, phase) of Dessert not reached: steps 0, alignment NaN
NOT_REACHED = {(0, "LA+SA", "scoop"), (0, "LA+SA", "dip"), (1, "LA+SA", "dip"), (11, "R+SA", "dip")}


@pytest.fixture(scope="module", autouse=True)
def _fast_and_closed():
    """Fewer bootstrap resamples than the figures' 1000 (seaborn's bootstrap is most of a figure's time)."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setitem(plots.CI, "n_boot", 100)
        yield
    plt.close("all")


def _keys(p: int, cond: str) -> dict[str, object]:
    asst = "hindsight" if cond.endswith("+SA") else "none"
    decoder = "transfers" if cond.startswith("LA") else "none"
    return dict(
        robot="panda", participant=p, condition=cond, assistance=asst, decoder=decoder, model="planning"
    )


def _value(cond: str, task: str) -> float:
    """Each (task, condition)'s Goal Error: 1..4 for Entree, 5..8 for Dessert."""
    return 1.0 + CONDITIONS.index(cond) + 4 * TASKS.index(task)


def _alignment_value(cond: str, phase: str) -> float:
    return 0.3 + 0.05 * CONDITIONS.index(cond) + 0.2 * PHASES.index(phase)


def _episodes():
    return [(p, c, t) for p in range(N) for c in CONDITIONS for t in TASKS]


@pytest.fixture(scope="module")
def time() -> pd.DataFrame:
    rows = []
    for p, c, t in _episodes():
        total = 10 * _value(c, t)  # 10..80; idle 0.3 of it: 3..24, never a total
        done = (p, c, t) not in UNFINISHED
        rows.append(dict(_keys(p, c), task=t, total_time=total, idle_time=0.3 * total, completed=done))
    return pd.DataFrame(rows)


@pytest.fixture(scope="module")
def goal_error() -> pd.DataFrame:
    rows = [dict(_keys(p, c), task=t, order=0, goal_error=_value(c, t)) for p, c, t in _episodes()]
    return pd.DataFrame(rows)


@pytest.fixture(scope="module")
def alignment() -> pd.DataFrame:
    rows = []
    for p, c, t in _episodes():
        for phase in (*PHASES, "plate") if t == "Dessert" else ("reach", "stab", "cut", "plate"):
            reached = (p, c, phase) not in NOT_REACHED
            value = _alignment_value(c, phase) if phase in PHASES and t == "Dessert" else 0.99
            rows.append(
                dict(
                    _keys(p, c),
                    task=t,
                    phase=phase,
                    alignment=value if reached else float("nan"),
                    steps=20 if reached else 0,
                )
            )
    return pd.DataFrame(rows)


def _bars(fig: Figure, groups: dict[float, object]) -> list[dict[object, Rectangle]]:
    """Per panel, its bars by group (read off their heights), every expected bar found once."""
    out = []
    for sub in fig.subfigs:
        found: dict[object, Rectangle] = {}
        for ax in sub.axes:
            for patch in ax.patches:
                match = [g for h, g in groups.items() if patch.get_height() == pytest.approx(h)]
                if isinstance(patch, Rectangle) and match:
                    assert match[0] not in found
                    found[match[0]] = patch
        assert set(found) == set(groups.values())
        out.append(found)
    return out


STATS = {"headline": "ours (10): SA − no SA = +1.24 m s, F(1,9) = 32.8, p < .001", "cohort": "ours (12): x"}


@pytest.fixture(scope="module")
def drawn(goal_error, time, alignment) -> dict[str, Figure]:
    """The three figures of the 12 participants, with our statistic per panel (drawn once: they are slow)."""
    return {
        "goal_error": plots.plot_goal_error(goal_error, decoder="transfers", stats=STATS, completed=time),
        "time": plots.plot_time(time, decoder="transfers", horizon=150.0, stats=STATS),
        "alignment": plots.plot_alignment(alignment, decoder="transfers", stats=STATS, completed=time),
    }


def _hatched(fig: Figure) -> int:
    return sum(bool(p.get_hatch()) for ax in fig.axes for p in ax.patches)


def _legend_text(fig: Figure) -> str:
    return " ".join(t.get_text() for leg in fig.legends for t in leg.get_texts())


def _goal_error_groups() -> dict[float, object]:
    return {_value(c, t): (t, c) for c in CONDITIONS for t in TASKS}


def _alignment_groups() -> dict[float, object]:
    return {_alignment_value(c, ph): (ph, c) for c in CONDITIONS for ph in PHASES}


def test_the_headline_is_the_first_ten_and_the_cohort_a_second_panel(goal_error, time, alignment, drawn):
    for fig in drawn.values():
        assert len(fig.subfigs) == 2
        head, cohort = (sub.get_suptitle() for sub in fig.subfigs)
        assert "first 10 simulated participants" in head and "cohort" not in head
        assert cohort.startswith(f"cohort of {N} (a reading)")
    few = [
        plots.plot_goal_error(goal_error[goal_error.participant < 10], completed=time),
        plots.plot_time(time[time.participant < 10]),
        plots.plot_alignment(alignment[alignment.participant < 3], completed=time),
    ]
    for fig, n in zip(few, (10, 10, 3), strict=True):
        assert len(fig.subfigs) == 1
        assert fig.subfigs[0].get_suptitle().startswith(f"first {n} simulated participants")


def test_goal_error_hatches_the_censored_bars_only(drawn):
    fig = drawn["goal_error"]
    head, cohort = _bars(fig, _goal_error_groups())
    assert {g for g, bar in head.items() if bar.get_hatch()} == {("Dessert", "LA+SA")}
    assert {g for g, bar in cohort.items() if bar.get_hatch()} == {("Dessert", "LA+SA"), ("Entree", "LA")}
    assert _hatched(fig) == 3  # no other patch (dots, legend) is hatched
    assert plots.CENSORED in _legend_text(fig)


def test_goal_error_takes_completion_from_its_own_column_and_needs_every_episode(goal_error, time):
    own = goal_error.merge(time[[*plots.ROW_KEYS, "completed"]], on=list(plots.ROW_KEYS))
    assert _hatched(plots.plot_goal_error(own[own.participant < 10], decoder="transfers")) == 1
    unmarked = plots.plot_goal_error(goal_error[goal_error.participant < 10], decoder="transfers")
    assert _hatched(unmarked) == 0 and "completion not given" in _legend_text(unmarked)
    with pytest.raises(ConfigError, match="completed has no row"):
        plots.plot_goal_error(goal_error, decoder="transfers", completed=time[time.participant != 4])


def test_time_hatches_the_censored_bars_only(drawn):
    fig = drawn["time"]
    groups = {10 * h: g for h, g in _goal_error_groups().items()}
    head, cohort = _bars(fig, groups)
    assert {g for g, bar in head.items() if bar.get_hatch()} == {("Dessert", "LA+SA")}
    assert {g for g, bar in cohort.items() if bar.get_hatch()} == {("Dessert", "LA+SA"), ("Entree", "LA")}
    assert _hatched(fig) == 3  # the Idle Time bars drawn over them are not
    legend = _legend_text(fig)
    assert "some episodes cut at the horizon (a lower bound; censored at the 150 s horizon)" in legend


def test_time_dodges_the_total_and_idle_whiskers_apart(drawn):
    """Each bar's two intervals sit on either side of its centre, inside it, each in its own colour:
    read off the figure's lines by their height (each group's times are constant: a zero-length
    whisker at its mean), Total at 10 x the group's value and Idle at 3 x."""
    fig = drawn["time"]
    for sub in fig.subfigs:
        for ax, task in zip(sub.axes, TASKS, strict=True):
            at: dict[tuple[str, str], tuple[float, str]] = {}
            for line in ax.lines:
                y = np.asarray(line.get_ydata(), dtype=float)
                for cond in CONDITIONS:
                    for measure, scale in (("total", 10), ("idle", 3)):
                        if len(y) and np.allclose(y, scale * _value(cond, task)):
                            assert (cond, measure) not in at
                            at[cond, measure] = (float(line.get_xdata()[0]), line.get_color())
            assert len(at) == 2 * len(CONDITIONS)
            for i, cond in enumerate(CONDITIONS):
                (x_total, c_total), (x_idle, c_idle) = at[cond, "total"], at[cond, "idle"]
                assert i - 0.4 < x_total < i < x_idle < i + 0.4  # dodged apart, inside the bar
                assert c_total != c_idle
    legend = _legend_text(fig)
    assert "Total Time's 95% CI: whisker left of the bar's centre" in legend
    assert "Idle Time's 95% CI: whisker right of the bar's centre" in legend


def _alignment_hatches(fig: Figure, given: bool) -> None:
    head, cohort = _bars(fig, _alignment_groups())
    la_sa = {(ph, "LA+SA") for ph in PHASES} if given else {("scoop", "LA+SA"), ("dip", "LA+SA")}
    assert {g for g, bar in head.items() if bar.get_hatch()} == la_sa
    assert {g for g, bar in cohort.items() if bar.get_hatch()} == la_sa | {("dip", "R+SA")}
    assert _hatched(fig) == 2 * len(la_sa) + 1
    legend = _legend_text(fig)
    assert "did not reach the phase" in legend
    assert ("some episodes cut at the horizon" in legend) == given


def test_alignment_hatches_unfinished_or_unreached_bars(alignment, drawn):
    _alignment_hatches(drawn["alignment"], given=True)  # LA+SA's Dessert unfinished: all its phases
    _alignment_hatches(plots.plot_alignment(alignment, decoder="transfers"), given=False)


def test_alignment_says_the_n_of_every_bar(drawn):
    fig = drawn["alignment"]
    expected = [{g: 10 for g in _alignment_groups().values()}, {g: 12 for g in _alignment_groups().values()}]
    for panel, n in zip(expected, (10, 12), strict=True):
        panel[("scoop", "LA+SA")], panel[("dip", "LA+SA")] = n - 1, n - 2
    expected[1][("dip", "R+SA")] = 11
    for sub, bars, want in zip(fig.subfigs, _bars(fig, _alignment_groups()), expected, strict=True):
        (ax,) = sub.axes
        labels = {round(t.xy[0], 3): t.get_text() for t in ax.texts if t.get_text().startswith("n=")}
        assert len(labels) == len(want)
        for group, bar in bars.items():
            assert labels[round(bar.get_x() + bar.get_width() / 2, 3)] == f"n={want[group]}", group


def test_our_statistic_is_printed_per_panel_beside_the_papers(time, drawn):
    for name, h in (("goal_error", "h1"), ("time", "h3"), ("alignment", "h2")):
        fig = drawn[name]
        assert plots.PAPER_H[h] in fig.get_suptitle().replace("\n", " ")
        for sub, key in zip(fig.subfigs, ("headline", "cohort"), strict=True):
            assert STATS[key] in sub.get_suptitle().replace("\n", " ")
    only_head = plots.plot_time(time, stats={"headline": "ours (10): y"})
    assert "ours (10): y" in only_head.subfigs[0].get_suptitle()
    assert "ours" not in only_head.subfigs[1].get_suptitle()
    bare = plots.plot_time(time[time.participant < 10])
    assert bare.subfigs[0].get_suptitle().count("\n") == 0  # no stats: nothing extra
    with pytest.raises(ConfigError, match="stats keys"):
        plots.plot_time(time, stats={"main": "ours"})


def test_the_figures_are_the_same_run_after_run(goal_error, time):
    def png() -> bytes:
        buf = io.BytesIO()
        part = goal_error[goal_error.participant < 10]
        plots.plot_goal_error(part, completed=time).savefig(buf, format="png", dpi=40)
        return buf.getvalue()

    assert png() == png()


def test_specs_keep_their_names_and_columns():
    assert [s.NAME for s in (plots.GOAL_ERROR, plots.TIME, plots.ALIGNMENT)] == [
        "study_goal_error",
        "study_time",
        "study_alignment",
    ]
    assert "completed" in plots.TIME.COLUMNS and "completed" not in plots.GOAL_ERROR.COLUMNS


def test_video_clips_take_one_participants_episode_under_each_condition():
    from types import SimpleNamespace

    import numpy as np

    from lasa.base.config import NO_ASSISTANCE

    members = ("hindsight", "grasp_set", NO_ASSISTANCE)
    keys = [(p, c, a, t) for p in (0, 1) for c in CONDITIONS for a in members
            if (a == NO_ASSISTANCE) != c.endswith("+SA") for t in TASKS]  # fmt: skip
    n_steps = 12
    states = (
        np.arange(n_steps)[:, None, None] + 100 * np.arange(len(keys))[None, :, None] + np.zeros((1, 1, 7))
    )
    episodes = SimpleNamespace(
        participant=np.array([k[0] for k in keys]),
        condition=np.array([k[1] for k in keys]),
        assistance=np.array([k[2] for k in keys]),
        task=np.array([k[3] for k in keys]),
        end=np.array([5 + CONDITIONS.index(k[1]) for k in keys]),
        states=states,
    )
    clips = plots.video_clips(episodes, 1, "grasp_set", stride=2, dt=0.1)
    assert len(clips) == len(CONDITIONS)
    for cond, (frames, captions) in zip(CONDITIONS, clips, strict=True):
        e = keys.index((1, cond, "grasp_set" if cond.endswith("+SA") else NO_ASSISTANCE, "Dessert"))
        steps = np.arange(0, 5 + CONDITIONS.index(cond) + 1, 2)  # up to the episode's end
        assert (frames == states[steps, e]).all()
        assert captions == [f"{cond}  t = {s * 0.1:.1f} s" for s in steps]
    with pytest.raises(ConfigError, match="participant 2"):
        plots.video_clips(episodes, 2, "grasp_set", stride=2, dt=0.1)
