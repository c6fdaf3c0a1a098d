"""A participant's protocol (consent; per condition in their ``study/schedule.csv`` order a practice, the
Entree, the Dessert and the questionnaire; thanks) and their progress through it (``study/progress.json``:
one who disconnects comes back where they left off; a finished participant's link ends)."""

from __future__ import annotations

import dataclasses
import json
import os
from typing import Any

import pandas as pd

from lasa.base.io import write_text
from lasa.evidence.sessions import PRACTICE_TASK
from lasa.live.web.tokens import check_participant, study_dir
from lasa.live.web.withdraw import withdrawn


@dataclasses.dataclass(frozen=True)
class Step:
    """One step of the protocol, ``practice``, ``trial`` or ``survey``, under a condition at position
    ``order`` of the participant's schedule (0 first; the sidecar records it)."""

    kind: str
    condition: str
    task: str = ""
    order: int = 0

    @property
    def label(self) -> str:
        """The condition's letter in the participant's own order (A first): the page never shows its code."""
        return chr(ord("A") + self.order)


def plan_of(sessions: str | os.PathLike[str], participant: str) -> list[Step]:
    """The participant's steps, from the study's schedule (empty if they are not in it)."""
    schedule = pd.read_csv(study_dir(sessions) / "schedule.csv", dtype={"participant": str})
    rows = schedule[schedule.participant == check_participant(participant)].sort_values("position")
    kinds = (("practice", PRACTICE_TASK), ("trial", "Entree"), ("trial", "Dessert"), ("survey", ""))
    return [Step(kind, c, task, order) for order, c in enumerate(rows.condition) for kind, task in kinds]


class Progress:
    """Each participant's consent, next step and attempts, saved atomically on every change."""

    def __init__(self, sessions: str | os.PathLike[str]) -> None:
        self.path = study_dir(sessions) / "progress.json"
        self._state: dict[str, dict[str, Any]] = (
            json.loads(self.path.read_text()) if self.path.is_file() else {}
        )

    def of(self, participant: str) -> dict[str, Any]:
        """``{"consented", "step", "attempts"}`` of one participant (a fresh one: nothing done)."""
        return self._state.setdefault(
            check_participant(participant), {"consented": False, "step": 0, "attempts": 0}
        )

    def consent(self, participant: str) -> None:
        """Record the participant's consent."""
        self.mark(participant, "consented")

    def mark(self, participant: str, key: str) -> None:
        """Record that the participant has done ``key`` (``demographics``: answered or skipped)."""
        self.of(participant)[key] = True
        self._save()

    def count(self, participant: str, key: str) -> int:
        """One more ``attempts`` (a session started) or ``step`` (the current one done); the new count."""
        entry = self.of(participant)
        entry[key] += 1
        self._save()
        return int(entry[key])

    def finished(self, participant: str, plan: list[Step]) -> bool:
        """Whether every step of ``plan`` is done."""
        return int(self.of(participant)["step"]) >= len(plan)

    def _save(self) -> None:
        gone = withdrawn(self.path.parent.parent)  # a withdrawal while the server runs stays done
        state = {p: entry for p, entry in self._state.items() if p not in gone}
        write_text(self.path, json.dumps(state, indent=2, sort_keys=True) + "\n")
