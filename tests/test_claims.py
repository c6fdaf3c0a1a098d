"""The claims table: rows keyed by a stable id, replaced per (figure, robot); the README's copy."""

import pandas as pd
import pytest

from lasa.base.errors import ConfigError
from lasa.evidence.claims import (
    CLAIM_COLUMNS,
    README_MARKERS,
    Claim,
    _row,
    render_verdicts,
    sync_readme,
    update_claims,
)


def claim(name, text=None, figure="sim1", robot="planar5", verdict="yes"):
    return Claim(
        id=f"{figure}.{name}",
        claim=text or f"claim {name}",
        figure=figure,
        paper="p",
        measured="m",
        reproduced=verdict,
        note="n",
        robot=robot,
    )


def test_update_replaces_own_rows_and_keeps_others(tmp_path):
    path = tmp_path / "claims.csv"
    update_claims(path, [claim("a"), claim("b")])
    update_claims(path, [claim("x", figure="sim2")])
    update_claims(path, [claim("a", robot="panda")])
    table = update_claims(path, [claim("a", verdict="no"), claim("b")])
    assert list(table.columns) == list(CLAIM_COLUMNS)
    assert len(table) == 4
    mine = table[(table.figure == "sim1") & (table.robot == "planar5")].set_index("id")
    assert mine.loc["sim1.a", "reproduced"] == "no"
    assert len(pd.read_csv(path)) == 4
    md = path.with_suffix(".md").read_text()
    assert md.startswith("| id | claim | figure |") and md.count("\n") == 6


def test_a_reworded_claim_replaces_its_row(tmp_path):
    path = tmp_path / "claims.csv"
    update_claims(path, [claim("a", "SA lowers the error")])
    table = update_claims(path, [claim("a", "SA lowers the final state error")])
    assert list(table.claim) == ["SA lowers the final state error"]


def test_a_claim_a_figure_no_longer_makes_leaves_the_table(tmp_path):
    path = tmp_path / "claims.csv"
    update_claims(path, [claim("a"), claim("old")])
    table = update_claims(path, [claim("a")])
    assert list(table.id) == ["sim1.a"]


def test_ids_are_checked():
    with pytest.raises(ConfigError, match="claim id"):
        Claim(
            id="final error",
            claim="c",
            figure="sim1",
            paper="",
            measured="",
            reproduced="yes",
            note="",
            robot="r",
        )
    with pytest.raises(ConfigError, match="claim id"):
        claim("a", figure="sim1").__class__(
            **{**claim("a").__dict__, "id": "sim2.a"}  # an id of another figure
        )
    with pytest.raises(ConfigError, match="unique"):
        update_claims("unused.csv", [claim("a"), claim("a")])


def test_pipes_in_text_are_escaped(tmp_path):
    update_claims(tmp_path / "c.csv", [claim("a", "a | b")])
    assert "a \\| b" in (tmp_path / "c.md").read_text()


def test_bad_verdict_is_refused():
    with pytest.raises(ConfigError, match="reproduced"):
        claim("a", verdict="maybe")


def test_foreign_file_is_refused(tmp_path):
    path = tmp_path / "claims.csv"
    path.write_text("a,b\n1,2\n")
    with pytest.raises(ConfigError, match="columns"):
        update_claims(path, [claim("a")])


def test_readme_gets_the_table_between_its_markers(tmp_path):
    begin, end = README_MARKERS
    readme, table = tmp_path / "README.md", tmp_path / "claims.md"
    readme.write_text(f"# x\n\n{begin}\nold table\n{end}\n\nafter\n")
    table.write_text("| id |\n| --- |\n| sim1.a |\n")
    assert sync_readme(readme, table) is True
    assert readme.read_text() == f"# x\n\n{begin}\n| id |\n| --- |\n| sim1.a |\n{end}\n\nafter\n"
    assert sync_readme(readme, table) is False  # already current
    readme.write_text("no markers\n")
    with pytest.raises(ConfigError, match="must hold"):
        sync_readme(readme, table)


def test_the_repository_readme_holds_the_committed_verdict_table():
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    begin, end = README_MARKERS
    text = (root / "README.md").read_text()
    block = text.split(begin, 1)[1].split(end, 1)[0].strip()
    assert block == (root / "figures" / "verdicts.md").read_text().strip()
    assert len(text.splitlines()) <= 250 and text[: text.index(end)].count("\n") <= 80
    table = pd.read_csv(root / "figures" / "claims.csv", dtype=str, keep_default_na=False)
    assert (root / "figures" / "verdicts.md").read_text() == render_verdicts(table)  # generated, not edited


def test_the_verdict_table_has_a_row_per_paper_claim_with_both_robots_and_the_flips():
    def row(cid, robot, verdict, n):
        base = claim("time_ratio", robot=robot, verdict=verdict)
        return Claim(**{**base.__dict__, "id": cid, "n_users": n, "settled": verdict != "undecided"})

    rows = []
    for robot, head, other in (("planar5", "no", "partly"), ("panda", "undecided", "undecided")):
        rows.append(row("sim1.time_ratio", robot, head, 150))
        rows.append(row("sim1.time_ratio@grasp_set", robot, other, 60))
    table = pd.DataFrame([_row(c) for c in rows], columns=list(CLAIM_COLUMNS)).astype(str)
    md = render_verdicts(table)
    lines = md.strip().splitlines()
    assert len(lines) == 3  # header, rule, one claim (claims without rows are left out)
    cells = [c.strip() for c in lines[2].strip("|").split("|")]
    assert cells[1] == "time ratio 1.45 and 1.30"
    assert cells[2].startswith("**no**") and "N = 150" in cells[2] and "settled" in cells[2]
    assert cells[3].startswith("undecided") and "settled" not in cells[3]
    assert cells[4] == "`grasp_set` (planar5 partly)"  # the Panda's reading agrees with its headline
    assert "(notebooks/04_fixed_expertise.ipynb#what-it-shows-against-the-paper)" in cells[5]


def test_a_claim_that_is_not_testable_is_written_and_rendered_with_its_reason(tmp_path):
    from lasa.evidence.claims import VERDICTS
    from lasa.evidence.rules import NOT_TESTABLE

    assert NOT_TESTABLE == "not testable" and NOT_TESTABLE in VERDICTS
    with pytest.raises(ConfigError, match="never settled"):
        Claim(**{**claim("h3", figure="study").__dict__, "reproduced": NOT_TESTABLE, "settled": True})
    measured = "not testable (completion: LA 0%, LA+SA 0%); mean total (idle) time ..."
    guard = Claim(
        **{
            **claim("h3", figure="study", robot="panda").__dict__,
            "id": "study.h3",
            "reproduced": NOT_TESTABLE,
            "measured": measured,
            "n_users": 10,
        }
    )
    reason = "not testable (no decoder with both halves of the property; best reading t). 10 participants"
    other = Claim(**{**guard.__dict__, "id": "study.h2", "measured": "alignment +0.04", "note": reason})
    table = update_claims(tmp_path / "claims.csv", [guard, other]).set_index("id")
    assert table.loc["study.h3", "reproduced"] == NOT_TESTABLE and table.loc["study.h3", "settled"] == "no"
    assert table.loc["study.h3", "ci_low"] == "" and "nan" not in (tmp_path / "claims.md").read_text()
    cells = {
        line.split("|")[1].strip(): line.split("|")[4].strip()
        for line in render_verdicts(table.reset_index().astype(str)).splitlines()[2:]
    }
    h3 = next(v for k, v in cells.items() if k.startswith("H3"))
    h2 = next(v for k, v in cells.items() if k.startswith("H2"))
    assert h3 == "not testable, N = 10 (completion: LA 0%, LA+SA 0%)"  # the reason from measured
    assert h2 == "not testable, N = 10 (no decoder with both halves of the property; best reading t)"
