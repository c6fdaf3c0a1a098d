"""Shared panels read as the other figures do: the demonstrations in the cups' colours, and the
training curves each on an axis of its own, labelled with its unit (lasa.evidence.plots)."""

from __future__ import annotations

import matplotlib
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest
from matplotlib.collections import LineCollection
from matplotlib.colors import to_rgb
from matplotlib.patches import Rectangle

from lasa.evidence.plots import belief_cmap, goal_colors, plot_demonstrations, plot_training_curves

matplotlib.use("Agg")


@pytest.fixture(autouse=True)
def _closed():
    yield
    plt.close("all")


def _rgb(color) -> tuple[float, float, float]:
    return tuple(float(c) for c in to_rgb(color))  # type: ignore[return-value]


def _centre(patch: Rectangle) -> float:
    return float(patch.get_x() + patch.get_width() / 2)


def _distance(a, b) -> float:
    return float(np.linalg.norm(np.subtract(_rgb(a), _rgb(b))))


def test_each_cup_and_the_paths_heading_for_it_share_the_cups_colour(task, demos):
    fig, ax = plt.subplots()
    plot_demonstrations(task, demos, ax=ax)  # coloured by the belief in goal 1, the right cup
    colors = goal_colors(task.n_goals)
    # every cup is drawn in its goal's colour (the planar arm's cups: rectangles centred on each x)
    cups = task.robot.goal_positions()[:, 0]
    for g, x in enumerate(cups):
        (patch,) = [p for p in ax.patches if isinstance(p, Rectangle) and _centre(p) == pytest.approx(x)]
        assert _rgb(patch.get_facecolor()) == pytest.approx(_rgb(colors[g]))
    # the belief's ends are the cups' colours: all on the right cup is its green, none is the left's
    paths = [c for c in ax.collections if isinstance(c, LineCollection)]
    lc = paths[0]
    assert _rgb(lc.cmap(lc.norm(1.0))) == pytest.approx(_rgb(colors[1]))
    assert _rgb(lc.cmap(lc.norm(0.0))) == pytest.approx(_rgb(colors[0]))
    # and every demonstration ends in the colour of the cup it was demonstrated to
    clean = demos.clean()
    for lc, d in zip(paths, np.unique(clean.demo), strict=True):
        end = lc.to_rgba(lc.get_array()[-1])
        cup = int(clean.goal[clean.demo == d][-1])
        assert _distance(end, colors[cup]) < _distance(end, colors[1 - cup]), d
    assert fig.axes[-1].get_ylabel() == "belief in the right cup"


def test_a_belief_map_runs_from_the_rest_to_the_goals_colour():
    three = goal_colors(3)
    assert _rgb(belief_cmap(2, 0)(1.0)) == pytest.approx(_rgb(three[0]))
    assert _rgb(belief_cmap(2, 0)(0.0)) == pytest.approx(_rgb(three[1]))
    # with more goals, no belief in the goal is no one goal's colour
    assert all(_distance(belief_cmap(3, 2)(0.0), c) > 0.1 for c in three)
    assert _rgb(belief_cmap(3, 2)(1.0)) == pytest.approx(_rgb(three[2]))
    with pytest.raises(ValueError, match="goal_index"):
        belief_cmap(2, 2)


def test_the_training_curves_each_have_an_axis_named_with_its_unit():
    history = pd.DataFrame(
        {"step": [100, 200, 300], "train_loss": [0.3, 0.1, 0.06], "val_error": [1e-2, 6e-3, 5e-3]}
    )
    fig, ax = plt.subplots()
    loss_ax, error_ax = plot_training_curves(history, ax=ax)
    assert loss_ax is ax and error_ax is not ax
    assert ax.get_xlabel() == "optimiser step"
    assert loss_ax.get_ylabel().startswith("training loss [-]")  # dimensionless: units of sigma_h^2
    assert "sigma_h^2" in loss_ax.get_ylabel()
    assert error_ax.get_ylabel() == "held-out $\\|e_a\\|^2$ [(rad/s)$^2$]"
    for axes, column in ((loss_ax, "train_loss"), (error_ax, "val_error")):
        (line,) = axes.get_lines()
        np.testing.assert_array_equal(line.get_ydata(), history[column])
        assert axes.get_yscale() == "log"
        assert _rgb(axes.yaxis.label.get_color()) == pytest.approx(_rgb(line.get_color()))
    (legend,) = [a.get_legend() for a in fig.axes if a.get_legend() is not None]
    assert [t.get_text() for t in legend.get_texts()] == ["training loss", "held-out error"]
