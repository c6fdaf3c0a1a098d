"""Before the server listens: everything the schedule needs is there (a missing decoder would otherwise
show up mid-study). :func:`preflight` builds every scheduled condition's station on every task, as a
trial would; the first missing piece is one line naming the command that makes it.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import pandas as pd

from lasa.base.errors import ArtifactError, ConfigError
from lasa.evidence.sessions import PRACTICE_TASK
from lasa.live.station import SessionConfig, Station
from lasa.live.web.tokens import study_dir

if TYPE_CHECKING:
    from lasa.live.web.app import WebConfig

__all__ = ["TASKS", "preflight"]

TASKS = tuple(dict.fromkeys((PRACTICE_TASK, "Entree", "Dessert")))  # the tasks a condition runs


def preflight(config: WebConfig) -> list[str]:
    """Check that every step of ``config``'s schedule can run; the conditions checked.

    Raises:
        ConfigError: naming the first thing missing (a decoder, the schedule) and the command
            that makes it, in one line.
    """
    schedule = study_dir(config.sessions) / "schedule.csv"
    if not schedule.is_file():
        raise ConfigError(f"no study in {config.sessions}: run `python -m lasa.live.web schedule` first")
    conditions = list(dict.fromkeys(pd.read_csv(schedule).condition))
    for condition in conditions:
        for task in TASKS:
            session = SessionConfig(
                robot="panda", task=task, condition=condition, participant="p00", build_dir=config.build_dir
            )
            try:
                Station(session)
            except (ArtifactError, ConfigError) as exc:
                first = " ".join(str(exc).split())
                raise ConfigError(f"the study's {condition} condition cannot run: {first}") from exc
    return conditions
