"""Session logs of live use: ``<stem>.csv`` (a row per step, floats to 17 digits for bit-exact replay;
written as ``.csv.part``, renamed at the end), the ``<stem>.json`` sidecar (what ran, its ``status``)
and ``<stem>.xml`` (the scene, checked by its ``scene_sha256``)."""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from lasa.base.errors import ArtifactError, ConfigError, DamagedLogError
from lasa.base.io import write_text

STATUS = ("running", "complete", "interrupted")
FLUSH_EVERY = 10  # rows between flushes to disk: a crash loses at most this many steps


class SessionWriter:
    """Write one session's steps as they happen: in ``folder`` (created), as ``stem``, the sidecar ``meta``
    (plain JSON), the scene's MJCF and the step ``columns``; flushed every :data:`FLUSH_EVERY` steps."""

    def __init__(
        self,
        folder: str | os.PathLike[str],
        stem: str,
        meta: dict[str, Any],
        scene_xml: str,
        columns: list[str],
    ) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.stem = stem
        self.columns = columns
        digest = hashlib.sha256(scene_xml.encode()).hexdigest()
        self.meta = {**meta, "status": "running", "steps": 0, "scene_sha256": digest}
        self.csv = self.folder / f"{stem}.csv"
        self.part = self.folder / f"{stem}.csv.part"
        self.sidecar = self.folder / f"{stem}.json"
        if self.csv.exists() or self.part.exists():
            raise ArtifactError(f"session {self.csv} exists already; choose another participant or stem")
        write_text(self.folder / f"{stem}.xml", scene_xml)
        self._write_meta()
        self._fh = open(self.part, "w", newline="")  # noqa: SIM115 (closed in close())
        self._fh.write(",".join(columns) + "\n")
        self._rows = 0

    def _write_meta(self) -> None:
        write_text(self.sidecar, json.dumps(self.meta, indent=2, sort_keys=True) + "\n")

    def append(self, row: list[float]) -> None:
        """Write one step's values (in ``columns`` order); flush every :data:`FLUSH_EVERY` rows."""
        if len(row) != len(self.columns):
            raise ConfigError(f"a row has {len(self.columns)} values, got {len(row)}")
        self._fh.write(",".join(repr(float(v)) for v in row) + "\n")
        self._rows += 1
        if self._rows % FLUSH_EVERY == 0:
            self.flush()

    def flush(self) -> None:
        """Push the rows written so far to disk."""
        self._fh.flush()
        os.fsync(self._fh.fileno())

    def close(self, status: str = "complete", **extra: Any) -> Path:
        """End the session: the rows become ``<stem>.csv``; the sidecar records ``status`` and ``extra``."""
        if status not in STATUS[1:]:
            raise ConfigError(f"a session ends complete or interrupted, not {status!r}")
        self.flush()
        self._fh.close()
        os.replace(self.part, self.csv)
        self.meta.update(extra, status=status, steps=self._rows)
        self._write_meta()
        return self.csv


def repair_running(folder: str | os.PathLike[str], reason: str = "the server stopped") -> list[str]:
    """Close every session in ``folder`` whose sidecar still says ``running`` (its process was killed):
    its rows kept (``.csv.part`` renamed ``.csv``, a torn last line dropped), its sidecar ``interrupted``
    with ``reason`` and the rows it holds. The repaired sessions' stems, in order."""
    repaired = []
    for sidecar in sorted(Path(folder).glob("*.json")):
        try:
            meta = json.loads(sidecar.read_text())
        except (json.JSONDecodeError, UnicodeDecodeError):
            continue  # a damaged sidecar: the analysis names it; nothing here can be sure of it
        if not isinstance(meta, dict) or meta.get("status") != "running":
            continue
        stem = sidecar.name.removesuffix(".json")
        part, rows = sidecar.with_name(f"{stem}.csv.part"), sidecar.with_name(f"{stem}.csv")
        if part.is_file() and not rows.exists():
            _drop_torn_line(part)
            os.replace(part, rows)
        steps = max(0, len(rows.read_bytes().splitlines()) - 1) if rows.is_file() else 0
        meta.update(status="interrupted", reason=reason, steps=steps)
        write_text(sidecar, json.dumps(meta, indent=2, sort_keys=True) + "\n")
        repaired.append(stem)
    return repaired


def _drop_torn_line(path: Path) -> None:
    """Cut ``path`` after its last newline: a row half-written when the process died goes."""
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        with open(path, "r+b") as fh:
            fh.truncate(data.rfind(b"\n") + 1)
            fh.flush()
            os.fsync(fh.fileno())


def read_session(
    path: str | os.PathLike[str], allow_damaged: bool = False
) -> tuple[pd.DataFrame, dict[str, Any]]:
    """A session's steps and sidecar, from any of its files or its stem (a crashed one's ``.csv.part`` reads
    ``interrupted``); ArtifactError if its sidecar or rows are missing, DamagedLogError if damaged
    (unparsable, non-finite outside the raw axes, out of time order, or not its ``steps``), unless
    ``allow_damaged``: then the rows that parse, the reason in ``damaged``."""
    folder, stem = _locate(path)
    sidecar = folder / f"{stem}.json"
    if not sidecar.is_file():
        raise ArtifactError(f"no session sidecar {sidecar}")
    try:
        meta = json.loads(sidecar.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise DamagedLogError(f"session sidecar {sidecar} is damaged: not JSON ({exc})") from None
    if not isinstance(meta, dict):
        raise DamagedLogError(f"session sidecar {sidecar} is damaged: not a JSON object")
    rows = folder / f"{stem}.csv"
    ended = rows.is_file() and meta.get("status") in STATUS[1:]
    if not rows.is_file() or meta.get("status") == "running":  # crashed (rows in .csv.part) or never closed
        meta["status"] = "interrupted"
    if not rows.is_file():
        rows = folder / f"{stem}.csv.part"
    if not rows.is_file():
        raise ArtifactError(f"session {stem} has no rows in {folder}")
    frame, problem = _parse_rows(rows)
    if problem is None and ended and int(meta.get("steps", -1)) != len(frame):
        problem = f"its sidecar records {meta.get('steps')} steps, the log holds {len(frame)} rows"
    if problem is not None:
        if not allow_damaged or not len(frame.columns):
            raise DamagedLogError(f"session {stem} is damaged: {problem}")
        meta["damaged"] = problem
    return frame, meta


def check_scene(path: str | os.PathLike[str], meta: dict[str, Any]) -> Path:
    """The session's scene XML, checked: it exists (else ArtifactError) and matches the sidecar's
    checksum (else DamagedLogError)."""
    folder, stem = _locate(path)
    scene = folder / f"{stem}.xml"
    if not scene.is_file():
        raise ArtifactError(
            f"session {stem} has no scene {scene}: it cannot be checked against the scene it ran in"
        )
    expected = meta.get("scene_sha256")
    if expected and hashlib.sha256(scene.read_text().encode()).hexdigest() != expected:
        raise DamagedLogError(f"{scene} is not the scene session {stem} logged (checksum differs)")
    return scene


def _locate(path: str | os.PathLike[str]) -> tuple[Path, str]:
    p = Path(path)
    stem = p.name
    for suffix in (".csv.part", ".csv", ".json", ".xml"):
        stem = stem.removesuffix(suffix)
    return p.parent, stem


def _parse_rows(rows: Path) -> tuple[pd.DataFrame, str | None]:
    torn = None
    try:
        raw = pd.read_csv(rows, dtype=str, keep_default_na=False)
    except pd.errors.EmptyDataError:
        return pd.DataFrame(), f"its log {rows.name} is empty (not even a header)"
    except pd.errors.ParserError as exc:  # a row with another number of fields: the rows that parse
        torn = f"a row has the wrong number of fields ({str(exc).strip().splitlines()[-1]})"
        raw = pd.read_csv(rows, dtype=str, keep_default_na=False, on_bad_lines="skip")
    numbers = raw.apply(lambda c: pd.to_numeric(c, errors="coerce")).astype(np.float64)
    if torn is not None:
        return numbers, torn
    bad = numbers.isna() & ~raw.apply(lambda c: c.str.lower().isin(["nan", "-nan"]))
    if bad.to_numpy().any():
        row, col = np.argwhere(bad.to_numpy())[0]
        value = raw.iat[row, col]
        return numbers, f"row {row + 1}, column {raw.columns[col]!r} holds {value!r}, not a number"
    checked = [c for c in numbers.columns if not str(c).startswith("raw")]
    finite = np.isfinite(numbers[checked].to_numpy())
    if not finite.all():
        row, col = np.argwhere(~finite)[0]
        value = float(numbers[checked].iat[row, col])
        return numbers, f"row {row + 1}, column {checked[col]!r} holds {value}, not a finite number"
    for column in [c for c in ("step", "time") if c in numbers]:
        back = np.flatnonzero(np.diff(numbers[column].to_numpy()) <= 0)
        if back.size:
            row = int(back[0]) + 2
            why = f"rows out of time order: row {row}'s {column} does not come after row {row - 1}'s"
            return numbers, why
    return numbers, None
