"""Did a regenerated figures folder reproduce the committed one? (``make verify``)
Prints each run's ``kernels.json``, a table of every file (CSVs by column, pages by outputs, others by
bytes) and a summary; status 1 only if a verdict differs or a claims table is missing, 2 if a folder is."""

from __future__ import annotations

import argparse
import ast
import dataclasses
import hashlib
import itertools
import json
import re
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from lasa.base.errors import ArtifactError
from lasa.pipeline.pages import INJECTED, cell_text

CLAIMS = "claims.csv"
KERNELS = "kernels.json"  # the run's kernel settings (lasa.runtime), printed for both runs
VERDICT_COLUMNS = ("effect", "number", "reproduced", "settled")  # a claim's words, per (id, robot)


@dataclasses.dataclass(frozen=True)
class Tolerance:
    """When two numbers are the same: ``|a - b| <= atol + rtol * |b|`` (``b`` committed)."""

    rtol: float = 1e-6  # below one unit of the 6th significant digit that the CSVs hold [-]
    atol: float = 1e-9  # values below it are zero to any physical resolution [unit of the column]


@dataclasses.dataclass(frozen=True)
class Row:
    """One line of the table: a file, the part of it compared, the result and its numbers."""

    file: str
    part: str
    result: str
    detail: str = ""


@dataclasses.dataclass
class Report:
    """The comparison of two folders: the table's rows and what makes it fail."""

    rows: list[Row] = dataclasses.field(default_factory=list)
    verdicts_differ: list[str] = dataclasses.field(default_factory=list)  # "id / robot: why"
    claims_missing: bool = False

    @property
    def failed(self) -> bool:
        """A verdict differs, or the claims table is missing from either folder."""
        return bool(self.verdicts_differ) or self.claims_missing

    def summary(self) -> str:
        """One line: files compared, what differs, and whether the verdicts are the same."""
        n, files = len(self.verdicts_differ), len({r.file for r in self.rows})
        verdicts = f"{n} verdict(s) differ" if n else "every verdict identical"
        verdicts = f"{CLAIMS} missing: verdicts not compared" if self.claims_missing else verdicts
        differing = len({r.file for r in self.rows if r.result != "identical"})
        status = "FAILED" if self.failed else "OK"
        return f"{status}: {files} files compared, {differing} with differences; {verdicts}"


def _files(folder: Path) -> dict[str, Path]:
    if not folder.is_dir():
        raise ArtifactError(f"figures folder {folder} does not exist (run `make figures OUT=...` first)")
    return {p.relative_to(folder).as_posix(): p for p in sorted(folder.rglob("*")) if p.is_file()}


def _run_folders(cells: list[dict]) -> dict[str, str]:
    """``{value: placeholder}`` of the injected cell's ``figures_dir`` and ``build_dir``, longest first."""
    values: dict[str, str] = {}
    injected = (c for c in cells if INJECTED in c.get("metadata", {}).get("tags", ()))
    for node in (node for cell in injected for node in ast.parse(cell_text(cell["source"])).body):
        if isinstance(node, ast.Assign) and isinstance(node.value, ast.Constant):
            name, value = ast.unparse(node.targets[0]), node.value.value
            if name in ("build_dir", "figures_dir") and isinstance(value, str) and value:
                values[value.rstrip("/")] = f"<{name}>"
    return dict(sorted(values.items(), key=lambda kv: -len(kv[0])))


def _output_lines(output: dict, folders: dict[str, str]) -> list[str]:
    """One output as lines of text: a stream's text, each MIME type's text, an image's digest."""

    def text(value: str | list[str]) -> str:
        joined = cell_text(value)
        for value_, placeholder in folders.items():  # a path under the run's folder, not a word
            joined = re.sub(rf"(?<![\w./-]){re.escape(value_)}(?=/)", placeholder, joined)
        return joined

    kind = output.get("output_type", "")
    if kind == "stream":
        return [f"{output.get('name')}: {line}" for line in text(output.get("text", "")).splitlines()]
    if kind == "error":
        return [f"error: {output.get('ename')}: {output.get('evalue')}"]
    lines = []
    for mime, value in sorted(output.get("data", {}).items()):
        if mime.startswith("image/"):
            digest = hashlib.sha256(str(value).replace("\n", "").encode()).hexdigest()[:12]
            lines.append(f"{mime}: sha256 {digest}")
        elif mime.startswith("text/") and mime != "text/html":  # the HTML of a table repeats its text
            lines += [f"{mime}: {line}" for line in text(value).splitlines()]
    return lines


def _notebook_outputs(path: Path) -> dict[str, list[str]]:
    """A page's code cells, by id, each as the lines of its outputs; ArtifactError if not a notebook."""
    try:
        cells = json.loads(path.read_text())["cells"]
    except (ValueError, KeyError, TypeError, UnicodeDecodeError) as exc:
        raise ArtifactError(f"{path} is not a notebook: {exc}") from None
    folders = _run_folders(cells)
    return {
        c.get("id", str(i)): [line for o in c.get("outputs", []) for line in _output_lines(o, folders)]
        for i, c in enumerate(cells)
        if c.get("cell_type") == "code"
    }


def _first_difference(old: list[str], new: list[str]) -> str:
    """The first line at which two cells' outputs differ, as ``old -> new`` (shortened)."""
    i, *lines = next((i, a, b) for i, (a, b) in enumerate(itertools.zip_longest(old, new)) if a != b)
    a, b = ("(none)" if x is None else repr(x if len(x) <= 60 else x[:57] + "...") for x in lines)
    return f"line {i + 1}: {a} -> {b}"


def _compare_notebook(name: str, old: Path, new: Path) -> list[Row]:
    """A page's code cells whose outputs differ (folders as placeholders) or in one page only."""
    try:
        a, b = _notebook_outputs(old), _notebook_outputs(new)
    except ArtifactError as exc:
        return [Row(name, "notebook", "not a notebook", str(exc))]
    rows = []
    for cell in [*a, *(c for c in b if c not in a)]:
        if cell not in a or cell not in b:
            rows.append(Row(name, f"cell {cell}", f"cell only in {'new' if cell not in a else 'committed'}"))
        elif a[cell] != b[cell]:
            rows.append(Row(name, f"cell {cell}", "outputs differ", _first_difference(a[cell], b[cell])))
    return rows or [Row(name, "outputs", "identical", f"{len(a)} code cells")]


def _numeric(frame: pd.DataFrame, column: str) -> bool:
    """Whether ``column`` holds numbers (booleans are labels, compared as text)."""
    dtype = frame[column].dtype
    return bool(pd.api.types.is_numeric_dtype(dtype) and not pd.api.types.is_bool_dtype(dtype))


def _cells(column: pd.Series) -> np.ndarray:
    """A column's cells as strings, missing ones as ``<NA>`` (so that two missing cells agree)."""
    return column.astype(object).where(column.notna(), "<NA>").astype(str).to_numpy()


def key_columns(frame: pd.DataFrame) -> list[str]:
    """What a row is: the leading one-token text columns (``robot``, ``id``) before the first number."""
    leading = itertools.takewhile(lambda column: not _numeric(frame, column), frame.columns)
    return [c for c in leading if not frame[c].dropna().astype(str).str.contains(r"\s").any()]


def _numeric_rows(
    name: str, column: str, old: pd.DataFrame, new: pd.DataFrame, tol: Tolerance, keys: list[str]
) -> tuple[np.ndarray, list[Row]]:
    """A numeric column's cells beyond the tolerance (a mask) and its lines: non-finite changes, max diffs."""
    a, b = old[column].to_numpy(dtype=float), new[column].to_numpy(dtype=float)
    finite = np.isfinite(a) & np.isfinite(b)
    changed = ~finite & ~((a == b) | (np.isnan(a) & np.isnan(b)))  # inf == inf; two NaN are equal
    with np.errstate(invalid="ignore", divide="ignore"):
        diff = np.where(finite, np.abs(b - a), 0.0)
        rel = np.where(diff == 0, 0.0, diff / np.abs(a))
    beyond = (diff > tol.atol + tol.rtol * np.abs(np.where(finite, a, 0.0))) | changed
    rows = []
    if (where := np.flatnonzero(changed)).size:
        label = (lambda i: " ".join(str(old[k].iloc[i]) for k in keys)) if keys else str
        shown = "; ".join(f"row {i} ({label(i)}): {a[i]:.6g} -> {b[i]:.6g}" for i in where[:5])
        more = f"; and {len(where) - 5} more" if len(where) > 5 else ""
        rows.append(Row(name, column, "non-finite", f"{len(where)} rows: {shown}{more}"))
    if beyond.any():
        detail = f"max abs {diff.max(initial=0.0):.3g}, max rel {rel.max(initial=0.0):.3g}"
        rows.append(Row(name, column, "beyond tolerance", f"{detail}, {beyond.sum()} rows"))
    return beyond, rows


def _column_rows(
    name: str, old: pd.DataFrame, new: pd.DataFrame, tol: Tolerance, keys: list[str]
) -> list[Row]:
    """One line per common column that differs, and one for the rows beyond the tolerance."""
    rows, beyond_any = [], np.zeros(len(old), dtype=bool)
    for column in [c for c in old.columns if c in new.columns]:
        if _numeric(old, column) and _numeric(new, column):
            beyond, lines = _numeric_rows(name, column, old, new, tol, keys)
            rows += lines
            beyond_any |= beyond
        elif cells := int((_cells(old[column]) != _cells(new[column])).sum()):
            rows.append(Row(name, column, "text differs", f"{cells} cells"))
    if beyond_any.any():
        rows.insert(0, Row(name, "rows", "beyond tolerance", f"{beyond_any.sum()} of {len(old)} rows"))
    return rows


def _compare_csv(name: str, old_path: Path, new_path: Path, tol: Tolerance) -> list[Row]:
    """The table's lines for one CSV: identical, or its shape, columns and values that differ."""
    old, new = pd.read_csv(old_path), pd.read_csv(new_path)
    missing = [c for c in old.columns if c not in new.columns]
    extra = [c for c in new.columns if c not in old.columns]
    detail = f"missing: {', '.join(missing) or '-'}; extra: {', '.join(extra) or '-'}"
    rows = [Row(name, "columns", "columns differ", detail)] if missing or extra else []
    keys = [k for k in key_columns(old) if k in new.columns]
    if len(old) != len(new):
        rows.append(Row(name, "rows", "rows differ", f"{len(old)} -> {len(new)} rows"))
    elif keys and (moved := np.any([_cells(old[k]) != _cells(new[k]) for k in keys], axis=0)).any():
        rows.append(
            Row(name, "rows", "rows differ", f"key columns {', '.join(keys)} differ at {moved.sum()} rows")
        )
    else:
        rows += _column_rows(name, old, new, tol, keys)
    return rows or [Row(name, "all", "identical", f"{old.shape[0]} rows x {old.shape[1]} columns")]


def _verdicts(path: Path) -> dict[tuple[str, str], tuple[str, ...]]:
    """``(id, robot) -> (effect, number, reproduced, settled)`` of a claims table, every cell as written."""
    frame = pd.read_csv(path, dtype=str, keep_default_na=False)
    if absent := [c for c in ("id", "robot", *VERDICT_COLUMNS) if c not in frame.columns]:
        raise ArtifactError(f"{path} has no column(s) {', '.join(absent)}: not a claims table")
    return {(r["id"], r["robot"]): tuple(r[c] for c in VERDICT_COLUMNS) for r in frame.to_dict("records")}


def _compare_claims(report: Report, files: dict[str, dict[str, Path]]) -> None:
    """Add each ``(id, robot)`` whose verdict differs, with why, to ``report``; or mark claims missing."""
    old_path, new_path = files["old"].get(CLAIMS), files["new"].get(CLAIMS)
    if old_path is None or new_path is None:
        report.claims_missing = True
        return
    old, new = _verdicts(old_path), _verdicts(new_path)
    for key in sorted(k for k in old.keys() | new.keys() if old.get(k) != new.get(k)):
        a, b = old.get(key), new.get(key)
        if a is None or b is None:
            why = "only in the new table" if a is None else "missing from the new table"
        else:
            changes = (f"{c} {x} -> {y}" for c, x, y in zip(VERDICT_COLUMNS, a, b, strict=True) if x != y)
            why = "; ".join(changes)
        report.verdicts_differ.append(f"{key[0]} / {key[1]}: {why}")
        report.rows.append(Row(CLAIMS, f"verdict {key[0]} / {key[1]}", "verdict differs", why))
    if not report.verdicts_differ:
        report.rows.append(Row(CLAIMS, "verdicts", "identical", f"{len(old)} (id, robot)"))


def compare_folders(committed: str | Path, new: str | Path, tol: Tolerance | None = None) -> Report:
    """Compare the files and verdicts; ArtifactError for a missing folder or a malformed claims table."""
    tol = tol or Tolerance()
    files = {"old": _files(Path(committed)), "new": _files(Path(new))}
    report = Report()
    for name in sorted(files["old"].keys() | files["new"].keys()):
        old, fresh = files["old"].get(name), files["new"].get(name)
        if old is None or fresh is None:
            where = "new" if fresh is None else "committed"
            report.rows.append(Row(name, "file", f"missing in {where}"))
        elif name.endswith(".csv"):
            report.rows += _compare_csv(name, old, fresh, tol)
        elif name.endswith(".ipynb"):
            report.rows += _compare_notebook(name, old, fresh)
        else:  # PNG, MP4, Markdown: identical bytes or not
            a, b = old.read_bytes(), fresh.read_bytes()
            same = ("identical", f"{len(a)} bytes") if a == b else ("differs", f"{len(a)} -> {len(b)} bytes")
            report.rows.append(Row(name, "bytes", *same))
    _compare_claims(report, files)
    return report


def main(argv: list[str] | None = None) -> int:
    """Command line: ``python -m lasa.pipeline.verify COMMITTED NEW [--rtol R] [--atol A]``."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("committed", help="the committed figures folder (e.g. figures)")
    parser.add_argument("new", help="the regenerated figures folder (e.g. build/verify/figures)")
    parser.add_argument("--rtol", type=float, default=Tolerance.rtol, help="relative tolerance [%(default)g]")
    parser.add_argument("--atol", type=float, default=Tolerance.atol, help="absolute tolerance [%(default)g]")
    args = parser.parse_args(argv)
    try:
        report = compare_folders(args.committed, args.new, Tolerance(args.rtol, args.atol))
    except ArtifactError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    for label, folder in (("committed", args.committed), ("new", args.new)):  # lasa.runtime.record's
        path = Path(folder) / KERNELS
        what = f"kernels of the {label} run"
        if not path.is_file():
            print(f"{what}: {KERNELS} missing (its kernels were not recorded)")
            continue
        data = json.loads(path.read_text())
        env = ", ".join(f"{k}={v}" for k, v in sorted(data.get("environment", {}).items()))
        state = "pinned" if data.get("pinned") else "NOT pinned"
        print(f"{what}: {state}, torch {data.get('torch_cpu_capability')}; {env}")
    header = [f.name for f in dataclasses.fields(Row)]  # the rows as a Markdown table, readable as text
    cells = [header, *([str(v) for v in dataclasses.astuple(r)] for r in report.rows)]
    widths = [max(len(line[i]) for line in cells) for i in range(len(header))]
    cells.insert(1, ["-" * w for w in widths])
    for line in cells:
        print(f"| {' | '.join(v.ljust(w) for v, w in zip(line, widths, strict=True))} |")
    if report.claims_missing:
        print(f"error: {CLAIMS} is missing from {args.committed} or {args.new}", file=sys.stderr)
    print(report.summary())
    return 1 if report.failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
