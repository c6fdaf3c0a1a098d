"""Fig. sim4's analysis: lines of the grasp error against the new cup's distance (through the origin, the
paper's form), the claims on them, and notebook 07's tables and sentences of what they mean."""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Iterator

import numpy as np
import pandas as pd
from scipy import stats

from lasa.base.errors import ConfigError
from lasa.evidence import verdicts
from lasa.evidence.claims import Claim
from lasa.experiments import sweep

# the measures: (distance column, error column); "table" is the headline, the others are
# readings whose claims carry ``@<measure>`` ids
MEASURES = {"table": ("distance", "error"), "joint_space": ("distance_joint", "error_joint")}
HEADLINE = "table"
# the fits' forms, each with its reading (None: the headline): the paper's lines, y = 0.11x and
# y = x, go through the origin; the line with an intercept is the reading ``@intercept``
FORMS: dict[str, str | None] = {"origin": None, "intercept": "intercept"}
HEADLINE_FORM = "origin"


def fit_form(x: np.ndarray, y: np.ndarray, form: str) -> tuple[float, float, float]:
    """(slope, intercept, R^2) of the least-squares line of ``form`` (:data:`FORMS`): through the origin,
    y = slope x (the paper's form, intercept 0, R^2 uncentred), or y = slope x + intercept."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if form == "intercept":
        res = stats.linregress(x, y)
        return float(res.slope), float(res.intercept), float(res.rvalue**2)
    slope, r2 = _lines(x, y[None], "origin")
    return float(slope[0]), 0.0, float(r2[0])


def fits(frame: pd.DataFrame, measure: str = HEADLINE, form: str = HEADLINE_FORM) -> pd.DataFrame:
    """Least-squares lines (``form``: :data:`FORMS`) of the mean error per new cup against its distance
    (``measure``: :data:`MEASURES`) per kind of map ``h``: ``r2`` of the cups' means, ``r2_episodes``."""
    if form not in FORMS:
        raise ConfigError(f"form must be one of {sorted(FORMS)}, got {form!r}")
    x, y = MEASURES[measure]
    out = []
    for kind, part in frame.groupby("h"):
        means = part.groupby(x)[y].mean()
        slope, intercept, r2 = fit_form(means.index.to_numpy(), means.to_numpy(), form)
        _, _, r2_ep = fit_form(part[x].to_numpy(), part[y].to_numpy(), form)
        out.append({"h": kind, "slope": slope, "intercept": intercept, "r2": r2, "r2_episodes": r2_ep})
    return pd.DataFrame(out).set_index("h")


# per kind of map: the claim it is judged under, the reading it is (None: the claim's own map) and its
# name; the paper's straight line "between the start and g", in the gripper's space, is ``@ee_line``
_LINE = "the paper's straight-line context map"
_KIND_CLAIMS = {
    "straight_line": ("straight_line", None, _LINE),
    "grasp": ("grasp", None, "the grasp-to-grasp context map (ours)"),
    "straight_line_ee": ("straight_line", "ee_line", f"{_LINE}, the line in the gripper's space"),
}


def _claim_id(name: str, *readings: str | None) -> str:
    """``sim4.<name>``, or ``sim4.<name>@<reading>+<reading>`` for the readings given."""
    parts = [r for r in readings if r]
    return f"sim4.{name}" + (f"@{'+'.join(parts)}" if parts else "")


def _measures(frame: pd.DataFrame) -> list[str]:
    """The measures a frame holds, the headline first (the joint-space reading needs its columns)."""
    return [m for m, cols in MEASURES.items() if set(cols) <= set(frame.columns)]


def _ids(measure: str, form: str, kinds: Iterable[str]) -> Iterator[tuple[str | None, str]]:
    """(kind of map, id) of each linear claim of ``measure`` and ``form``, then (None, the no-map claim's)."""
    readings = (None if measure == HEADLINE else measure, FORMS[form])
    for kind in [k for k in _KIND_CLAIMS if k in kinds]:
        name, reading, _ = _KIND_CLAIMS[kind]
        yield kind, _claim_id(f"{name}_linear", reading, *readings)
    yield None, _claim_id("no_map_training_goal", *readings)


def claims(frame: pd.DataFrame) -> list[Claim]:
    """Fig. sim4's claims on one robot's frame, under every measure it holds and both forms of fit."""
    robot, out = str(frame.robot.iloc[0]), []
    for measure, form in itertools.product(_measures(frame), FORMS):
        x, y = MEASURES[measure]
        table, n_cups = fits(frame, measure, form), frame[x].nunique()
        means = frame.groupby(["h", x])[y].mean()
        angles = None
        if measure == HEADLINE and "angle_error_deg" in frame:
            angles = frame.groupby(["h", x]).angle_error_deg.mean()
        for kind, cid in _ids(measure, form, table.index):
            f = table.loc[kind or "none"]
            notes = []
            values = {"slope": float(f.slope), "r2": float(f.r2)}
            claim = "without the map, the robot only reaches for the training goal"
            if kind:
                below = means[kind] < means["none"]
                values["share_below"] = float(below.mean())
                if above := int((~below).sum()):
                    notes.append(f"Above the no-map error at {above} of {n_cups} cups.")
                claim = (
                    f"with {_KIND_CLAIMS[kind][2]}, the error at a new goal grows linearly with its distance"
                )
            if angles is not None and (kind or "none") in angles.index.get_level_values(0):
                per_cup = angles[kind or "none"]  # the mean approach-axis error at each cup
                notes.append(
                    f"Mean approach-axis error {per_cup.iloc[0]:.1f}° at the nearest cup, "
                    f"{per_cup.iloc[-1]:.1f}° at the farthest."
                )
            uncentred = " (uncentred)" if f.intercept == 0.0 else ""  # R^2 of a line through the origin
            measured = (
                f"{equation(f)}, R^2{uncentred} = {f.r2:.3f} over the {n_cups} cups' means "
                f"({f.r2_episodes:.2f} over episodes) (the interval is for the slope)"
            )
            paper = "y = 0.11x, R^2 = 0.98" if kind else "y = x"
            out.append(sweep.sim_claim(cid, robot, values, claim, paper, measured, " ".join(notes)))
    return out


def _lines(x: np.ndarray, ys: np.ndarray, form: str) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares slope and R^2 of each row of ``ys`` (R, K) against ``x`` (K,), lines of ``form``:
    through the origin sum(x y) / sum(x^2) and sum(x y)^2 / (sum(x^2) sum(y^2)), else of x, y less means."""
    if form == "intercept":
        x, ys = x - x.mean(), ys - ys.mean(axis=1, keepdims=True)
    sxy, sxx, syy = ys @ x, float(x @ x), (ys**2).sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return sxy / sxx, sxy**2 / (sxx * syy)


def boot_values(frame: pd.DataFrame, counts: np.ndarray) -> dict[str, dict[str, np.ndarray]]:
    """:func:`claims`' numbers in every resample of users (``counts``, :mod:`lasa.evidence.verdicts`)."""
    out: dict[str, dict[str, np.ndarray]] = {}
    for measure in _measures(frame):
        x, y = MEASURES[measure]
        means = verdicts.group_means(frame, ["h", x], y, counts)
        dist = np.array(sorted({d for _, d in means}))
        curve = {k: np.stack([means[(k, d)] for d in dist], axis=1) for k in {h for h, _ in means}}
        for form in FORMS:
            for kind, cid in _ids(measure, form, curve):
                slope, r2 = _lines(dist, curve[kind or "none"], form)
                out[cid] = {"slope": slope, "r2": r2}
                if kind:
                    out[cid]["share_below"] = (curve[kind] < curve["none"]).mean(axis=1)
    return out


def end_shares(frame: pd.DataFrame) -> pd.DataFrame:
    """Per (``h``, ``distance``): the share of beliefs that end on another training cup (``other``), the
    ``mean`` and ``median`` error, the mean of those episodes (``mean_left``) and the rest's, and ``n``."""
    rows = []
    for (kind, d), part in frame.groupby(["h", "distance"]):
        left = part.end_goal == "other"
        rows.append(
            {
                "h": kind,
                "distance": d,
                "other": float(left.mean()),
                "mean": float(part.error.mean()),
                "median": float(part.error.median()),
                "mean_left": float(part.error[left].mean()) if left.any() else np.nan,
                "mean_stayed": float(part.error[~left].mean()) if (~left).any() else np.nan,
                "n": len(part),
            }
        )
    return pd.DataFrame(rows).set_index(["h", "distance"])


def with_cup_columns(frame: pd.DataFrame) -> pd.DataFrame:
    """``frame`` with :data:`CUP_COLUMNS`, each cup's numbers on every one of its episodes' rows."""
    keys = [k for k in ("robot", "assistance", "h", "distance") if k in frame]
    other = (frame.end_goal == "other").astype(float) if "end_goal" in frame else np.nan
    groups = frame.assign(other_=other).groupby(keys, sort=False)
    return frame.assign(
        cup_mean_error=groups.error.transform("mean"),
        cup_median_error=groups.error.transform("median"),
        cup_other_share=groups.other_.transform("mean"),
    )


def no_map_check(frame: pd.DataFrame, form: str = HEADLINE_FORM) -> pd.DataFrame:
    """The paper's "without the map ... y = x", taken apart: per part of the no-map episodes, the line
    of ``form`` through the cups' means (NaN with fewer than two cups), ``mean_error`` and ``share``."""
    none = frame[frame.h == "none"]
    parts = {"held at the training cup": none.assign(error=none.reference), "without the map": none}
    if "end_goal" in none:
        parts["without the map, belief ends on the training cup"] = none[none.end_goal == "reference"]
        parts["without the map, belief ends on another cup"] = none[none.end_goal == "other"]
    rows = {}
    for name, part in parts.items():
        means = part.groupby("distance").error.mean()
        line = fit_form(means.index.to_numpy(), means.to_numpy(), form) if len(means) >= 2 else (np.nan,) * 3
        mean_error = float(part.error.mean()) if len(part) else np.nan
        rows[name] = (*line, mean_error, len(part) / max(len(none), 1))
    columns = ["slope", "intercept", "r2", "mean_error", "share"]
    return pd.DataFrame.from_dict(rows, orient="index", columns=columns).rename_axis("line")


# the grasps the users want, in three bands of the preference theta (0: top, 1: side)
BANDS = {"top (θ < 1/3)": (0.0, 1 / 3), "middle": (1 / 3, 2 / 3), "side (θ ≥ 2/3)": (2 / 3, 1.0 + 1e-9)}


def by_preference(frame: pd.DataFrame) -> pd.DataFrame:
    """Mean error, approach-axis error and the share of beliefs that end on another cup (``other``),
    and ``n``, per (``h``, ``band`` of the wanted grasp, :data:`BANDS`, ``distance``)."""
    edges = [lo for lo, _ in BANDS.values()] + [1.0 + 1e-9]
    band = pd.cut(frame.theta, edges, right=False, labels=list(BANDS))
    # every band appears, empty ones with NaN numbers and n = 0 (a small run may draw no middle grasp)
    grouped = frame.assign(band=band, other=frame.end_goal == "other").groupby(
        ["h", "band", "distance"], observed=False
    )
    return grouped.agg(
        error=("error", "mean"),
        angle_error_deg=("angle_error_deg", "mean"),
        other=("other", "mean"),
        n=("error", "size"),
    )


def equation(f: pd.Series, digits: int = 3) -> str:
    """``y = 0.110x`` through the origin (intercept 0), ``y = 0.110x +0.010`` with an intercept."""
    line = f"y = {f.slope:.{digits}f}x"
    return line if f.intercept == 0.0 else f"{line} {f.intercept:+.{digits}f}"


def _listed(values: np.ndarray, fmt: str) -> str:
    """``a, b and c`` of ``values`` formatted by ``fmt``."""
    text = [format(float(v), fmt) for v in values]
    return text[0] if len(text) == 1 else ", ".join(text[:-1]) + " and " + text[-1]


def identity_sentence(frame: pd.DataFrame) -> str:
    """What :func:`no_map_check` and :func:`end_shares` say of y = x on one robot's headline rows."""
    check, share = no_map_check(frame), end_shares(frame).loc["none", "other"]
    held, every = check.loc["held at the training cup"], check.loc["without the map"]
    stay = check.loc["without the map, belief ends on the training cup"]
    left = check.loc["without the map, belief ends on another cup"]
    text = (
        f"{frame.robot.iloc[0]}, {frame[verdicts.USER].nunique()} users per cup, "
        "lines through the origin: held at "
        f"the training cup, the error is {equation(held)} (R² = {held.r2:.3f}). Without the map it "
        f"is {equation(every, 2)} (R² = {every.r2:.2f}); over the {100 * stay.share:.0f}% of episodes "
        f"whose belief ends on the training cup, {equation(stay, 2)} (R² = {stay.r2:.2f}). "
    )
    if not left.share > 0:
        return text + "No episode's belief ends on the other training cup."
    return text + (
        f"The belief ends on the other training cup in {100 * share.iloc[0]:.0f}% of the episodes at "
        f"the nearest new cup and {100 * share.iloc[-1]:.0f}% at the farthest, and those episodes end "
        f"{left.mean_error:.2f} D from the wanted grasp on average."
    )


def map_sentences(frame: pd.DataFrame, geometry: pd.DataFrame) -> list[str]:
    """Why the straight-line map errs, from one robot's headline rows and its :func:`map_geometry`: its
    sentence, then the gripper's-space map's if the frame has it."""
    g, bands = geometry, by_preference(frame[frame.h != "none"])
    far = g.xs(g.index.get_level_values("offset_m").max(), level="offset_m")
    line = far.loc["straight_line"]
    top, middle, side = (bands.loc["straight_line"].xs(name, level="band") for name in BANDS)
    out = [
        f"{frame.robot.iloc[0]}: the new cups' grasps differ from the training cup's by at most "
        f"{g.joint1_rad.max():.2f} rad in joint 1 and {g.joint_last_rad.max():.2f} rad in the last joint, "
        f"and that difference changes by at most {g.branch_rad.max():.3f} rad between neighbouring "
        f"preferences: no branch switch. The mapped grasps keep at least {g.margin_rad.min():.2f} rad "
        f"from every joint limit, and the map stretches progress along the line by {g.stretch.min():.2f} "
        f"to {g.stretch.max():.2f}. At the farthest cup the straight-line map sends the new cup's grasps "
        f"up to {line.misfit_rad:.3f} rad from the training cup's same grasps ({100 * line.misfit_m:.1f} cm "
        f"and {line.misfit_deg:.1f}° at the gripper; the grasp-to-grasp map "
        f"{100 * far.loc['grasp', 'misfit_m']:.1f} cm). With the straight-line map, users who want a top "
        f"grasp end {top.error.min():.2f} to {top.error.max():.2f} D off (approach error up to "
        f"{top.angle_error_deg.max():.0f}°; belief on the other training cup in up to "
        f"{100 * top.other.max():.0f}% of them), middle grasps {middle.error.min():.3f} to "
        f"{middle.error.max():.3f} D, side grasps {side.error.min():.3f} to {side.error.max():.3f} D."
    ]
    if "straight_line_ee" in bands.index.get_level_values("h"):
        ee, ends = bands.loc["straight_line_ee"], end_shares(frame).loc["straight_line_ee"]
        ee_top, ee_side = (ee.xs(name, level="band").error.max() for name in (*BANDS,)[::2])
        out.append(
            f"The same line in the gripper's space (@ee_line) sends the farthest cup's grasps "
            f"{100 * far.loc['straight_line_ee', 'misfit_m']:.2f} cm from the training cup's; its users "
            f"end {ee_top:.3f} D off at most for top grasps, {ee_side:.3f} D for side grasps, with a median "
            f"error of {ends['median'].min():.3f} to {ends['median'].max():.3f} D over the cups."
        )
    return out


def medians_sentence(frame: pd.DataFrame) -> str:
    """What :func:`end_shares`' no-map medians and beliefs on the other cup say of y = x (one robot)."""
    table = end_shares(frame).loc["none"]
    far = table.iloc[-1]
    text = (
        f"{frame.robot.iloc[0]}, without the map, new cups at {_listed(table.index, '.2f')} D: the median "
        f"error is {_listed(table['median'], '.2f')} D, the mean {_listed(table['mean'], '.2f')} D "
        f"(y = x gives the distance). The belief of {_listed(100 * table.other, '.0f')}% of the users "
        f"ends on the other training cup"
    )
    if not far.other > 0:
        return text + "."
    return text + (
        f"; at the farthest cup those users end {far.mean_left:.2f} D from the wanted grasp on average, "
        f"the others {far.mean_stayed:.2f} D."
    )
