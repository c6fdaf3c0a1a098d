"""The kit for running the eating study with people: the schedule (:func:`write_schedule`) and the 7-point
Likert questionnaire (:func:`survey`). Neither replaces what exists unless asked (``overwrite``)."""

from __future__ import annotations

import os
import warnings
from collections.abc import Sequence
from pathlib import Path

import pandas as pd

from lasa.base.conditions import CONDITIONS, williams_square
from lasa.base.errors import ConfigError
from lasa.base.io import write_csv
from lasa.evidence.sessions import QUESTIONS, SCALES
from lasa.live.answers import answered, record, refuse_answered

MAX_PARTICIPANTS = 1000  # a schedule's largest cohort: far beyond any study the kit runs


def write_schedule(n: int, out: str | os.PathLike[str], overwrite: bool = False) -> Path:
    """Write the order of conditions for ``n`` (1..:data:`MAX_PARTICIPANTS`) participants by a balanced Latin
    square (Williams), participant i on row i mod 4 (CSV: participant, position, condition)."""
    if isinstance(n, bool) or int(n) != n or not 1 <= n <= MAX_PARTICIPANTS:
        raise ConfigError(
            f"the number of participants must be a whole number in 1..{MAX_PARTICIPANTS}, got {n!r}"
        )
    if Path(out).exists() and not overwrite:
        raise ConfigError(f"{out} exists already: pass --overwrite to replace the schedule")
    square = williams_square(len(CONDITIONS))
    if n % len(square):
        warnings.warn(
            f"a schedule of {n} participants fills the balanced Latin square's {len(square)} orders unevenly "
            f"({n // len(square)} full round(s) and {n % len(square)} more): the orders and their "
            f"carry-over are balanced only for a multiple of {len(square)}",
            stacklevel=2,
        )
    rows = [
        {"participant": f"p{i:02d}", "position": k + 1, "condition": CONDITIONS[c]}
        for i in range(int(n))
        for k, c in enumerate(square[i % len(CONDITIONS)])
    ]
    return write_csv(out, pd.DataFrame(rows))


def parse_answer(answer: object) -> int:
    """One Likert answer as an int: a whole number in 1..7 (``6``, ``"6"``, ``6.0``), else a ConfigError."""
    text = str(answer).strip()
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if isinstance(answer, bool) or not value.is_integer() or not 1 <= value <= 7:
        raise ConfigError(f"a Likert answer is a whole number from 1 to 7, got {text!r}")
    return int(value)


def ask(participant: str, condition: str) -> list[int]:
    """The questionnaire on the terminal: a bad answer is said and asked again, the others kept."""
    answers: list[int] = []
    print(f"{participant}, {condition}: 1 = strongly disagree ... 7 = strongly agree")
    while len(answers) < len(SCALES):  # the next scale's question until it is answered
        try:
            text = input(f"{QUESTIONS[SCALES[len(answers)]]} [1-7]: ")
        except EOFError:
            raise ConfigError(
                f"the questionnaire ended after {len(answers)} answers; nothing was saved"
            ) from None
        try:
            answers.append(parse_answer(text))
        except ConfigError as exc:
            print(f"{exc}; please answer again")
    return answers


def survey(
    folder: str | os.PathLike[str],
    participant: str,
    condition: str,
    answers: Sequence[int | str] | None = None,
    overwrite: bool = False,
) -> Path:
    """Record ``participant``'s ``answers`` (one in 1..7 per scale, ``6`` or ``"6"``; None: asked) after
    ``condition`` in ``<folder>/likert.csv``; ``overwrite`` replaces answers recorded before, and the same
    answers recorded before pass."""
    if condition not in CONDITIONS:
        raise ConfigError(f"unknown condition {condition!r}; choose one of {CONDITIONS}")
    path = Path(folder) / "likert.csv"
    if answers is None:
        _others(path, participant, condition, overwrite)  # before asking: refused answers would be lost
        answers = ask(participant, condition)
    values = [parse_answer(a) for a in answers]
    if len(values) != len(SCALES):
        raise ConfigError(f"give {len(SCALES)} answers in 1..7 ({', '.join(SCALES)}), got {answers}")
    new = pd.DataFrame(
        {"participant": participant, "condition": condition, "scale": SCALES, "answer": values}
    )
    # the same answers again pass (a server that crashed before its progress step asks again)
    return record(path, new, {"participant": participant, "condition": condition}, overwrite)


def _others(path: Path, participant: str, condition: str, overwrite: bool) -> None:
    """A ConfigError if ``path`` holds ``participant``'s answers for ``condition`` (and not ``overwrite``)."""
    key = {"participant": participant, "condition": condition}
    _, mine = answered(path, key)
    if mine is not None and mine.any() and not overwrite:
        refuse_answered(path, key)
