"""The verdict table's findings: each result sentence written from the numbers of its own rows.

The verdict table (:func:`lasa.evidence.claims.render_verdicts`) says per claim of the paper what
makes our verdict. A sentence there that states a result (the time gap grows, 10 participants
cannot tell) is written here, by :func:`finding`, from the claims table's rows: the interval of
each number a rule reads (as :func:`lasa.evidence.verdicts.assess` states it in a row's note),
the study's effect interval and N, and the completion a ``not testable`` row names. So it
follows the numbers when a verdict moves. What stays hand-written
(:data:`lasa.evidence.claims.PAPER_CLAIMS`) is the mechanism, which no result changes.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping, Sequence

import pandas as pd

from lasa.evidence.decision import CENSORED, NOT_TESTABLE

__all__ = ["Rows", "FINDINGS", "finding", "stated_numbers", "not_testable_why", "effect_of"]

Rows = Mapping[tuple[str, str], pd.Series]  # (id, robot) -> a row of claims.csv, read as strings

# every number a rule reads, as lasa.evidence.verdicts.assess states it in a row's note:
# "<level>% intervals: <name> = <value> [<low>, <high>]; ...". "
_NUMBERS = re.compile(r"(\w+) = (\S+ \[[^\]]*\])(?=[;.] )")
_WHY = re.compile(
    re.escape(NOT_TESTABLE) + r" \(([^()]*)\)"
)  # "not testable (<why>)", <why> without parentheses
_COMPLETION = re.compile(r"(\S+) ([\d.]+)%")  # "LA+SA 45%" in "completion: LA+SA 45%, LA 90%"
_MODEL = re.compile(r"participant model = ([^;]+);")  # a study row's note
_EFFECT = re.compile(r"Measured effect: (.*?)\. ")  # a study row's note states its effect in words


def effect_of(note: object) -> str | None:
    """The effect a study row's note states (``Measured effect: <sentence>. ``), or None."""
    found = _EFFECT.search(str(note))
    return found.group(1) if found else None


def stated_numbers(note: object) -> list[tuple[str, str]]:
    """``(name, "<value> [<low>, <high>]")`` of every number a row's note states its interval of."""
    return _NUMBERS.findall(str(note))


def not_testable_why(row: pd.Series) -> str | None:
    """Why a row is not testable: the first ``not testable (<why>)`` of its ``measured``, else its note."""
    found = _WHY.search(str(row.measured)) or _WHY.search(str(row.note))
    return found.group(1) if found else None


def _interval(row: pd.Series | None, name: str) -> tuple[float, float] | None:
    """The interval of the number ``name`` in the row's note, None if it states none."""
    if row is None:
        return None
    for stated, text in stated_numbers(row.note):
        if stated == name:
            low, high = (float(x) for x in text.split("[", 1)[1].rstrip("]").split(","))
            return (low, high) if math.isfinite(low) and math.isfinite(high) else None
    return None


def _side(interval: tuple[float, float], ref: float) -> str:
    """Where an interval lies against ``ref``: ``above``, ``below``, or ``reaches`` it."""
    low, high = interval
    return "above" if low > ref else "below" if high < ref else "reaches"


def _across(
    rows: Rows, robots: Sequence[str], cid: str, name: str, ref: float, says: Mapping[str, str]
) -> str:
    """What the robots' intervals of ``name`` say against ``ref``: ``says[side]``, where each lies.

    Robots whose intervals lie on the same side share one clause; a robot without the number is
    left out, and so is the clause when none has it.
    """
    groups: dict[str, list[str]] = {}
    for robot in robots:
        interval = _interval(rows.get((cid, robot)), name)
        if interval is not None:
            groups.setdefault(_side(interval, ref), []).append(robot)
    clauses = []
    for side, where in groups.items():
        clauses.append(f"{says[side]} ({name}'s interval {side} {ref:g} on {_on(where)})")
    return "; ".join(clauses)


def _time_ratio(rows: Rows, robots: Sequence[str]) -> str:
    """sim1.time_ratio: who reaches sooner with the pull, near-optimal (beta = 1000) and noisy (75) users."""
    near = {
        "above": "near-optimal users (beta = 1000) reach sooner with the pull",
        "below": "near-optimal users (beta = 1000) reach later with the pull",
        "reaches": "near-optimal users (beta = 1000) gain no clear time from the pull",
    }
    noisy = {
        "above": "noisy ones (beta = 75) reach sooner with it",
        "below": "noisy ones (beta = 75) reach later with it",
        "reaches": "noisy ones (beta = 75) gain no clear time",
    }
    parts = (
        _across(rows, robots, "sim1.time_ratio", "ratio_1000", 1.0, near),
        _across(rows, robots, "sim1.time_ratio", "ratio_75", 1.0, noisy),
    )
    return "; ".join(p for p in parts if p)


def _gap_narrows(rows: Rows, robots: Sequence[str]) -> str:
    """sim1.gap_narrows: per gap (time, final error), whether it narrows in the paper's direction."""
    parts = (_gap_part(rows, robots, "time"), _gap_part(rows, robots, "error"))
    return "; ".join(p for p in parts if p)


def _gap_part(rows: Rows, robots: Sequence[str], what: str) -> str:
    """What each robot's ``<what>_gap_75`` and ``<what>_narrowing`` say; robots that agree together."""
    groups: dict[str, list[str]] = {}
    for robot in robots:
        row = rows.get(("sim1.gap_narrows", robot))
        gap, narrowing = _interval(row, f"{what}_gap_75"), _interval(row, f"{what}_narrowing")
        if gap is None or narrowing is None:
            continue
        side, change = _side(gap, 0.0), _side(narrowing, 0.0)
        said = (
            f"at beta = 75 LA+SA is worse, so the {what} gap is not the paper's"
            if side == "below"
            else f"the {what} gap's sign at beta = 75 is unclear"
            if side == "reaches"
            else f"the {what} gap narrows"
            if change == "above"
            else f"the {what} gap grows"
            if change == "below"
            else f"the {what} gap's change is unclear"
        )
        groups.setdefault(said, []).append(robot)
    return "; ".join(f"{said} ({_on(where)})" for said, where in groups.items())


def _on(robots: list[str]) -> str:
    """``both robots``, ``the Panda``, ``planar5``: where a clause holds."""
    if len(robots) == 2:
        return "both robots"
    return " and ".join({"panda": "the Panda"}.get(r, r) for r in robots)


def _grows(cid: str) -> Callable[[Rows, Sequence[str]], str]:
    """sim4's linear claims: whether the error at a new cup grows with its distance (the slope against 0)."""
    says = {
        "above": "the error grows with the new cup's distance",
        "below": "the error falls with the new cup's distance",
        "reaches": "the error does not grow measurably with the new cup's distance",
    }
    return lambda rows, robots: _across(rows, robots, cid, "slope", 0.0, says)


def _study(rows: Rows, cid: str, says: Mapping[str, str]) -> str:
    """What the headline row and its ``@cohort`` row tell: ``lead; 10 ... cannot tell, 40 can``.

    The lead is ``says`` at the side of 0 where the larger N's interval lies, if any excludes
    0 (else ``says["reaches"]``); then per N whether its interval tells that side, none, or the
    other side. The study runs on the Panda only.
    """
    sides = []
    for row in (rows.get((cid, "panda")), rows.get((f"{cid}@cohort", "panda"))):
        if row is not None:
            low, high = str(row.ci_low), str(row.ci_high)
            known = row.reproduced != NOT_TESTABLE and low and high
            sides.append((int(row.n_users), _side((float(low), float(high)), 0.0) if known else NOT_TESTABLE))
    if not sides:
        return ""
    told = [side for _, side in sides if side in ("above", "below")]
    lead = told[-1] if told else "reaches"
    tell = {lead: "tell it", "reaches": "cannot tell", NOT_TESTABLE: "cannot test it"}
    verbs = [tell.get(side, "tell the opposite") for _, side in sides]
    if len(set(verbs)) == 1 and len(sides) > 1:
        return f"{says[lead]}; {' and '.join(str(n) for n, _ in sides)} participants alike {verbs[0]}"
    clauses = [
        f"{n}{' participants' if i == 0 else ''} {verb}"
        for i, ((n, _), verb) in enumerate(zip(sides, verbs, strict=True))
    ]
    return f"{says[lead]}; {', '.join(clauses)}"


def _censored(rows: Rows, cid: str) -> list[tuple[str, str]]:
    """(condition, share finished in %) of each condition the headline row names as too short, if any."""
    row = rows.get((cid, "panda"))
    why = not_testable_why(row) if row is not None and row.reproduced == NOT_TESTABLE else None
    return (
        _COMPLETION.findall(why.removeprefix("completion: "))
        if why and why.startswith("completion: ")
        else []
    )


def _model(rows: Rows, cid: str) -> str:
    """``planning `` for the headline's participant model (``participant model = planning``), or ``""``."""
    row = rows.get((cid, "panda"))
    found = _MODEL.search(str(row.note)) if row is not None else None
    return f"{found.group(1)} " if found else ""


def _h1(rows: Rows, robots: Sequence[str]) -> str:
    """study.h1: the episodes cut at the horizon (censoring Goal Error), or what each N tells."""
    short = _censored(rows, "study.h1")
    if short:
        done = " and ".join(f"{pct}% of their {cond} episodes" for cond, pct in short)
        model = _model(rows, "study.h1")
        cut = "the rest are cut there, so Goal Error is censored"
        return f"the {model}participants finish {done} within the horizon: {cut}"
    return _study(
        rows,
        "study.h1",
        {
            "below": "SA lowers Goal Error",
            "above": "SA raises Goal Error",
            "reaches": "SA's effect on Goal Error is unclear",
        },
    )


def _h2(rows: Rows, robots: Sequence[str]) -> str:
    """study.h2: the compared conditions' completion when it gates H2, or whether LA+SA's scoop alignment is
    above R+SA's, and which N tells."""
    short = _censored(rows, "study.h2")
    if short:
        done = " and ".join(f"{pct}% of their {cond} episodes" for cond, pct in short)
        model = _model(rows, "study.h2")
        return f"the {model}participants finish {done}: alignment is measured only on the phases they reached"
    return _study(
        rows,
        "study.h2",
        {
            "above": "LA+SA tilts the fork further into the scoop than R+SA",
            "below": "R+SA tilts the fork further into the scoop than LA+SA",
            "reaches": "LA+SA's scoop alignment is not told from R+SA's",
        },
    )


def _h3(rows: Rows, robots: Sequence[str]) -> str:
    """study.h3: which condition finishes too few episodes (and why, for LA+SA), or what each N tells."""
    short = _censored(rows, "study.h3")
    if short:
        done = ", ".join(f"{cond} finishes {pct}% of its episodes" for cond, pct in short)
        held = f": the assistance holds {_model(rows, 'study.h3')}participants at a bowl"
        return done + (held if any(cond == "LA+SA" for cond, _ in short) else "")
    head = rows.get(("study.h3", "panda"))
    bound = " even as a lower bound" if head is not None and str(head.measured).startswith(CENSORED) else ""
    return _study(
        rows,
        "study.h3",
        {
            "below": "LA+SA is faster than the fastest other condition",
            "above": f"another condition is faster than LA+SA{bound}",
            "reaches": "LA+SA's gap to the fastest other condition is unclear",
        },
    )


# claim id -> its finding: (rows, robots) -> the result sentence ("" when the rows state no number for it)
FINDINGS: dict[str, Callable[[Rows, Sequence[str]], str]] = {
    "sim1.time_ratio": _time_ratio,
    "sim1.gap_narrows": _gap_narrows,
    "sim4.straight_line_linear": _grows("sim4.straight_line_linear"),
    "sim4.grasp_linear": _grows("sim4.grasp_linear"),
    "study.h1": _h1,
    "study.h2": _h2,
    "study.h3": _h3,
}


def finding(claim_id: str, rows: Rows, robots: Sequence[str]) -> str:
    """The result sentence of a claim (:data:`FINDINGS`), from its rows; empty if it has none.

    Args:
        claim_id: The headline row's id, e.g. ``sim1.time_ratio``.
        rows: The claims table's rows by (id, robot).
        robots: The robots whose rows to read, in the order to name them.
    """
    make = FINDINGS.get(claim_id)
    return make(rows, robots) if make is not None else ""
