"""The study's links: one secret token per participant, kept on the server only as its SHA-256
(:func:`issue_links`, :class:`TokenStore`). Ids come from the schedule only (:data:`PARTICIPANT_ID`):
no string a browser sends becomes a path."""

from __future__ import annotations

import contextlib
import hashlib
import hmac
import json
import os
import re
import secrets
from pathlib import Path

import pandas as pd

from lasa.base.errors import ConfigError
from lasa.base.io import write_csv, write_text

PARTICIPANT_ID = re.compile(r"p[0-9]{2,4}")
TOKEN_BYTES = 32  # 256 bits of randomness per link
MAX_TOKEN_CHARS = 128  # a longer presented token is refused before hashing


def check_participant(participant: str) -> str:
    """``participant`` if it is a strict id (``p`` and 2-4 digits), else a ConfigError."""
    if not isinstance(participant, str) or not PARTICIPANT_ID.fullmatch(participant):
        raise ConfigError(f"a participant id is 'p' and 2-4 digits, got {participant!r}")
    return participant


def study_dir(sessions: str | os.PathLike[str]) -> Path:
    """The server's own files beside the sessions (a subfolder: the analysis reads ``<sessions>/*.json``)."""
    return Path(sessions) / "study"


def _hash(token: str) -> str:
    return hashlib.sha256(token.encode()).hexdigest()


def issue_links(n: int, sessions: str | os.PathLike[str], base_url: str) -> Path:
    """Schedule ``n`` participants in ``<sessions>/study/``, write ``tokens.json`` (hashes) and one link each
    to the server at ``base_url`` (``links.csv``, the only copy of the tokens; returned). An existing study
    (tokens, progress and sessions together) is never replaced."""
    from lasa.live.studykit import write_schedule

    folder = study_dir(sessions)
    if (folder / "tokens.json").exists():
        raise ConfigError(f"{folder} holds a study already; give another --sessions folder")
    made = [p for p in (folder, *folder.parents) if not p.exists()]
    folder.mkdir(parents=True, exist_ok=True)
    try:
        schedule = pd.read_csv(write_schedule(n, folder / "schedule.csv"), dtype={"participant": str})
    except ConfigError:  # a refused schedule leaves no folder behind
        for path in made:
            with contextlib.suppress(OSError):
                path.rmdir()
        raise
    participants = [check_participant(p) for p in dict.fromkeys(schedule.participant)]
    tokens = {p: secrets.token_urlsafe(TOKEN_BYTES) for p in participants}
    write_text(folder / "tokens.json", json.dumps({p: _hash(t) for p, t in tokens.items()}, indent=2) + "\n")
    # the token in the fragment, which browsers never send: no server or proxy logs it
    link = [f"{base_url.rstrip('/')}/study#token={tokens[p]}" for p in participants]
    path = write_csv(folder / "links.csv", pd.DataFrame({"participant": participants, "link": link}))
    path.chmod(0o600)  # the only copy of the tokens
    return path


class TokenStore:
    """The tokens' hashes of one study (``<sessions>/study/tokens.json``), read once; entries whose id is
    not strict are dropped (a hand-edited file cannot put a path into a session's name)."""

    def __init__(self, sessions: str | os.PathLike[str]) -> None:
        path = study_dir(sessions) / "tokens.json"
        if not path.is_file():
            raise ConfigError(f"no study in {Path(sessions)}: run `python -m lasa.live.web schedule` first")
        raw = json.loads(path.read_text())
        self._hashes = {p: str(h) for p, h in raw.items() if PARTICIPANT_ID.fullmatch(str(p))}

    def participant(self, token: str | None) -> str | None:
        """The participant whose token this is, or None (compared in constant time)."""
        if not token or len(token) > MAX_TOKEN_CHARS:
            return None
        digest = _hash(token)  # compared with every stored hash, each in constant time
        found = [p for p, stored in self._hashes.items() if hmac.compare_digest(digest, stored)]
        return found[-1] if found else None
