"""Atomic file writes (a temporary file renamed into place); loads whose errors name what makes the file."""

from __future__ import annotations

import contextlib
import fcntl
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pandas as pd

from lasa.base import journal
from lasa.base.errors import ArtifactError, ConfigError


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary path beside ``path`` (same suffix), renamed onto it (journaled) if all goes well."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".tmp{path.suffix}", dir=path.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; give the usual permissions
        journal.before_write(path)  # a notebook run's old file, to undo the run if it fails
        os.replace(tmp, path)
        journal.after_write(path)
    finally:
        tmp.unlink(missing_ok=True)


_HELD: dict[Path, int] = {}  # folders this process holds locked, with nesting depth


@contextlib.contextmanager
def locked(folder: str | os.PathLike[str]) -> Iterator[Path]:
    """Hold an exclusive ``flock`` on ``folder`` (made if missing), for a read-modify-write; re-entrant."""
    folder = Path(folder).resolve()
    if _HELD.get(folder):
        _HELD[folder] += 1
        try:
            yield folder
        finally:
            _HELD[folder] -= 1
        return
    folder.mkdir(parents=True, exist_ok=True)
    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        _HELD[folder] = 1
        yield folder
    finally:
        _HELD.pop(folder, None)
        fcntl.flock(fd, fcntl.LOCK_UN)
        os.close(fd)


def write_text(path: str | os.PathLike[str], text: str) -> Path:
    """Atomically write ``text`` to ``path`` and return the path."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return Path(path)


def write_csv(path: str | os.PathLike[str], frame: pd.DataFrame) -> Path:
    """Atomically write a data frame as CSV (no index, fixed float format)."""
    with atomic_path(path) as tmp:
        frame.to_csv(tmp, index=False, float_format="%.6g")
    return Path(path)


def update_csv(path: str | os.PathLike[str], frame: pd.DataFrame, key: str = "robot") -> Path:
    """Replace the rows of ``path`` whose ``key`` matches ``frame``'s (journaled, under :func:`locked`)."""
    path = Path(path)
    with locked(path.parent):
        journal.note_rows(path, frame[[key]], sort=[key])  # undone row by row if the run fails
        if path.exists():
            old = pd.read_csv(path)
            replaced = key in old.columns and old[key].isin(frame[key].unique()).all()
            if list(old.columns) != list(frame.columns) and replaced:
                old = old.iloc[:0].reindex(columns=frame.columns)
            elif key not in old.columns or list(old.columns) != list(frame.columns):
                raise ArtifactError(
                    f"{path} has columns {list(old.columns)}, expected {list(frame.columns)}; "
                    "delete it and re-run the notebooks that write it"
                )
            frame = pd.concat([old[~old[key].isin(frame[key].unique())], frame], ignore_index=True)
        frame = frame.sort_values(key, kind="stable", ignore_index=True)  # whatever order robots ran in
        write_csv(path, frame)
    return path


def save_npz(path: str | os.PathLike[str], **arrays: np.ndarray) -> Path:
    """Atomically save arrays to a compressed ``.npz`` file."""
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        np.savez_compressed(f, **arrays)  # type: ignore[arg-type]
    return Path(path)


def require_file(path: str | os.PathLike[str], make_hint: str) -> Path:
    """``path`` if it exists, else ArtifactError naming ``make_hint``, the command that makes it."""
    path = Path(path)
    if not path.is_file():
        raise ArtifactError(f"{path} does not exist. Make it with: {make_hint}")
    return path


def load_npz(path: str | os.PathLike[str], make_hint: str) -> dict[str, np.ndarray]:
    """Load every array of an ``.npz`` file, with a clear error if it is missing or corrupt."""
    path = require_file(path, make_hint)
    try:
        with np.load(path, allow_pickle=False) as data:
            return {key: data[key] for key in data.files}
    except Exception as exc:  # zipfile.BadZipFile, ValueError, EOFError, OSError...
        raise ArtifactError(
            f"{path} is corrupt or unreadable ({exc}). Delete it and re-make it with: {make_hint}"
        ) from exc


def sync_between(
    path: str | os.PathLike[str], markers: tuple[str, str], text: str, inline: bool = False
) -> bool:
    """Put ``text`` between the (begin, end) ``markers`` in file ``path`` (``inline``: in a line); changed?"""
    path = Path(path)
    content = path.read_text()
    begin, end = markers
    if begin not in content or end not in content or content.index(begin) > content.index(end):
        raise ConfigError(f"{path} must hold the markers {begin!r} and {end!r}, in that order")
    head, rest = content.split(begin, 1)
    _, tail = rest.split(end, 1)
    body = text.strip() if inline else f"\n{text.strip()}\n"
    if (new := f"{head}{begin}{body}{end}{tail}") == content:
        return False
    write_text(path, new)
    return True
