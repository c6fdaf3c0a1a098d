"""Every figure that tests a paper claim draws the paper's number or ordering, labelled."""

import matplotlib
import numpy as np
import pandas as pd
import pytest

from lasa.experiments import sim1, sim2, sim3, sim4
from lasa.experiments.study import plots

matplotlib.use("Agg")


def _texts(fig) -> str:
    """Every legend entry, axes text, title and axis label of a figure, joined."""
    out = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
    out.append(fig.get_suptitle())
    for ax in fig.axes:
        leg = ax.get_legend()
        out += [t.get_text() for t in leg.get_texts()] if leg else []
        out += [t.get_text() for t in ax.texts]
        out += [ax.get_title(), ax.get_xlabel()]
    return "\n".join(out)


def _sim1_table() -> pd.DataFrame:
    rng = np.random.default_rng(0)
    rows = []
    for beta in (1.0, 75.0, 1000.0):
        for seed in range(5):
            for method, scale in (("LA", 1.4), ("LA+SA", 1.0), ("LA+SA+Entropy", 1.1)):
                rows.append(
                    dict(
                        robot="planar5",
                        method=method,
                        beta=beta,
                        seed=seed,
                        final_error=0.1 * scale,
                        time=100 * scale + 10 * rng.random(),
                        completed=True,
                        assistance="none" if method == "LA" else "point",
                    )
                )
    return pd.DataFrame(rows)


def test_sim1_draws_the_papers_time_ratios_with_the_rules_tolerance():
    fig = sim1.plot(_sim1_table())
    text = _texts(fig)
    assert "paper: 1.45 (β = 75)" in text and "paper: 1.30 (β = 1000)" in text
    assert "± 0.15" in text
    ratio_ax = fig.axes[2]
    stars = {
        (float(x), float(y))
        for line in ratio_ax.lines
        if line.get_marker() == "*"
        for x, y in line.get_xydata()
    }
    assert stars == {(75.0, 1.45), (1000.0, 1.30)}
    for ax in fig.axes[:2]:  # the grey lines at the paper's betas are labelled
        assert any("paper's time ratios" in t.get_text() for t in ax.get_legend().get_texts())


def test_sim1_time_ratio_band_is_the_claims_ratio_and_deterministic():
    table = _sim1_table()
    band = sim1.time_ratio_band(table)
    means = table.groupby(["beta", "method"]).time.mean()
    assert np.allclose(band.ratio, [means[b, "LA"] / means[b, "LA+SA"] for b in band.beta])
    assert (band.low <= band.ratio).all() and (band.ratio <= band.high).all()
    pd.testing.assert_frame_equal(band, sim1.time_ratio_band(table))


def test_sim2_and_sim3_state_the_papers_shape():
    rows = [
        dict(
            robot="planar5",
            method=m,
            change_step=n,
            seed=s,
            final_error=0.1,
            confidence=0.9,
            success=True,
            assistance="none" if m == "LA" else "point",
        )
        for n in (0, 20)
        for s in range(3)
        for m in ("LA", "LA+SA", "LA+SA+Entropy")
    ]
    text = _texts(sim2.plot(pd.DataFrame(rows))).replace("\n", " ")
    assert "paper: LA+SA's error grows with N; LA+SA+Entropy stays low" in text
    rows = [
        dict(robot="planar5", method=m, learner=lr, slope=1.0, seed=s, t=t, error=0.5, assistance="point")
        for lr in ("fast", "slow")
        for s in range(3)
        for m in ("LA+SA", "LA+SA+Entropy")
        for t in (0, 5)
    ]
    text = _texts(sim3.plot(pd.DataFrame(rows))).replace("\n", " ")
    assert text.count("paper: LA+SA+Entropy below LA+SA over time") == 2  # fast and slow


def test_sim4_draws_the_papers_lines_through_the_origin():
    rows = [
        dict(robot="panda", distance=d, seed=s, error=slope * d + 0.01 * s, h=h, assistance="point")
        for d in (0.4, 0.7, 1.0)
        for s in range(3)
        for h, slope in (("none", 1.0), ("grasp", 0.1))
    ]
    ax = sim4.plot(pd.DataFrame(rows)).axes[0]
    labels = {line.get_label(): line.get_xydata() for line in ax.lines}
    for label, slope in (("paper, with the map: y = 0.11x", 0.11), ("paper, without the map: y = x", 1.0)):
        xy = labels[label]
        assert xy[0] == pytest.approx([0.0, 0.0]) and xy[-1, 1] == pytest.approx(slope * xy[-1, 0])
    assert {"paper, with the map: y = 0.11x", "paper, without the map: y = x"} <= {
        t.get_text() for t in ax.get_legend().get_texts()
    }
    assert "as the paper's" in ax.get_xlabel()  # the units drawn are said


def _study_rows() -> list[dict[str, object]]:
    rows = []
    for p in range(3):
        for cond in ("R", "R+SA", "LA", "LA+SA"):
            for task in ("Entree", "Dessert"):
                done = cond != "LA" and (cond != "LA+SA" or p == 0)  # LA 0%, LA+SA 33%
                t = 30.0 if done else 150.0
                base = dict(
                    participant=p,
                    condition=cond,
                    assistance="hindsight" if "+" in cond else "none",
                    decoder="none",
                    task=task,
                )
                rows += [
                    dict(
                        base,
                        goal_error=1.0,
                        total_time=t,
                        idle_time=t / 3,
                        completed=done,
                        phase=ph,
                        alignment=0.5,
                    )
                    for ph in ("stab", "scoop", "dip")
                ]
    return rows


def test_study_figures_label_the_papers_hypotheses():
    frame = pd.DataFrame(_study_rows())
    text = _texts(plots.plot_goal_error(frame)).replace("\n", " ")
    assert "paper: F(1,18) = 29.9, p < .001" in text and "H1" in text
    assert "H2" in _texts(plots.plot_alignment(frame)) and "LA+SA" in _texts(plots.plot_alignment(frame))
    assert "paper (H3): LA+SA fastest" in _texts(plots.plot_time(frame)).replace("\n", " ")


def test_study_time_hatches_every_censored_bar_and_prints_its_completion():
    fig = plots.plot_time(pd.DataFrame(_study_rows()))
    for ax in fig.axes:
        hatched = [p for p in ax.patches if p.get_hatch() and p.get_height() > 100]  # LA and LA+SA
        assert len(hatched) == 2
        labels = {t.get_text(): t.xy[0] for t in ax.texts}
        centres = sorted(p.get_x() + p.get_width() / 2 for p in hatched)
        assert labels["0% done"] == pytest.approx(centres[0]) and labels["33% done"] == pytest.approx(
            centres[1]
        )
