"""A browsable book of the executed notebooks, built offline with Jupyter Book (``make book``).
The verdict table as front page, the notebooks in the paper's order, the claims table last; nothing runs."""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd

from lasa.base.errors import ArtifactError
from lasa.base.io import require_file, write_text
from lasa.base.paths import repo_root, resolve
from lasa.evidence.claims import render_markdown, render_verdicts
from lasa.evidence.values import VALUES_NAME, Values, read_values
from lasa.pipeline.pages import cell_text, executed_notebooks

ROBOT_TITLES = {"planar5": "planar5 (5-DoF planar arm)", "panda": "Panda (7-DoF Franka)"}  # paper's order


def ordered_notebooks(folder: Path) -> list[Path]:
    """The executed notebooks in ``folder``, in the paper's order (number, then planar5, Panda)."""
    rank = {robot: i for i, robot in enumerate(ROBOT_TITLES)}
    runs = {p: p.stem.partition("-")[::2] for p in executed_notebooks(folder)}  # (stem, robot)
    return sorted(runs, key=lambda p: (runs[p][0], rank.get(runs[p][1], -1)))


def front_page(claims: pd.DataFrame, pages: set[str], values: Values | None = None) -> str:
    """The front page's Markdown: what the book is, then the verdict table with the claims' ``values``."""

    def link(stem: str) -> str:
        found = (name for name in (f"{stem}-planar5", stem, f"{stem}-panda") if name in pages)
        return f"{next(found, stem)}.ipynb"

    lines = [
        "# lasa: Shared Autonomy with Learned Latent Actions",
        "",
        "The executed notebooks of a `make figures` run of **lasa**, a reproducibility package for Jeon,",
        'Losey & Sadigh, "Shared Autonomy with Learned Latent Actions" (RSS 2020). The table says, claim by',
        "claim and robot, whether the paper's result reproduced, in two words: the effect (the claim's",
        "shape, settled when every interval is clear of its rule's thresholds, else undecided) and, for",
        "each number the paper states, whether it lies in our interval (in, out or undecided), with the",
        "numbers and N (simulated users per point, or participants). Each row links to the notebook that",
        "measures it. The pages that follow are the notebooks, in the paper's order; the full claims",
        "table, every reading of every claim, is the last page.",
        "",
        # the front page's links are put under notebooks/ (_write_sources): claims.md is beside it
        render_verdicts(claims, values or {}, link, claims_md="../claims.md"),
    ]
    return "\n".join(lines)


def claims_page(claims: pd.DataFrame) -> str:
    """The full claims table (``figures/claims.md``) as a page of its own."""
    return "# Every reading of every claim\n\nThe rows of `figures/claims.csv`.\n\n" + render_markdown(claims)


def retitle(notebook: Path, robot: str) -> None:
    """Append the robot to a notebook's first heading, so its two robots' pages differ."""
    nb = json.loads(notebook.read_text())
    for cell in nb["cells"]:
        if cell["cell_type"] == "markdown" and (text := cell_text(cell["source"])).startswith("# "):
            first, newline, rest = text.partition("\n")
            cell["source"] = f"{first} — {ROBOT_TITLES.get(robot, robot)}" + (newline + rest if rest else "")
            break
    write_text(notebook, json.dumps(nb, indent=1, ensure_ascii=False) + "\n")


def build_book(notebooks: str | Path, figures: str | Path, out: str | Path, progress: bool = True) -> Path:
    """Build the book's sources in ``out/src``, its site in ``out/html``; return its ``index.html``."""
    notebooks, figures, out = resolve(notebooks), resolve(figures), resolve(out)
    books = ordered_notebooks(notebooks)
    claims_csv = require_file(figures / "claims.csv", "make figures")
    mathjax = require_file(repo_root() / ".venv" / "mathjax" / "es5" / "tex-chtml.js", "make setup").parent
    src = out / "src"
    build = out / "_build"
    _write_sources(src, books, figures, mathjax, pd.read_csv(claims_csv, dtype=str, keep_default_na=False))
    shutil.rmtree(build, ignore_errors=True)
    command = [
        str(Path(sys.executable).parent / "jupyter-book"),
        "build",
        str(src),
        "--path-output",
        str(out),
    ]
    result = subprocess.run(command, capture_output=not progress, text=True)
    html = build / "html"
    if result.returncode != 0 or not (html / "index.html").is_file():
        detail = "" if progress else (result.stdout or "")[-3000:] + (result.stderr or "")[-3000:]
        raise ArtifactError(f"jupyter-book could not build the book from {src}\n{detail}")
    target = out / "html"
    shutil.rmtree(target, ignore_errors=True)
    shutil.move(str(html), target)
    shutil.rmtree(build, ignore_errors=True)
    return target / "index.html"


_CONFIG = """title: lasa
author: the lasa developers
only_build_toc_files: true
execute:
  execute_notebooks: 'off'
launch_buttons:
  thebe: false
sphinx:
  config:
    mathjax_path: ../mathjax/tex-chtml.js
    html_extra_path: ['_extra']
    nb_ipywidgets_js: {}
    html_show_sourcelink: false
"""  # Jupyter Book's _config.yml: nothing executed, MathJax served from the site, no CDN widgets


def _write_sources(src: Path, books: list[Path], figures: Path, mathjax: Path, claims: pd.DataFrame) -> None:
    """The book's sources in ``src``: notebooks (retitled per robot), figures, MathJax, pages, contents."""
    shutil.rmtree(src, ignore_errors=True)
    (src / "notebooks").mkdir(parents=True)
    for book in books:
        shutil.copy2(book, src / "notebooks" / book.name)
        if robot := book.stem.partition("-")[2]:
            retitle(src / "notebooks" / book.name, robot)
    shutil.copytree(figures, src / "figures", ignore=shutil.ignore_patterns("*.csv", "*.md"))
    shutil.copytree(mathjax, src / "_extra" / "mathjax")
    values_csv = figures / VALUES_NAME
    values = (
        read_values(pd.read_csv(values_csv, dtype=str, keep_default_na=False)) if values_csv.is_file() else {}
    )
    index = front_page(claims, {b.stem for b in books}, values).replace("](", "](notebooks/")
    write_text(src / "index.md", index)
    write_text(src / "claims.md", claims_page(claims))
    toc = ["format: jb-book", "root: index", "chapters:"] + [f"- file: notebooks/{b.stem}" for b in books]
    toc.append("- file: claims")
    write_text(src / "_toc.yml", "\n".join(toc) + "\n")
    write_text(src / "_config.yml", _CONFIG)


def main(argv: list[str] | None = None) -> int:
    """Command line: ``python -m lasa.pipeline.book [--notebooks DIR] [--figures DIR] [--out DIR]``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--notebooks", default="build/notebooks", help="the executed notebooks [%(default)s]")
    parser.add_argument("--figures", default="figures", help="the figures and claims table [%(default)s]")
    parser.add_argument("--out", default="build/book", help="where the HTML book goes [%(default)s]")
    args = parser.parse_args(argv)
    try:
        index = build_book(args.notebooks, args.figures, args.out)
    except ArtifactError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"book: {index}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
