"""The figures drawn from the committed CSVs say their N, keep probabilities on [0, 1], and clip nothing.

Each figure module of :data:`FIGURES` draws its committed CSV (``figures/``) with its
``plot(table)``. Its suptitle's N (one for every robot, or one per robot) must be the users
per point of the rows it shows: the distinct users (``seed``) per robot, method and point of
the headline member (:func:`lasa.evidence.verdicts.member_frame`). A figure module that draws
from a CSV is added with one line in :data:`FIGURES`.
"""

from __future__ import annotations

import functools
import re
from pathlib import Path
from types import ModuleType

import matplotlib
import numpy as np
import pandas as pd
import pytest
from matplotlib.axes import Axes
from matplotlib.collections import PathCollection
from matplotlib.figure import Figure
from matplotlib.path import Path as MplPath

from lasa.evidence.verdicts import USER, member_frame
from lasa.experiments import sim1, sim2, sim3, sim4, sweep

matplotlib.use("Agg")

FIGURES_DIR = Path(__file__).resolve().parents[1] / "figures"
HEADLINE = "point"  # the member ``plot`` draws by default
# name: (module, its CSV under figures/, the columns besides robot that make one point)
FIGURES: dict[str, tuple[ModuleType, str, tuple[str, ...]]] = {
    "sim1": (sim1, "sim1_fixed_expertise.csv", ("method", "beta")),
    "sim2": (sim2, "sim2_change_of_mind.csv", ("method", "change_step")),
    "sim3": (sim3, "sim3_learning_users.csv", ("method", "learner", "t")),
    "sim4": (sim4, "sim4_new_goals.csv", ("h", "distance")),
}
PROBABILITY = re.compile(r"confidence|success|share|probability", re.IGNORECASE)
LIMITS = (-0.05, 1.05)  # a probability axis lies within these, and shows all of [0, 1] [-]


@functools.cache
def _table(name: str) -> pd.DataFrame:
    return pd.read_csv(FIGURES_DIR / FIGURES[name][1])


@functools.cache
def _figure(name: str) -> Figure:
    return FIGURES[name][0].plot(_table(name))


def title_ns(title: str) -> dict[str | None, tuple[int, int]]:
    """The N(s) a suptitle states: ``{None: (lo, hi)}`` for one N, else ``{robot: (lo, hi)}``.

    Reads ``"150 users per point"``, ``"60–150 users per point"`` and
    ``"users per curve: planar5 60, panda 150"``.
    """
    title = " ".join(title.split())
    per_robot = re.search(r"users per \w+: (.*?)(?:, assistance|$)", title)
    number = r"(\d+)(?:–(\d+))?"
    if per_robot:
        pairs = re.findall(rf"(\w+) {number}", per_robot.group(1))
        return {robot: (int(lo), int(hi or lo)) for robot, lo, hi in pairs}
    one = re.search(rf"{number} users per", title)
    assert one, f"no N in the title {title!r}"
    return {None: (int(one.group(1)), int(one.group(2) or one.group(1)))}


def shown_ns(table: pd.DataFrame, keys: tuple[str, ...]) -> dict[str, tuple[int, int]]:
    """Per robot, the fewest and most distinct users per point (``keys``) of the headline member."""
    counts = member_frame(table, HEADLINE).groupby(["robot", *keys])[USER].nunique()
    return {str(r): (int(c.min()), int(c.max())) for r, c in counts.groupby(level="robot")}


def check_title(fig: Figure, table: pd.DataFrame, keys: tuple[str, ...]) -> None:
    """Assert that ``fig``'s suptitle states the users per point of ``table``'s drawn rows."""
    stated, shown = title_ns(fig.get_suptitle()), shown_ns(table, keys)
    if None in stated:
        assert all(n == stated[None] for n in shown.values()), (fig.get_suptitle(), shown)
    else:
        assert stated == shown, (fig.get_suptitle(), shown)


@pytest.mark.parametrize("name", FIGURES)
def test_the_titles_n_is_the_users_per_point_shown(name: str) -> None:
    check_title(_figure(name), _table(name), FIGURES[name][2])


def test_the_check_fails_on_a_wrong_n(monkeypatch: pytest.MonkeyPatch) -> None:
    """The committed sim3 CSV has 60 planar5 and 150 Panda users: one N for both is wrong (sims 1-3 title
    through :func:`lasa.experiments.sweep.sim_figure`)."""
    table, keys = _table("sim3"), FIGURES["sim3"][2]
    assert shown_ns(table, keys) == {"planar5": (60, 60), "panda": (150, 150)}
    # drawn at its first three time steps, every user kept: the same N per point, and a fourteenth of
    # the bands' bootstraps to draw (the N, not the number of points, is what this test is about)
    few = table[table.t.isin(sorted(table.t.unique())[:3])]
    assert shown_ns(few, keys) == shown_ns(table, keys) and few.t.nunique() == 3
    monkeypatch.setattr(sweep, "users_text", lambda *args, **kwargs: "150 users per curve")
    with pytest.raises(AssertionError, match="150 users per curve"):
        check_title(sim3.plot(few), few, keys)


def test_title_ns_reads_every_form() -> None:
    assert title_ns("Fig. x: 150 users per point, assistance: point") == {None: (150, 150)}
    assert title_ns("Fig. x: 60–150 users per point, assistance: point") == {None: (60, 150)}
    assert title_ns("Fig. x, users per curve: planar5 60, panda 150, assistance: point") == {
        "planar5": (60, 60),
        "panda": (150, 150),
    }


def _probability_axes(fig: Figure) -> list[Axes]:
    return [ax for ax in fig.axes if PROBABILITY.search(ax.get_ylabel())]


@pytest.mark.parametrize("name", FIGURES)
def test_probability_axes_are_on_zero_to_one(name: str) -> None:
    for ax in _probability_axes(_figure(name)):
        low, high = ax.get_ylim()
        assert LIMITS[0] <= low <= 0.0 and 1.0 <= high <= LIMITS[1], (ax.get_ylabel(), low, high)


def test_sim2_has_probability_panels() -> None:
    labels = [ax.get_ylabel() for ax in _probability_axes(_figure("sim2"))]
    assert len(labels) == 4 and sum("success" in label for label in labels) == 2  # per robot


def _data_points(ax: Axes) -> np.ndarray:
    """Every finite point drawn in ``ax``'s data coordinates: lines, markers, bands, error bars."""
    points = [line.get_xydata() for line in ax.lines if line.get_transform() is ax.transData]
    for coll in ax.collections:
        if isinstance(coll, PathCollection):  # scatter markers: their offsets are the data
            if coll.get_offset_transform() is ax.transData:
                points.append(np.asarray(coll.get_offsets()))
        elif coll.get_transform() is ax.transData:  # bands, error bars: their paths are the data
            for path in coll.get_paths():
                codes = path.codes if path.codes is not None else np.ones(len(path.vertices))
                points.append(path.vertices[codes != MplPath.CLOSEPOLY])  # not the closing dummy
    xy = np.concatenate([np.asarray(p, dtype=float).reshape(-1, 2) for p in points])
    return xy[np.isfinite(xy).all(axis=1)]


@pytest.mark.parametrize("name", FIGURES)
def test_no_point_lies_outside_its_axes(name: str) -> None:
    for ax in _figure(name).axes:
        xy = _data_points(ax)
        assert len(xy), ax.get_title()
        for values, (low, high) in ((xy[:, 0], ax.get_xlim()), (xy[:, 1], ax.get_ylim())):
            slack = 1e-9 * max(abs(low), abs(high))
            assert values.min() >= min(low, high) - slack and values.max() <= max(low, high) + slack, (
                name,
                ax.get_title(),
                (values.min(), values.max()),
                (low, high),
            )
