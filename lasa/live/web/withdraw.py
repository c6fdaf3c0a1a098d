"""The experimenter's data commands: :func:`withdraw` deletes one participant's data and records the
withdrawal (``study/withdrawn.csv``: the id and the UTC time only); :func:`export` writes one archive of
what the analysis reads (the tidy tables, the session logs and their sidecars) and nothing of the server's
own (tokens, links, progress, its log)."""

from __future__ import annotations

import datetime as dt_
import json
import os
import zipfile
from pathlib import Path

import pandas as pd

from lasa.base.errors import ConfigError
from lasa.base.io import atomic_path, locked, write_csv, write_text
from lasa.live.web.tokens import check_participant, study_dir

# The tidy tables beside the sessions, each with a ``participant`` column.
TABLES = ("likert.csv", "tlx.csv", "comments.csv", "demographics.csv")
SESSION_SUFFIXES = (".csv", ".csv.part", ".json", ".xml")  # a session's log, its rows so far, sidecar, scene
README = """This archive holds one web study's data, as `lasa` records it:

{tables}
- the sessions: per trial `<participant>_<task>_<condition>_<time>_a<attempt>` with `.csv` (a row per 0.1 s
  step), `.json` (its sidecar: what ran, how it ended, the input device) and `.xml` (the scene); a
  `.csv.part` holds the rows of a session that never closed; `practice/` holds the practice sessions,
  which the analysis never reads.

It holds no tokens, links, progress or server log. Withdrawn participants' data were deleted before it
was made. Participants appear under their ids only.
"""
TABLE_LINES = {
    "likert.csv": "- `likert.csv`: participant, condition, scale, answer (1-7) of the five statements",
    "tlx.csv": "- `tlx.csv`: participant, condition, subscale, value (NASA-TLX raw, 0-100)",
    "comments.csv": "- `comments.csv`: participant, condition, comment (as written)",
    "demographics.csv": "- `demographics.csv`: participant, item, answer (optional answers)",
}


def withdrawn(sessions: str | os.PathLike[str]) -> set[str]:
    """The ids of the participants who withdrew from the study in ``sessions``."""
    path = study_dir(sessions) / "withdrawn.csv"
    return set(pd.read_csv(path, dtype=str).participant) if path.is_file() else set()


def participant_files(sessions: str | os.PathLike[str], participant: str) -> list[Path]:
    """The session files (trials and practice) of ``participant`` in ``sessions``."""
    folders = (Path(sessions), Path(sessions) / "practice")
    return sorted(
        path
        for folder in folders
        for path in folder.glob(f"{check_participant(participant)}_*")
        if path.name.endswith(SESSION_SUFFIXES)
    )


def withdraw(sessions: str | os.PathLike[str], participant: str) -> list[str]:
    """Delete ``participant``'s sessions, answers, progress and token in ``sessions`` and record the
    withdrawal; what was deleted, in words. Their link stops working (a running server checks the record)."""
    check_participant(participant)
    folder = study_dir(sessions)
    if not (folder / "tokens.json").is_file():
        raise ConfigError(f"no study in {sessions}: nothing to withdraw from")
    done = []
    with locked(sessions):
        for path in participant_files(sessions, participant):
            path.unlink()
            done.append(str(path.relative_to(sessions)))
        for name in TABLES:
            path = Path(sessions) / name
            if path.is_file():
                table = pd.read_csv(path, dtype=str, keep_default_na=False)
                mine = table.participant == participant
                if mine.any():
                    write_csv(path, table[~mine])
                    done.append(f"{mine.sum()} rows of {name}")
        for name in ("progress.json", "tokens.json"):
            path = folder / name
            state = json.loads(path.read_text()) if path.is_file() else {}
            if state.pop(participant, None) is not None:
                write_text(path, json.dumps(state, indent=2, sort_keys=True) + "\n")
                done.append(f"study/{name}'s entry")
        _without_link(folder / "links.csv", participant)
        _record(folder / "withdrawn.csv", participant)
    return done


def _without_link(path: Path, participant: str) -> None:
    """``links.csv`` without the participant's link (the token in it opens nothing any more)."""
    if path.is_file():
        links = pd.read_csv(path, dtype=str)
        if (links.participant == participant).any():
            write_csv(path, links[links.participant != participant]).chmod(0o600)


def _record(path: Path, participant: str) -> None:
    old = (
        pd.read_csv(path, dtype=str)
        if path.is_file()
        else pd.DataFrame(columns=["participant", "withdrawn_utc"])
    )
    if participant not in set(old.participant):
        now = dt_.datetime.now(dt_.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")
        row = pd.DataFrame({"participant": [participant], "withdrawn_utc": [now]})
        write_csv(path, pd.concat([old, row], ignore_index=True))


def export(sessions: str | os.PathLike[str], out: str | os.PathLike[str]) -> list[str]:
    """Write ``out`` (a zip): the tidy tables, every session's files and a README; the names in it."""
    sessions = Path(sessions)
    if not sessions.is_dir():
        raise ConfigError(f"no sessions folder {sessions}")
    tables = [name for name in TABLES if (sessions / name).is_file()]
    logs = [
        path
        for folder in (sessions, sessions / "practice")
        for path in sorted(folder.glob("p*_*"))
        if path.is_file() and path.name.endswith(SESSION_SUFFIXES)
    ]
    names = ["README.md", *tables, *(str(p.relative_to(sessions)) for p in logs)]
    readme = README.format(tables="\n".join(TABLE_LINES[t] for t in tables) or "- no answers yet")
    with atomic_path(out) as tmp, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("README.md", readme)
        for name in names[1:]:
            archive.write(sessions / name, name)
    return names
