"""The committed notebook pages (lasa.pipeline.pages): cleaned, stable, within the budget."""

from __future__ import annotations

import base64
import json
import subprocess
from pathlib import Path

import pytest

from lasa.base.errors import ArtifactError
from lasa.pipeline.pages import (
    BUDGET,
    PageBudgetError,
    _to_link,
    clean_notebook,
    main,
    page_text,
    relink_markdown,
    write_pages,
)

ROOT = Path(__file__).resolve().parents[1]
PNG = b"\x89PNG\r\n\x1a\n" + bytes(range(64))  # the bytes of a committed figure
OTHER_PNG = b"\x89PNG\r\n\x1a\n" + bytes(range(64, 0, -1))  # an image not in figures/
MP4 = b"\x00\x00\x00\x18ftypmp42" + bytes(32)
STAMP = {"iopub.execute_input": "2026-01-01T00:00:00Z", "shell.execute_reply": "2026-01-01T00:00:01Z"}
PAPERMILL_CELL = {
    "duration": 0.5,
    "start_time": "2026-01-01",
    "end_time": "2026-01-01",
    "status": "completed",
}


def _b64(data: bytes) -> str:
    return base64.b64encode(data).decode("ascii")


def _code(cell_id: str, count: int, outputs: list[dict], tags: list[str] | None = None) -> dict:
    metadata = {"execution": dict(STAMP), "papermill": dict(PAPERMILL_CELL), "tags": tags or []}
    return {
        "cell_type": "code",
        "execution_count": count,
        "id": cell_id,
        "metadata": metadata,
        "outputs": outputs,
        "source": "x = 1",
    }


def _display(data: dict, kind: str = "display_data", metadata: dict | None = None, count: int = 0) -> dict:
    out = {"data": data, "metadata": metadata or {}, "output_type": kind}
    if kind == "execute_result":
        out["execution_count"] = count
    return out


def _executed() -> dict:
    """A small executed notebook with every kind of output the pipeline's notebooks produce."""
    tqdm_stderr = {
        "name": "stderr",
        "output_type": "stream",
        "text": "train:  50%|#####     | 5/10 [00:01<00:01]\r",
    }
    widget = _display({"application/vnd.jupyter.widget-view+json": {"model_id": "abc"}, "text/plain": "0%"})
    table = _display({"text/html": "<table></table>", "text/plain": "a  b\n1  2"}, "execute_result", count=7)
    sentences = {"name": "stdout", "output_type": "stream", "text": ["panda: V rose on 0 steps.\n"]}
    shows = _display({"text/markdown": "See ![fig](../figures/sim.png) and [notes](../docs/notes.md#x)."})
    video = _display({"text/html": f'<video controls src="data:video/mp4;base64,{_b64(MP4)}"></video>'})
    stray_video = _display({"text/html": "<video src='elsewhere.mp4'></video>"})
    figure = _display({"image/png": _b64(PNG), "text/plain": "<Figure>"})
    frame = _display({"image/png": _b64(OTHER_PNG), "text/plain": "<Figure>"})
    cells = [
        {
            "cell_type": "markdown",
            "id": "md",
            "metadata": {"papermill": {}, "tags": []},
            "source": "![p](../figures/sim.png)",
        },
        _code("params", 3, [], ["parameters"]),
        _code("0e65a25a", 4, [], ["injected-parameters"]),
        _code("run", 5, [tqdm_stderr, widget, table, sentences]),
        _code("show", 9, [shows, video, stray_video, figure, frame]),
    ]
    metadata = {
        "kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"},
        "language_info": {"name": "python", "version": "3.11.7"},
        "papermill": {"duration": 8.8, "start_time": "2026-01-01", "parameters": {"robot": "panda"}},
        "widgets": {"application/vnd.jupyter.widget-state+json": {"state": {}}},
    }
    return {"cells": cells, "metadata": metadata, "nbformat": 4, "nbformat_minor": 5}


@pytest.fixture
def figures(tmp_path: Path) -> Path:
    folder = tmp_path / "figures"
    folder.mkdir()
    (folder / "sim.png").write_bytes(PNG)
    (folder / "rollouts_panda.mp4").write_bytes(MP4)
    return folder


def _outputs(page: dict, cell_id: str) -> list[dict]:
    return next(c for c in page["cells"] if c["id"] == cell_id)["outputs"]


def test_volatile_metadata_is_dropped(figures):
    page = clean_notebook(_executed(), figures)
    assert set(page["metadata"]) == {"kernelspec", "language_info", "lasa"}
    assert page["metadata"]["language_info"] == {"name": "python"}
    assert [c["metadata"] for c in page["cells"]] == [
        {},
        {"tags": ["parameters"]},
        {"tags": ["injected-parameters"]},
        {},
        {},
    ]
    code = [c for c in page["cells"] if c["cell_type"] == "code"]
    assert [c["execution_count"] for c in code] == [1, 2, 3, 4]  # papermill's 3, 4, 5, 9 renumbered
    assert _outputs(page, "run")[0]["execution_count"] == 3  # the table's result follows its cell
    assert code[1]["id"] == "injected-parameters"  # papermill's random id, made stable


def test_progress_bars_dropped_results_kept(figures):
    outputs = _outputs(clean_notebook(_executed(), figures), "run")
    assert [o["output_type"] for o in outputs] == ["execute_result", "stream"]
    assert outputs[0]["data"]["text/plain"] == "a  b\n1  2"
    assert outputs[1] == {"name": "stdout", "output_type": "stream", "text": "panda: V rose on 0 steps.\n"}


def test_warning_keeps_no_clone_path(figures):
    notebook = _executed()
    warning = f"{ROOT}/lasa/x.py:3: UserWarning: tight layout\n"
    notebook["cells"][3]["outputs"] = [{"name": "stderr", "output_type": "stream", "text": warning}]
    assert (
        _outputs(clean_notebook(notebook, figures), "run")[0]["text"]
        == "lasa/x.py:3: UserWarning: tight layout\n"
    )


def test_video_replaced_by_link_or_dropped_figures_kept(figures):
    outputs = _outputs(clean_notebook(_executed(), figures), "show")
    assert outputs[0]["data"]["text/markdown"] == "See ![fig](../sim.png) and [notes](../../docs/notes.md#x)."
    assert outputs[1]["data"]["text/markdown"] == "Video: [rollouts_panda.mp4](../rollouts_panda.mp4)"
    assert "<video" not in json.dumps(outputs)  # the unmatched video is dropped
    assert [base64.b64decode(o["data"]["image/png"]) for o in outputs[2:]] == [PNG, OTHER_PNG]


def test_markdown_cell_links_move_to_the_pages_folder(figures):
    assert clean_notebook(_executed(), figures)["cells"][0]["source"] == "![p](../sim.png)"
    assert relink_markdown("[a](https://x.org/y) [b](#top) <img src='../figures/z.png'>") == (
        "[a](https://x.org/y) [b](#top) <img src='../z.png'>"
    )


def test_figures_linked_when_asked(figures):
    outputs = _outputs(clean_notebook(_executed(), figures, link_figures=True), "show")
    assert outputs[2]["data"]["text/markdown"] == "![sim.png](../sim.png)"  # a committed figure: linked
    assert base64.b64decode(outputs[3]["data"]["image/png"]) == OTHER_PNG  # not committed: kept


def test_named_figure_shows_its_final_bytes(figures):
    notebook = _executed()
    stale = _display({"image/png": _b64(OTHER_PNG)}, metadata={"image/png": {"figure": "sim.png"}})
    notebook["cells"][4]["outputs"] = [stale]
    (out,) = _outputs(clean_notebook(notebook, figures), "show")
    assert base64.b64decode(out["data"]["image/png"]) == PNG  # the committed figure, not the stale copy


def test_deterministic_and_idempotent(figures):
    first = page_text(clean_notebook(_executed(), figures))
    assert first == page_text(clean_notebook(_executed(), figures))
    again = page_text(clean_notebook(json.loads(first), figures))
    assert again == first
    assert first.endswith("}\n") and '\n "cells": [' in first  # nbformat's layout: indent 1, sorted keys
    assert json.loads(first)["nbformat"] == 4


def _executed_folder(tmp_path: Path, n: int = 2) -> Path:
    folder = tmp_path / "build" / "notebooks"
    folder.mkdir(parents=True)
    for i in range(n):
        (folder / f"0{i}_x-panda.ipynb").write_text(json.dumps(_executed()))
    (folder / "09_x-panda.failed.ipynb").write_text("{}")  # a partial run: never a page
    (folder / ".08_x-panda.k2j4.tmp.ipynb").write_text("{}")  # a killed write's temporary file: neither
    return folder


def test_write_pages(tmp_path, figures):
    executed = _executed_folder(tmp_path)
    written, total, linked = write_pages(executed, figures)
    assert [p.name for p in written] == ["00_x-panda.ipynb", "01_x-panda.ipynb"]
    assert all(p.parent == figures / "notebooks" for p in written)
    assert total == sum(p.stat().st_size for p in written) and not linked
    before = [p.read_bytes() for p in written]
    write_pages(executed, figures)
    assert [p.read_bytes() for p in written] == before  # the same bytes on every run


def test_budget_links_figures_then_fails(tmp_path, figures, capsys):
    executed = _executed_folder(tmp_path)
    embedded = write_pages(executed, figures)[1]
    linked_total = write_pages(executed, figures, budget=embedded - 1)
    assert linked_total[2] == {"sim.png"} and linked_total[1] < embedded
    pages = figures / "notebooks"
    assert "![sim.png](../sim.png)" in (pages / "00_x-panda.ipynb").read_text()
    with pytest.raises(PageBudgetError, match="over the"):
        write_pages(executed, figures, budget=linked_total[1] - 1)
    assert main(["--notebooks", str(executed), "--figures", str(figures), "--budget", "10"]) == 1
    assert "budget" in capsys.readouterr().err


def test_missing_executed_notebooks_is_a_clear_error(tmp_path, figures):
    with pytest.raises(ArtifactError, match="run `make figures` first"):
        write_pages(tmp_path / "nothing", figures)


def test_committed_pages_within_budget():
    pages = sorted((ROOT / "figures" / "notebooks").glob("*.ipynb"))
    assert sum(p.stat().st_size for p in pages) <= BUDGET
    for page in pages:  # each as the cleaner leaves it: no progress bars, videos or timings
        text = page.read_text()
        assert "widget-view" not in text and "<video" not in text and '"papermill"' not in text


def test_make_figures_writes_the_pages():
    out = subprocess.run(
        ["make", "-n", "figures", "QUICK=1"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout
    lines = [line for line in out.splitlines() if "lasa.pipeline.pages" in line]
    assert lines, out
    assert "--notebooks build/quick/notebooks" in lines[0] and "--figures build/quick/figures" in lines[0]
    assert out.index("lasa.pipeline.pages") > out.rindex("lasa.pipeline.execute")  # after every notebook


def test_the_largest_figures_are_linked_first():
    taken = {"a.png": 300, "b.png": 500, "c.png": 300, "d.png": 100}
    assert _to_link(taken, 0) == frozenset()
    assert _to_link(taken, 450) == {"b.png"}
    assert _to_link(taken, 501) == {"b.png", "a.png"}  # equal sizes: by name
    assert _to_link(taken, 10_000) == set(taken)
