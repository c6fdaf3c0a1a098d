"""A write journal: what a notebook run changed in the figures folder, to undo it if the run fails. Each
atomic write (:func:`lasa.base.io.atomic_path`) records the path's old state and the file put in place, a
merged table (:func:`note_rows`) its rows' keys; :func:`restore` puts back what no run rewrote since."""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import io
import json
import os
import shutil
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import pandas as pd  # loaded with lasa.base.io anyway

ENV = "LASA_WRITE_JOURNAL"  # the journal folder of the run in progress, if any
_META = "journal.json"  # in the journal folder: {"root": the journaled folder}
_ROOTS: dict[str, Path] = {}  # journal folder -> its root, read once per process


@contextlib.contextmanager
def recording(journal: str | os.PathLike[str], root: str | os.PathLike[str]) -> Iterator[Path]:
    """Journal the writes under ``root`` in the block, by this process and its children (:data:`ENV`)."""
    journal = Path(journal)
    shutil.rmtree(journal, ignore_errors=True)
    journal.mkdir(parents=True)
    (journal / _META).write_text(json.dumps({"root": str(Path(root).resolve())}))
    previous = os.environ.get(ENV)
    os.environ[ENV] = str(journal.resolve())
    _ROOTS.pop(os.environ[ENV], None)  # a journal of the same name may have had another root
    try:
        yield journal
    finally:
        if previous is None:
            os.environ.pop(ENV, None)
        else:
            os.environ[ENV] = previous


def discard(journal: str | os.PathLike[str]) -> None:
    """Delete a journal (after a run that succeeded, or once restored)."""
    shutil.rmtree(journal, ignore_errors=True)


def _entry(path: str | os.PathLike[str]) -> tuple[Path, Path] | None:
    """The journal entry (a JSON file) of ``path`` and the path resolved, if ``path`` is journaled."""
    if not (folder := os.environ.get(ENV)):
        return None
    if folder not in _ROOTS:
        _ROOTS[folder] = Path(json.loads((Path(folder) / _META).read_text())["root"])
    target = Path(path).resolve()
    return (_entry_of(Path(folder), target), target) if target.is_relative_to(_ROOTS[folder]) else None


def _identity(path: Path) -> list[int] | None:
    """What tells one file apart from its replacement: device, inode, size, modification time."""
    try:
        st = path.stat()
    except FileNotFoundError:
        return None
    return [st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns]


def _save(entry: Path, record: dict[str, Any]) -> None:
    tmp = entry.with_suffix(f".{os.getpid()}.tmp")
    tmp.write_text(json.dumps(record))
    os.replace(tmp, entry)


def _link_or_copy(src: Path, dst: Path) -> None:
    try:
        os.link(src, dst)
    except OSError:  # another file system, or links not allowed: a copy keeps the bytes too
        shutil.copy2(src, dst)


def before_write(path: str | os.PathLike[str]) -> None:
    """Record ``path``'s state before this run first replaces it; a no-op without a journal."""
    if (found := _entry(path)) is None or found[0].exists():
        return
    entry, target = found
    if existed := target.exists():
        _link_or_copy(target, entry.with_suffix(".old"))
    record = {"path": str(target), "first": time.time_ns(), "existed": existed, "wrote": None, "rows": None}
    _save(entry, record)


def after_write(path: str | os.PathLike[str]) -> None:
    """Record the identity of the file this run just put at ``path``; a no-op without a journal."""
    if (found := _entry(path)) is None or not found[0].exists():
        return
    _save(found[0], {**json.loads(found[0].read_text()), "wrote": _identity(found[1])})


def note_rows(path: str | os.PathLike[str], keys: pd.DataFrame, sort: Sequence[str]) -> None:
    """Record that the merged table ``path`` gets this run's rows of ``keys`` (sorted by ``sort``)."""
    if (found := _entry(path)) is None:
        return
    before_write(path)
    text = keys.drop_duplicates().to_csv(index=False, float_format="%.6g")
    written = pd.read_csv(io.StringIO(text), dtype=str, keep_default_na=False)
    record = json.loads(found[0].read_text())
    old = record["rows"]["keys"] if record["rows"] else []
    values = sorted({tuple(k) for k in old} | set(written.itertuples(index=False, name=None)))
    record["rows"] = {"columns": list(keys.columns), "sort": list(sort), "keys": values}
    _save(found[0], record)


@dataclasses.dataclass
class Restored:
    """What :func:`restore` did: the paths put back, the ``(path, why)`` left as another run wrote them."""

    root: Path
    restored: list[Path] = dataclasses.field(default_factory=list)
    left: list[tuple[Path, str]] = dataclasses.field(default_factory=list)

    def __str__(self) -> str:
        written = len(self.restored) + len(self.left)
        if not written:
            return f"it had written nothing in {self.root}"
        if not self.left:
            return f"the {written} file(s) it wrote in {self.root} were restored as they were"
        left = ", ".join(f"{path.name} ({why})" for path, why in self.left)
        done = len(self.restored)
        return f"{done} of the {written} file(s) it wrote in {self.root} were restored; not: {left}"


def restore(journal: str | os.PathLike[str]) -> Restored:
    """Undo the journaled writes, newest first, under the journaled folder's lock (the journal stays)."""
    from lasa.base.io import locked  # io imports this module

    journal = Path(journal)
    result = Restored(Path(json.loads((journal / _META).read_text())["root"]))
    records = [json.loads(p.read_text()) for p in journal.glob("*.json") if p.name != _META]
    with locked(result.root):
        landed = (r for r in records if r["wrote"] is not None)  # not those recorded but never written
        for record in sorted(landed, key=lambda r: r["first"], reverse=True):
            path = Path(record["path"])
            old = _entry_of(journal, path).with_suffix(".old") if record["existed"] else None
            why = ""
            if _identity(path) == record["wrote"]:
                _put_back(path, old)
            elif record["rows"] is not None:
                why = _restore_rows(path, old, record["rows"])
            else:
                why = "another run rewrote it since"
            if why:
                result.left.append((path, why))
            else:
                result.restored.append(path)
    return result


def _entry_of(journal: Path, path: Path) -> Path:
    return journal / f"{hashlib.sha1(str(path).encode()).hexdigest()[:20]}.json"


def _put_back(path: Path, old: Path | None) -> None:
    """Replace ``path`` by ``old`` atomically (a link to the old file, or a copy), or remove it."""
    if old is None:
        path.unlink(missing_ok=True)
        return
    tmp = path.with_name(f".{path.name}.restore{os.getpid()}")
    tmp.unlink(missing_ok=True)
    _link_or_copy(old, tmp)
    os.replace(tmp, path)


def _restore_rows(path: Path, old: Path | None, rows: dict[str, Any]) -> str:
    """Put back the old rows of the journaled keys in the table at ``path``; why not, or ``""``."""
    columns, sort = rows["columns"], rows["sort"]
    keys = pd.MultiIndex.from_tuples([tuple(k) for k in rows["keys"]], names=columns)
    now, before = (
        pd.read_csv(p, dtype=str, keep_default_na=False) if p is not None and p.exists() else None
        for p in (path, old)
    )  # each cell as written
    if not (tables := [t for t in (now, before) if t is not None]):
        return ""
    header = list(tables[0].columns)
    if any(list(t.columns) != header or not set(columns) <= set(header) for t in tables):
        return "another run rewrote it since, with other columns"
    # every row of the keys this run did not write as it is now, the rows of those it wrote as they were
    parts = (t[pd.MultiIndex.from_frame(t[columns]).isin(keys) == (t is before)] for t in tables)
    table = pd.concat(parts, ignore_index=True)
    if table.empty and before is None:
        path.unlink(missing_ok=True)
        return ""
    table = table.sort_values(list(sort), kind="stable", key=_sort_key, ignore_index=True)
    tmp = path.with_name(f".{path.name}.restore{os.getpid()}")
    table.to_csv(tmp, index=False)
    os.replace(tmp, path)
    return ""


def _sort_key(column: pd.Series) -> pd.Series:
    """A text column as the writer sorted it: by number if every cell is one, else as text."""
    numbers = pd.to_numeric(column, errors="coerce")
    return numbers if numbers.notna().all() else column
