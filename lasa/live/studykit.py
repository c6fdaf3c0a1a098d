"""The kit for running the eating study with people: the schedule and the questionnaire.

- :func:`write_schedule`: the order of the four conditions for N participants, a balanced
  Latin square (Williams design, :func:`lasa.people.participants.williams_square`), participant i on row
  i mod 4, as the simulated cohort.
- :func:`survey`: the paper's 7-point Likert questionnaire after each condition, on five
  scales (Easy, Helpful, Precise, Intuitive, Prefer), saved beside the sessions in
  ``likert.csv`` (one row per participant x condition x scale).

Reading the logged sessions and the answers back for analysis is :mod:`lasa.evidence.sessions`
(notebook 11 uses it; no notebook imports this module).
"""

from __future__ import annotations

import os
from pathlib import Path

import pandas as pd

from lasa.base.conditions import CONDITIONS
from lasa.base.errors import ConfigError
from lasa.base.io import locked, write_csv
from lasa.evidence.sessions import SCALES
from lasa.people.participants import williams_square

__all__ = [
    "write_schedule",
    "survey",
]

QUESTIONS = {
    "Easy": "It was easy to complete the tasks with this robot.",
    "Helpful": "The robot was helpful.",
    "Precise": "I could make precise motions.",
    "Intuitive": "The robot was intuitive to control.",
    "Prefer": "I would use this condition again.",
}


def write_schedule(n: int, out: str | os.PathLike[str]) -> Path:
    """Write the order of conditions for ``n`` participants (CSV: participant, position, condition)."""
    if int(n) != n or n < 1:
        raise ConfigError(f"the number of participants must be a positive integer, got {n!r}")
    square = williams_square(len(CONDITIONS))
    rows = [
        {"participant": f"p{i:02d}", "position": k + 1, "condition": CONDITIONS[c]}
        for i in range(n)
        for k, c in enumerate(square[i % len(CONDITIONS)])
    ]
    return write_csv(out, pd.DataFrame(rows))


def survey(
    folder: str | os.PathLike[str], participant: str, condition: str, answers: list[int] | None = None
) -> Path:
    """Record one participant's questionnaire after one condition in ``<folder>/likert.csv``.

    Args:
        folder: The sessions folder.
        participant: The participant's id.
        condition: The condition just done.
        answers: One answer in 1..7 per scale of :data:`SCALES`; asked on the terminal if None.

    Raises:
        ConfigError: for an answer outside 1..7, or the wrong number of answers.
    """
    if condition not in CONDITIONS:
        raise ConfigError(f"unknown condition {condition!r}; choose one of {CONDITIONS}")
    if answers is None:
        answers = []
        print(f"{participant}, {condition}: 1 = strongly disagree ... 7 = strongly agree")
        for scale in SCALES:
            answers.append(int(input(f"{QUESTIONS[scale]} [1-7]: ")))
    if len(answers) != len(SCALES) or any(not 1 <= int(a) <= 7 for a in answers):
        raise ConfigError(f"give {len(SCALES)} answers in 1..7 ({', '.join(SCALES)}), got {answers}")
    path = Path(folder) / "likert.csv"
    path.parent.mkdir(parents=True, exist_ok=True)
    new = pd.DataFrame(
        {
            "participant": participant,
            "condition": condition,
            "scale": SCALES,
            "answer": [int(a) for a in answers],
        }
    )
    with locked(path.parent):
        if path.exists():
            old = pd.read_csv(path, dtype={"participant": str})
            keep = ~((old.participant == participant) & (old.condition == condition))
            new = pd.concat([old[keep], new], ignore_index=True)
        write_csv(path, new)
    return path
