"""The verdict table's findings: each result sentence written from the numbers of its own rows.

The verdict table (:func:`lasa.evidence.claims.render_verdicts`) says per claim of the paper what
makes our verdict. A sentence there that states a result (the time gap grows, 10 participants
cannot tell) is written here, by :func:`finding`, from the claims' numbers
(``figures/claim_values.csv``, :mod:`lasa.evidence.values`): the interval of each number a rule
reads, the study's effect with its test and N, and each condition's completion. So it follows
the numbers when a verdict moves; no sentence is parsed for a number. What stays hand-written
(:data:`lasa.evidence.claims.PAPER_CLAIMS`) is the mechanism, which no result changes.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence

import pandas as pd

from lasa.evidence.rules import COMPLETION_BAR
from lasa.evidence.stats import format_f
from lasa.evidence.values import Number, Numbers, Values

__all__ = [
    "Rows",
    "FINDINGS",
    "finding",
    "study_effect",
    "side_of",
    "on_robots",
    "below_bar",
    "short_arms",
    "completion_text",
]

Rows = Mapping[tuple[str, str], pd.Series]  # (id, robot) -> a row of claims.csv, read as strings
_NONE: dict[str, Number] = {}


def _interval(values: Values, cid: str, robot: str, name: str) -> tuple[float, float] | None:
    """The interval of the number ``name`` of row (``cid``, ``robot``), None if unknown."""
    number = values.get((cid, robot), _NONE).get(name)
    return number.interval if number is not None else None


def side_of(interval: tuple[float, float], ref: float) -> str:
    """Where an interval lies against ``ref``: ``above``, ``below``, or ``reaches`` it."""
    low, high = interval
    return "above" if low > ref else "below" if high < ref else "reaches"


def _across(
    values: Values, robots: Sequence[str], cid: str, name: str, ref: float, says: Mapping[str, str]
) -> str:
    """What the robots' intervals of ``name`` say against ``ref``: ``says[side]``, where each lies.

    Robots whose intervals lie on the same side share one clause; a robot without the number is
    left out, and so is the clause when none has it.
    """
    groups: dict[str, list[str]] = {}
    for robot in robots:
        interval = _interval(values, cid, robot, name)
        if interval is not None:
            groups.setdefault(side_of(interval, ref), []).append(robot)
    return "; ".join(f"{says[side]} ({on_robots(where)})" for side, where in groups.items())


def _time_ratio(values: Values, robots: Sequence[str]) -> str:
    """sim1.time_ratio: who reaches sooner with the pull, near-optimal (beta = 1000) and noisy (75) users."""
    near = {
        "above": "at beta = 1000 LA+SA is faster",
        "below": "at beta = 1000 LA+SA is slower",
        "reaches": "at beta = 1000 no clear gain",
    }
    noisy = {
        "above": "at beta = 75 LA+SA is faster",
        "below": "at beta = 75 LA+SA is slower",
        "reaches": "at beta = 75 no clear gain",
    }
    parts = (
        _across(values, robots, "sim1.time_ratio", "ratio_1000", 1.0, near),
        _across(values, robots, "sim1.time_ratio", "ratio_75", 1.0, noisy),
    )
    return "; ".join(p for p in parts if p)


def _gap_narrows(values: Values, robots: Sequence[str]) -> str:
    """sim1.gap_narrows: per gap (time, final error), whether it narrows in the paper's direction."""
    parts = (_gap_part(values, robots, "time"), _gap_part(values, robots, "error"))
    return "; ".join(p for p in parts if p)


def _gap_part(values: Values, robots: Sequence[str], what: str) -> str:
    """What each robot's ``<what>_gap_75`` and ``<what>_narrowing`` say; robots that agree together."""
    groups: dict[str, list[str]] = {}
    for robot in robots:
        gap = _interval(values, "sim1.gap_narrows", robot, f"{what}_gap_75")
        narrowing = _interval(values, "sim1.gap_narrows", robot, f"{what}_narrowing")
        if gap is None or narrowing is None:
            continue
        side, change = side_of(gap, 0.0), side_of(narrowing, 0.0)
        said = (
            f"LA+SA is worse in {what} at beta = 75"
            if side == "below"
            else f"the {what} gap at beta = 75 is unclear"
            if side == "reaches"
            else f"the {what} gap narrows"
            if change == "above"
            else f"the {what} gap grows"
            if change == "below"
            else f"the {what} gap's change is unclear"
        )
        groups.setdefault(said, []).append(robot)
    return "; ".join(f"{said} ({on_robots(where)})" for said, where in groups.items())


def on_robots(robots: list[str]) -> str:
    """``both robots``, ``the Panda``, ``planar5``: where a clause holds."""
    if len(robots) == 2:
        return "both robots"
    return " and ".join({"panda": "the Panda"}.get(r, r) for r in robots)


def _grows(cid: str) -> Callable[[Values, Sequence[str]], str]:
    """sim4's linear claims: whether the error at a new cup grows with its distance (the slope against 0)."""
    says = {
        "above": "the error grows with the distance",
        "below": "the error falls with the distance",
        "reaches": "no measurable growth with the distance",
    }
    return lambda values, robots: _across(values, robots, cid, "slope", 0.0, says)


def below_bar(done: Iterable[tuple[str, float]]) -> list[tuple[str, float]]:
    """(condition, share finished) of each condition below :data:`~lasa.evidence.rules.COMPLETION_BAR`
    (an unknown share, NaN, counts as below: its measure is a lower bound at best)."""
    return [(str(c), float(v)) for c, v in done if not v >= COMPLETION_BAR]


def short_arms(numbers: Numbers) -> list[tuple[str, float]]:
    """:func:`below_bar` of a study row's ``completion.<condition>`` facts."""
    return below_bar((k.split(".", 1)[1], n.value) for k, n in numbers.items() if k.startswith("completion."))


def completion_text(arms: Sequence[tuple[str, float]]) -> str:
    """``LA 20%, LA+SA 45%``."""
    return ", ".join(f"{c} {100 * v:.3g}%" for c, v in arms)


def _fact(numbers: Numbers, name: str) -> float:
    number = numbers.get(name)
    return number.value if number is not None else math.nan


def study_effect(claim_id: str, numbers: Numbers) -> str:
    """The effect a study row rests on, in words with its sign and test, from its numbers.

    E.g. ``SA lowers Goal Error by -2.04 m s, F(1,9) = 36.4, p < .001`` (H1; ``by at least``
    when the arm is censored, its measure a lower bound), ``LA+SA's scoop alignment is below
    R+SA's by -0.062, paired t, 10 pairs, p = 0.0336`` (H2), ``LA+SA is slower than R by +36.6 s
    [+29.8, +44.9] (restricted means)`` (H3); ``""`` for a row without the numbers.
    """
    base, _, reading = claim_id.partition("@")
    diff, bound = _fact(numbers, "difference"), "at least " if _fact(numbers, "censored") == 1 else ""
    if base == "study.h1" and math.isfinite(diff):
        mean = "mean_distance" in reading.split("+")
        what, unit = ("the mean distance", "cm") if mean else ("Goal Error", "m s")
        test = {k: _fact(numbers, k) for k in ("F", "df1", "df2", "p")}
        change = "raises" if diff > 0 else "lowers"
        return f"SA {change} {what} by {bound}{diff:+.2f} {unit}, {format_f(test)}"
    if base == "study.h2" and "pairs" in numbers:
        p, pairs = _fact(numbers, "p"), int(_fact(numbers, "pairs"))
        if not math.isfinite(p):
            return f"no scoop-phase comparison ({pairs} pairs)"
        side = "above" if diff > 0 else "below"
        return (
            f"LA+SA's scoop alignment is {side} R+SA's by {diff:+.3f}, paired t, {pairs} pairs, p = {p:.3g}"  # noqa: E501
        )
    effect = numbers.get("effect")
    versus = [k.split(".", 1)[1] for k in numbers if k.startswith("versus.")]
    if base == "study.h3" and (effect is None or effect.interval is None or not versus):
        return "no contrast (a compared condition finishes too few episodes)"
    if base == "study.h3" and effect is not None and effect.interval is not None:
        low, high = effect.interval
        side = "slower" if effect.value > 0 else "faster"
        return (
            f"LA+SA is {side} than {versus[0]} by {bound}{effect.value:+.1f} s [{low:+.1f}, {high:+.1f}] "
            "(restricted means)"
        )
    return ""


def _study(values: Values, cid: str, says: Mapping[str, str]) -> str:
    """What the headline row and its ``@cohort`` row tell: ``lead; 10 ... cannot tell, 40 can``.

    The lead is ``says`` at the side of 0 where the larger N's interval lies, if any excludes
    0 (else ``says["reaches"]``); then per N whether its interval tells that side, none, or the
    other side (an untestable row: cannot test it). The study runs on the Panda only.
    """
    sides = []
    for numbers in (values.get((cid, "panda")), values.get((f"{cid}@cohort", "panda"))):
        effect = numbers.get("effect") if numbers is not None else None
        if effect is not None:
            interval = effect.interval if _testable(numbers or _NONE) else None
            sides.append((effect.n, side_of(interval, 0.0) if interval is not None else "untestable"))
    if not sides:
        return ""
    told = [side for _, side in sides if side in ("above", "below")]
    lead = told[-1] if told else "reaches"
    tell = {lead: "tell it", "reaches": "cannot tell", "untestable": "cannot test it"}
    verbs = [tell.get(side, "tell the opposite") for _, side in sides]
    if len(set(verbs)) == 1 and len(sides) > 1:
        ns = " and ".join(str(n) for n, _ in sides)
        return f"{says[lead]}; {ns} simulated participants alike {verbs[0]}"
    clauses = [
        f"{n}{' simulated participants' if i == 0 else ''} {verb}"
        for i, ((n, _), verb) in enumerate(zip(sides, verbs, strict=True))
    ]
    return f"{says[lead]}; {', '.join(clauses)}"


def _testable(numbers: Numbers) -> bool:
    """Whether a study row was judged (its ``testable`` fact), with an interval of its effect."""
    effect = numbers.get("effect")
    return _fact(numbers, "testable") == 1 and effect is not None and effect.interval is not None


def _censored(values: Values, cid: str) -> list[tuple[str, float]]:
    """(condition, share finished) of each condition below the bar, if the headline row is untestable."""
    numbers = values.get((cid, "panda"), _NONE)
    return short_arms(numbers) if not _testable(numbers) else []


def _finish(short: Sequence[tuple[str, float]]) -> str:
    return " and ".join(f"{100 * v:.3g}% of their {c} episodes" for c, v in short)


def _h1(values: Values, robots: Sequence[str]) -> str:
    """study.h1: the episodes cut at the horizon (censoring Goal Error), or what each N tells."""
    short = _censored(values, "study.h1")
    if short:
        return f"simulated participants finish {_finish(short)}: the rest are cut, Goal Error censored"
    return _study(
        values,
        "study.h1",
        {
            "below": "SA lowers Goal Error",
            "above": "SA raises Goal Error",
            "reaches": "SA's effect on Goal Error is unclear",
        },
    )


def _h2(values: Values, robots: Sequence[str]) -> str:
    """study.h2: the compared conditions' completion when it gates H2, or which N tells what."""
    short = _censored(values, "study.h2")
    if short:
        return f"simulated participants finish {_finish(short)}: alignment only on the phases reached"
    return _study(
        values,
        "study.h2",
        {
            "above": "LA+SA tilts the fork further into the scoop than R+SA",
            "below": "R+SA tilts the fork further into the scoop than LA+SA",
            "reaches": "LA+SA's scoop alignment is not told from R+SA's",
        },
    )


def _h3(values: Values, robots: Sequence[str]) -> str:
    """study.h3: which condition finishes too few episodes, or what each N tells."""
    short = _censored(values, "study.h3")
    if short:
        done = ", ".join(f"{c} finishes {100 * v:.3g}% of its episodes" for c, v in short)
        held = ": the assistance holds simulated participants at a bowl"
        return done + (held if any(c == "LA+SA" for c, _ in short) else "")
    return _study(
        values,
        "study.h3",
        {
            "below": "LA+SA is faster than the fastest other condition",
            "above": "another condition is faster than LA+SA",
            "reaches": "LA+SA's gap to the fastest other condition is unclear",
        },
    )


# claim id -> its finding: (values, robots) -> the result sentence ("" when the rows state no number for it)
FINDINGS: dict[str, Callable[[Values, Sequence[str]], str]] = {
    "sim1.time_ratio": _time_ratio,
    "sim1.gap_narrows": _gap_narrows,
    "sim4.straight_line_linear": _grows("sim4.straight_line_linear"),
    "sim4.grasp_linear": _grows("sim4.grasp_linear"),
    "study.h1": _h1,
    "study.h2": _h2,
    "study.h3": _h3,
}


def finding(claim_id: str, values: Values, robots: Sequence[str]) -> str:
    """The result sentence of a claim (:data:`FINDINGS`), from its rows' numbers; empty if it has none.

    Args:
        claim_id: The headline row's id, e.g. ``sim1.time_ratio``.
        values: The claims' numbers by (id, robot) (:func:`lasa.evidence.values.read_values`).
        robots: The robots whose rows to read, in the order to name them.
    """
    make = FINDINGS.get(claim_id)
    return make(values, robots) if make is not None else ""
