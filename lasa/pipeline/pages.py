"""The executed notebooks as committed pages: light, stable copies under ``figures/notebooks/``, all under
:data:`BUDGET` (the largest committed figures linked until they fit, else :class:`PageBudgetError`)."""

from __future__ import annotations

import argparse
import base64
import copy
import hashlib
import itertools
import json
import posixpath
import re
import sys
from pathlib import Path
from typing import Any

from lasa.base.errors import ArtifactError
from lasa.base.io import write_text
from lasa.base.paths import repo_root

BUDGET = 5_000_000  # bytes of every page together (issue 47: "at most 5 MB in all")
PAGES = "notebooks"  # the pages' folder inside the figures folder
SOURCE_DIR = "notebooks"  # where the source notebooks' relative links start from
PAGE_DIR = "figures/notebooks"  # where the committed pages' relative links start from
INJECTED = "injected-parameters"  # papermill's tag (and, on the page, the id) of its parameters cell
WIDGET = "application/vnd.jupyter.widget-view+json"
VIDEO_HTML = re.compile(r"<video\b", re.IGNORECASE)
VIDEO_SRC = re.compile(r"""src=["']([^"']+\.mp4)["']""", re.IGNORECASE)
DATA_MP4 = re.compile(r"data:video/mp4;base64,([A-Za-z0-9+/=\s]+)")
PROGRESS = re.compile(r"\r|\|\s*\d+/\d+\s*\[")  # tqdm's carriage returns, or its "| 3/40 [" bar
LINK = re.compile(r"(!?\[[^\]]*\]\()([^)\s]+)(\))")  # Markdown [text](target) and ![alt](target)
ROOT = f"{repo_root()}/"  # the clone's path, in a warning's file names: written relative to it
SRC_ATTR = re.compile(r"""(\bsrc=["'])([^"']+)(["'])""")


Link = bool | frozenset[str]  # figures to link: none, all committed ones, or these


class PageBudgetError(ArtifactError):
    """The pages together exceed :data:`BUDGET`, even with the committed figures linked."""


class FigureIndex:
    """The committed figures folder's PNG and MP4 files, found by name or by their bytes."""

    def __init__(self, folder: Path | None) -> None:
        files = sorted(folder.glob("*.png")) + sorted(folder.glob("*.mp4")) if folder else []
        self.by_digest = {hashlib.sha256(p.read_bytes()).hexdigest(): p.name for p in files}
        self.files = {p.name: p for p in files}

    def name_of(self, data: bytes) -> str | None:
        """The name of the committed file with exactly these bytes, if any."""
        return self.by_digest.get(hashlib.sha256(data).hexdigest())

    def read(self, name: str) -> bytes | None:
        """The bytes of the committed file ``name``, if it is there."""
        return self.files[name].read_bytes() if name in self.files else None


def cell_text(value: str | list[str]) -> str:
    """A notebook's multi-line string (a string or a list of lines) as one string."""
    return value if isinstance(value, str) else "".join(value)


def _relink(target: str) -> str:
    """A relative link written from ``notebooks/``, as seen from ``figures/notebooks/``."""
    if re.match(r"^([a-z][a-z0-9+.-]*:|#|/)", target, re.IGNORECASE):
        return target  # a URL, an anchor or an absolute path
    path, sep, anchor = target.partition("#")
    moved = posixpath.relpath(posixpath.normpath(posixpath.join(SOURCE_DIR, path)), PAGE_DIR)
    return moved + sep + anchor


def relink_markdown(text: str) -> str:
    """Every relative Markdown link and ``src=`` attribute of ``text``, moved to the pages' folder."""
    text = LINK.sub(lambda m: m.group(1) + _relink(m.group(2)) + m.group(3), text)
    return SRC_ATTR.sub(lambda m: m.group(1) + _relink(m.group(2)) + m.group(3), text)


def _markdown_output(text: str, plain: str) -> dict[str, Any]:
    """A display output showing ``text`` as Markdown (``plain`` where Markdown is not rendered)."""
    data = {"text/markdown": text, "text/plain": plain}
    return {"data": data, "metadata": {}, "output_type": "display_data"}


def _video(data: dict[str, Any], figures: FigureIndex) -> dict[str, Any] | None:
    """An embedded video's replacement: a link to the committed MP4 it shows, or None (dropped)."""
    html = cell_text(data.get("text/html", ""))
    name = None
    if "video/mp4" in data:
        name = figures.name_of(base64.b64decode(cell_text(data["video/mp4"])))
    elif (match := DATA_MP4.search(html)) is not None:
        name = figures.name_of(base64.b64decode(re.sub(r"\s", "", match.group(1))))
    elif (match := VIDEO_SRC.search(html)) is not None:
        base = posixpath.basename(match.group(1))
        name = base if base in figures.files else None
    return None if name is None else _markdown_output(f"Video: [{name}](../{name})", f"video: {name}")


def _image(output: dict[str, Any], figures: FigureIndex, link: Link) -> dict[str, Any]:
    """An image output: its named figure's final bytes, or a link to the committed PNG ``link`` names."""
    png = cell_text(output["data"]["image/png"]).replace("\n", "")
    named = output.get("metadata", {}).get("image/png", {}).get("figure")
    final = figures.read(named) if isinstance(named, str) else None
    data = base64.b64decode(png) if final is None else final
    name = named if final is not None else figures.name_of(data)
    if name is not None and (link is True or (not isinstance(link, bool) and name in link)):
        return _markdown_output(f"![{name}](../{name})", f"figure: {name}")
    out = copy.deepcopy(output)
    out["data"]["image/png"] = base64.b64encode(data).decode("ascii")
    return out


def _clean_output(
    output: dict[str, Any], figures: FigureIndex, link: Link, count: int, relink: bool = True
) -> dict[str, Any] | None:
    """One output as it appears on the page, or None if it is dropped."""
    kind = output["output_type"]
    if kind == "stream":
        text = cell_text(output["text"])
        if output["name"] == "stderr" and PROGRESS.search(text):
            return None  # a tqdm bar (widgets off: the bar redrawn with carriage returns)
        return {**copy.deepcopy(output), "text": text.replace(ROOT, "")}  # a warning's file path
    if kind not in ("display_data", "execute_result"):
        return copy.deepcopy(output)  # an error's traceback
    data = output.get("data", {})
    if WIDGET in data:
        return None  # a tqdm bar as a widget: no state is saved, so it would show "0%"
    if "video/mp4" in data or VIDEO_HTML.search(cell_text(data.get("text/html", ""))):
        return _video(data, figures)
    output = copy.deepcopy(output)
    if relink and "text/markdown" in data:
        output["data"]["text/markdown"] = relink_markdown(cell_text(data["text/markdown"]))
    if "image/png" in data:
        output = _image(output, figures, link)
    if output["output_type"] == "execute_result":
        output["execution_count"] = count
    return output


def _clean_cell(
    cell: dict[str, Any], figures: FigureIndex, link: Link, count: int, relink: bool = True
) -> dict[str, Any]:
    """One cell without volatile metadata, its outputs cleaned and numbered ``count``; links moved."""
    volatile = ("execution", "papermill", "collapsed", "scrolled")  # and empty tags
    metadata = {k: v for k, v in cell.get("metadata", {}).items() if k not in volatile and (v or k != "tags")}
    out = copy.deepcopy({**{k: v for k, v in cell.items() if k != "metadata"}, "metadata": metadata})
    if INJECTED in metadata.get("tags", ()):
        out["id"] = INJECTED  # papermill gives it a random id
    if cell["cell_type"] == "markdown" and relink:
        out["source"] = relink_markdown(cell_text(cell["source"]))
    if cell["cell_type"] == "code":
        out["execution_count"] = count
        outputs = (_clean_output(o, figures, link, count, relink) for o in cell.get("outputs", []))
        out["outputs"] = [o for o in outputs if o is not None]
    return out


def clean_notebook(
    notebook: dict[str, Any], figures: Path | FigureIndex | None = None, link_figures: Link = False
) -> dict[str, Any]:
    """The page of an executed notebook (cleaning it again leaves it as it is): no volatile metadata,
    progress bars or clone's path; counts 1..n; videos linked to the committed MP4 of their bytes; an
    image naming its figure given its final bytes, or linked per ``link_figures``; links moved."""
    index = figures if isinstance(figures, FigureIndex) else FigureIndex(figures)
    out = {k: copy.deepcopy(v) for k, v in notebook.items() if k not in ("cells", "metadata")}
    metadata = notebook.get("metadata", {})
    out["metadata"] = {k: copy.deepcopy(metadata[k]) for k in ("kernelspec",) if k in metadata}
    if "language_info" in metadata:  # its name only: the version is the machine's Python
        out["metadata"]["language_info"] = {"name": metadata["language_info"].get("name", "python")}
    relink = metadata.get("lasa", {}).get("links_from") != PAGE_DIR  # False for a page: idempotent
    out["metadata"]["lasa"] = {"links_from": PAGE_DIR}
    cells = notebook.get("cells", [])
    codes = itertools.accumulate(int(c["cell_type"] == "code") for c in cells)
    out["cells"] = [_clean_cell(c, index, link_figures, n, relink) for c, n in zip(cells, codes, strict=True)]
    return out


def page_text(notebook: dict[str, Any]) -> str:
    """A notebook as nbformat writes it (sorted keys, indent 1, lines split), with a final newline."""
    sys.modules.setdefault("rfc3987_syntax", None)  # type: ignore[arg-type]  # see lasa.pipeline.execute
    import nbformat

    text = nbformat.writes(nbformat.from_dict(notebook), version=4)
    return text if text.endswith("\n") else text + "\n"


def _read(path: Path) -> dict[str, Any]:
    try:
        data = json.loads(path.read_text())
    except (ValueError, UnicodeDecodeError) as exc:
        raise ArtifactError(f"{path} is not a notebook (JSON): {exc}") from None
    if not isinstance(data, dict) or "cells" not in data:
        raise ArtifactError(f"{path} is not a notebook: it has no cells")
    return data


# a failed run's copy (``x.failed.ipynb``), or a killed write's temporary file (``.x.1a2b.tmp.ipynb``)
_PARTIAL = re.compile(r"^\.|\.(failed|tmp)\.ipynb$")


def executed_notebooks(folder: Path) -> list[Path]:
    """The executed notebooks of ``folder`` (not the partial runs ``*.failed.ipynb``), by name."""
    if not folder.is_dir():
        raise ArtifactError(f"no executed notebooks: {folder} does not exist (run `make figures` first)")
    if not (found := sorted(p for p in folder.glob("*.ipynb") if not _PARTIAL.search(p.name))):
        raise ArtifactError(f"no executed notebooks in {folder} (run `make figures` first)")
    return found


def _to_link(taken: dict[str, int], excess: int) -> frozenset[str]:
    """The figures to link so that ``excess`` bytes go: the largest first (then by name)."""
    ranked = sorted(taken.items(), key=lambda kv: (-kv[1], kv[0]))
    freed = itertools.accumulate((size for _, size in ranked), initial=0)  # by the figures before each
    return frozenset(name for (name, _), before in zip(ranked, freed, strict=False) if before < excess)


def _size(pages: dict[str, str]) -> int:
    return sum(len(t.encode()) for t in pages.values())


def write_pages(
    executed: str | Path, figures: str | Path, budget: int = BUDGET
) -> tuple[list[Path], int, frozenset[str]]:
    """Write the page of each executed notebook of ``executed`` to ``<figures>/notebooks/``; return them,
    the bytes of all pages there and the figures linked to fit; PageBudgetError (nothing written) if over."""
    notebooks = {p.name: _read(p) for p in executed_notebooks(Path(executed))}
    index = FigureIndex(Path(figures))
    folder = Path(figures) / PAGES
    others = sum(p.stat().st_size for p in folder.glob("*.ipynb") if p.name not in notebooks)
    embedded = {name: clean_notebook(nb, index) for name, nb in notebooks.items()}
    pages = {name: page_text(page) for name, page in embedded.items()}
    linked: frozenset[str] = frozenset()
    if (excess := others + _size(pages) - budget) > 0:
        taken: dict[str, int] = {}  # the bytes each committed figure takes, embedded, over all pages
        outputs = (o for p in embedded.values() for cell in p["cells"] for o in cell.get("outputs", []))
        for png in (cell_text(o["data"]["image/png"]) for o in outputs if "image/png" in o.get("data", {})):
            if (name := index.name_of(base64.b64decode(png))) is not None:
                taken[name] = taken.get(name, 0) + len(png)
        linked = _to_link(taken, excess)
        pages = {name: page_text(clean_notebook(nb, index, linked)) for name, nb in notebooks.items()}
    if (total := others + _size(pages)) > budget:
        biggest = sorted(pages, key=lambda n: -len(pages[n].encode()))[:3]
        sizes = ", ".join(f"{n} {len(pages[n].encode()) / 1e6:.2f} MB" for n in biggest)
        raise PageBudgetError(
            f"the notebook pages would take {total / 1e6:.2f} MB, over the {budget / 1e6:g} MB budget even "
            f"with the committed figures linked; the largest: {sizes}. Show fewer or smaller images there."
        )
    return [write_text(folder / name, text) for name, text in pages.items()], total, linked


def main(argv: list[str] | None = None) -> int:
    """Command line: ``python -m lasa.pipeline.pages --notebooks build/notebooks --figures figures``."""
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--notebooks", required=True, help="the executed notebooks (e.g. build/notebooks)")
    parser.add_argument("--figures", required=True, help="the figures folder; pages go to its notebooks/")
    parser.add_argument("--budget", type=int, default=BUDGET, help="bytes of all pages [%(default)d]")
    args = parser.parse_args(argv)
    try:
        written, total, linked = write_pages(args.notebooks, args.figures, args.budget)
    except ArtifactError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1 if isinstance(exc, PageBudgetError) else 2
    how = f"linked to fit: {', '.join(sorted(linked))}" if linked else "figures embedded"
    print(f"{len(written)} notebook pages in {Path(args.figures) / PAGES} ({total / 1e6:.2f} MB, {how})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
