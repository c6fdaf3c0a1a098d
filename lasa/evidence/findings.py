"""The verdict table's result sentences, each written from its rows' numbers in ``claim_values.csv``
(never from a note's prose), so it follows the numbers when a verdict moves."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence

from lasa.evidence.rules import COMPLETION_BAR
from lasa.evidence.stats import format_f
from lasa.evidence.values import Number, Numbers, Values

_NONE: dict[str, Number] = {}


def _interval(values: Values, cid: str, robot: str, name: str) -> tuple[float, float] | None:
    return values.get((cid, robot), _NONE).get(name, Number(math.nan)).interval


def side_of(interval: tuple[float, float], ref: float) -> str:
    """Where an interval lies against ``ref``: ``above``, ``below``, or ``reaches`` it."""
    return "above" if interval[0] > ref else "below" if interval[1] < ref else "reaches"


def _across(
    values: Values, robots: Sequence[str], cid: str, name: str, ref: float, says: Mapping[str, str]
) -> str:
    groups: dict[str, list[str]] = {}
    for robot in robots:
        if (interval := _interval(values, cid, robot, name)) is not None:
            groups.setdefault(side_of(interval, ref), []).append(robot)
    return "; ".join(f"{says[side]} ({on_robots(where)})" for side, where in groups.items())


def _time_ratio(values: Values, robots: Sequence[str]) -> str:
    says = {"above": "LA+SA is faster", "below": "LA+SA is slower", "reaches": "no clear gain"}
    at = {b: {side: f"at beta = {b} {said}" for side, said in says.items()} for b in ("1000", "75")}
    parts = [_across(values, robots, "sim1.time_ratio", f"ratio_{b}", 1.0, by) for b, by in at.items()]
    return "; ".join(p for p in parts if p)


def _gap_narrows(values: Values, robots: Sequence[str]) -> str:
    parts = []
    for what in ("time", "error"):
        groups: dict[str, list[str]] = {}
        for robot in robots:
            gap = _interval(values, "sim1.gap_narrows", robot, f"{what}_gap_75")
            narrowing = _interval(values, "sim1.gap_narrows", robot, f"{what}_narrowing")
            if gap is not None and narrowing is not None:
                change = _CHANGE_SAYS.get(side_of(narrowing, 0.0), "the {} gap's change is unclear")
                said = _GAP_SAYS.get(side_of(gap, 0.0)) or change
                groups.setdefault(said.format(what), []).append(robot)
        parts.append("; ".join(f"{said} ({on_robots(where)})" for said, where in groups.items()))
    return "; ".join(p for p in parts if p)


# sim1.gap_narrows' clause for a gap at beta = 75 below 0 or reaching it, else for its narrowing's side
_GAP_SAYS = {"below": "LA+SA is worse in {} at beta = 75", "reaches": "the {} gap at beta = 75 is unclear"}
_CHANGE_SAYS = {"above": "the {} gap narrows", "below": "the {} gap grows"}  # else: its change is unclear


def on_robots(robots: list[str]) -> str:
    """``both robots``, ``the Panda``, ``planar5``: where a clause holds."""
    if len(robots) == 2:
        return "both robots"
    return " and ".join({"panda": "the Panda"}.get(r, r) for r in robots)


def _grows(cid: str) -> Callable[[Values, Sequence[str]], str]:
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


def short_conditions(numbers: Numbers) -> list[tuple[str, float]]:
    """:func:`below_bar` of a study row's ``completion.<condition>`` facts."""
    return below_bar((k.split(".", 1)[1], n.value) for k, n in numbers.items() if k.startswith("completion."))


def completion_text(conditions: Sequence[tuple[str, float]]) -> str:
    """``LA 20%, LA+SA 45%``."""
    return ", ".join(f"{c} {100 * v:.3g}%" for c, v in conditions)


def _fact(numbers: Numbers, name: str) -> float:
    return numbers.get(name, Number(math.nan)).value


def study_effect(claim_id: str, numbers: Numbers) -> str:
    """The effect a study row rests on, in words with its sign and test (``SA lowers Goal Error by
    -2.04 m s, F(1,9) = 36.4, p < .001``), from its numbers; ``""`` for another row."""
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
        said = f"LA+SA's scoop alignment is {'above' if diff > 0 else 'below'} R+SA's by {diff:+.3f}"
        return f"{said}, paired t, {pairs} pairs, p = {p:.3g}"
    effect = numbers.get("effect")
    versus = [k.split(".", 1)[1] for k in numbers if k.startswith("versus.")]
    if base != "study.h3":
        return ""
    if effect is None or effect.interval is None or not versus:
        return "no contrast (a compared condition finishes too few episodes)"
    (low, high), side = effect.interval, "slower" if effect.value > 0 else "faster"
    by = f"{bound}{effect.value:+.1f} s [{low:+.1f}, {high:+.1f}]"
    return f"LA+SA is {side} than {versus[0]} by {by} (restricted means)"


def _testable(numbers: Numbers) -> bool:
    return _fact(numbers, "testable") == 1 and numbers.get("effect", Number(math.nan)).interval is not None


def _finish(short: Sequence[tuple[str, float]]) -> str:
    return " and ".join(f"{100 * v:.3g}% of their {c} episodes" for c, v in short)


def _h3_short(short: Sequence[tuple[str, float]]) -> str:
    done = ", ".join(f"{c} finishes {100 * v:.3g}% of its episodes" for c, v in short)
    held = ": the assistance holds simulated participants at a bowl"
    return done + (held if any(c == "LA+SA" for c, _ in short) else "")


def _hypothesis(
    cid: str, short_text: Callable[[Sequence[tuple[str, float]]], str], *says: str
) -> Callable[[Values, Sequence[str]], str]:
    said = dict(zip(("below", "above", "reaches"), says, strict=True))

    def find(values: Values, robots: Sequence[str]) -> str:
        headline = values.get((cid, "panda"), _NONE)
        if short := short_conditions(headline) if not _testable(headline) else []:
            return short_text(short)
        sides = []
        for numbers in (values.get((cid, "panda"), _NONE), values.get((f"{cid}@cohort", "panda"), _NONE)):
            if (effect := numbers.get("effect")) is not None:
                interval = effect.interval if _testable(numbers) else None
                sides.append((effect.n, side_of(interval, 0.0) if interval is not None else "untestable"))
        if not sides:
            return ""
        told = [side for _, side in sides if side in ("above", "below")]
        lead = told[-1] if told else "reaches"
        tell = {lead: "tell it", "reaches": "cannot tell", "untestable": "cannot test it"}
        verbs = [tell.get(side, "tell the opposite") for _, side in sides]
        if len(set(verbs)) == 1 and len(sides) > 1:
            ns = " and ".join(str(n) for n, _ in sides)
            return f"{said[lead]}; {ns} simulated participants alike {verbs[0]}"
        named = [f"{n} simulated participants" if i == 0 else str(n) for i, (n, _) in enumerate(sides)]
        return f"{said[lead]}; {', '.join(f'{who} {verb}' for who, verb in zip(named, verbs, strict=True))}"

    return find


# claim id -> its finding: (values, robots) -> the result sentence ("" when the rows state no number for it)
FINDINGS: dict[str, Callable[[Values, Sequence[str]], str]] = {
    "sim1.time_ratio": _time_ratio,
    "sim1.gap_narrows": _gap_narrows,
    **{cid: _grows(cid) for cid in ("sim4.straight_line_linear", "sim4.grasp_linear")},
    "study.h1": _hypothesis(
        "study.h1",
        lambda short: (
            f"simulated participants finish {_finish(short)}: the rest are cut, Goal Error censored"
        ),
        "SA lowers Goal Error",
        "SA raises Goal Error",
        "SA's effect on Goal Error is unclear",
    ),
    "study.h2": _hypothesis(
        "study.h2",
        lambda short: f"simulated participants finish {_finish(short)}: alignment only on the phases reached",
        "R+SA tilts the fork further into the scoop than LA+SA",
        "LA+SA tilts the fork further into the scoop than R+SA",
        "LA+SA's scoop alignment is not told from R+SA's",
    ),
    "study.h3": _hypothesis(
        "study.h3",
        _h3_short,
        "LA+SA is faster than the fastest other condition",
        "another condition is faster than LA+SA",
        "LA+SA's gap to the fastest other condition is unclear",
    ),
}


def finding(claim_id: str, values: Values, robots: Sequence[str]) -> str:
    """The result sentence of headline claim ``claim_id`` (:data:`FINDINGS`) on ``robots``; empty if none."""
    make = FINDINGS.get(claim_id)
    return make(values, robots) if make is not None else ""
