"""The claims table: rows keyed by a stable id, replaced per (figure, robot); the README's copy."""

import pandas as pd
import pytest

from lasa.base.errors import ConfigError
from lasa.evidence.claims import (
    CLAIM_COLUMNS,
    README_MARKERS,
    ROBOTS,
    SHOWN_COLUMNS,
    Claim,
    _row,
    claims_frame,
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
    assert mine.loc["sim1.a", "reproduced"] == "not reproduced"  # the table's word for a settled no
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
    assert len(text.splitlines()) <= 200 and text[: text.index(end)].count("\n") <= 80
    # for a newcomer: the prerequisites by the commands, the reading names before the table uses
    # them, and what does not reproduce (at most 10 lines) right under it
    assert text.index("**Needs:**") < text.index("make figures") < text.index(begin)
    assert "**Reading names.**" in text[: text.index(begin)]
    after = text[text.index(end) :].split("\n\n")[1]
    assert after.startswith("**What does not reproduce, and why.**") and after.count("\n") < 10
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
        rows.append(row("sim1.time_ratio@grasp_set+one_step", robot, head, 60))  # agrees: not listed
    rows.append(row("sim1.time_ratio@hindsight+one_step", "panda", "no", 60))  # compound, differs
    table = pd.DataFrame([_row(c) for c in rows], columns=list(CLAIM_COLUMNS)).astype(str)
    md = render_verdicts(table)
    lines = md.strip().splitlines()
    # the count line with the fragile rows, a blank line, header, rule, one claim (claims without
    # rows are left out)
    assert len(lines) == 5
    assert lines[0].startswith(
        "Of 2 paper claims × robot, the effect: 0 reproduced, 0 partly, 1 not reproduced, 1 undecided, "
        "0 not testable. Of the 0 numbers the paper states (× robot), the number: 0 in, 0 out, 0 undecided. "
        "Fragile (an interval ends within a fifth of its width"
    )
    cells = [c.strip() for c in lines[4].strip("|").split("|")]
    assert cells[1] == "time ratio 1.45 and 1.30"
    assert cells[2].startswith("**effect not reproduced**")
    assert "N = 150" in cells[2] and "settled" in cells[2]
    assert cells[3].startswith("effect undecided") and "settled" not in cells[3]
    # the Panda's grasp_set agrees with its headline; a compound reading that differs is listed too
    assert cells[4] == (
        "`grasp_set` (planar5: effect partly; number n/a); "
        "`hindsight+one_step` (panda: effect not reproduced; number n/a)"
    )
    assert "(notebooks/04_fixed_expertise.ipynb#what-it-shows-against-the-paper)" in cells[5]


def test_a_claim_that_is_not_testable_is_written_and_rendered_with_its_reason(tmp_path):
    from lasa.evidence.claims import VERDICTS
    from lasa.evidence.decision import NOT_TESTABLE

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
        for line in render_verdicts(table.reset_index().astype(str)).splitlines()[4:]
    }
    h3 = next(v for k, v in cells.items() if k.startswith("H3"))
    h2 = next(v for k, v in cells.items() if k.startswith("H2"))
    assert h3 == "effect not testable, N = 10 (completion: LA 0%, LA+SA 0%)"  # the reason from measured
    assert h2 == "effect not testable, N = 10 (no decoder with both halves of the property; best reading t)"
    assert table.loc["study.h3", "effect"] == NOT_TESTABLE and table.loc["study.h3", "number"] == "n/a"


def _time_ratio(robot, low75, high75, low1000, high1000, reading="undecided"):
    base = claim("time_ratio", robot=robot, verdict=reading)
    intervals = {"ratio_75": (low75, high75), "ratio_1000": (low1000, high1000)}
    values = {k: (lo + hi) / 2 for k, (lo, hi) in intervals.items()}
    return Claim(**{**base.__dict__, "n_users": 150, "intervals": intervals, "values": values})


def test_each_paper_number_gets_its_own_word_beside_the_effect():
    # the paper: 1.45 at beta = 75 and 1.30 at beta = 1000, each +- 0.15 by the rule
    row = _row(_time_ratio("planar5", 0.844, 1.1, 1.34, 1.39))
    assert row["effect"] == "undecided"  # the rule's reading: ratio_75's interval straddles 1
    assert row["number"] == "out; in"  # [0.844, 1.1] misses [1.30, 1.60]; [1.34, 1.39] inside [1.15, 1.45]
    assert row["reproduced"] == "not reproduced"  # both in one word: a number is out
    assert row["paper_in_ci"] == "no; yes"  # 1.30 +- 0.15 meets [1.34, 1.39]
    assert row["direction"] == "no"  # ratio_75's interval straddles 1
    assert row["paper_numbers"] == (
        "1.45 ± 0.15 (beta = 75): out, 0.972 [0.844, 1.1]; 1.3 ± 0.15 (beta = 1000): in, 1.36 [1.34, 1.39]"
    )
    assert str(row["note"]).startswith("Effect undecided; 1.45 out, 1.3 in. ")  # the note's words: the row's
    both = _row(_time_ratio("panda", 1.35, 1.55, 1.2, 1.5, reading="yes"))
    assert both["effect"] == "reproduced" and both["number"] == "in; undecided"  # [1.2, 1.5] crosses 1.45
    assert both["reproduced"] == "undecided" and both["paper_in_ci"] == "yes; yes"
    assert both["direction"] == "yes"
    table = pd.DataFrame([row, both], columns=list(CLAIM_COLUMNS)).astype(str)
    md = render_verdicts(table)
    assert "effect undecided; 1.45 out (0.972 [0.844, 1.1]); 1.3 in (1.36 [1.34, 1.39])" in md
    assert "**effect reproduced**; 1.45 in (1.45 [1.35, 1.55]); 1.3 undecided (1.35 [1.2, 1.5])" in md
    assert "Of the 4 numbers the paper states (× robot), the number: 2 in, 1 out, 1 undecided." in md
    assert "nan" not in md


def test_a_rule_without_paper_numbers_reads_n_a_and_our_additions_stand_apart():
    trapped = Claim(
        **{
            **claim("sa_trapped", figure="sim2").__dict__,
            "settled": True,
            "intervals": {"error_growth": (0.05, 0.27), "confidence_drop": (0.7, 0.9)},
        }
    )
    row = _row(trapped)
    assert row["paper_in_ci"] == "n/a" and row["paper_numbers"] == ""  # the paper states an ordering
    assert row["number"] == "n/a" and row["effect"] == "reproduced" == row["reproduced"]
    assert row["direction"] == "yes"  # the final error grows with N
    assert str(row["note"]).startswith("Effect reproduced; number n/a. ")
    base = claim("grasp_linear", figure="sim4")
    ours = Claim(**{**base.__dict__, "reproduced": "undecided", "intervals": {"slope": (0.05, 0.2)}})
    assert _row(ours)["paper_in_ci"] == "yes; n/a"  # 0.11 in [0.05, 0.2]; R^2's interval unknown
    assert _row(ours)["number"] == "in; n/a"  # no tolerance: in when our interval contains 0.11
    table = pd.DataFrame([row, _row(ours)], columns=list(CLAIM_COLUMNS)).astype(str)
    md = render_verdicts(table)
    head, apart = md.split("Our additions, not claims of the paper (not counted above):")
    assert "grasp-to-grasp" in apart and "grasp-to-grasp" not in head
    assert head.startswith("Of 1 paper claims × robot, the effect: 1 reproduced,")


def test_the_word_follows_the_vocabulary():
    from lasa.evidence.decision import PaperNumber, effect_word, word

    ratio = (PaperNumber("r", 1.45, 0.15, "beta = 75"),)
    assert word("yes", {"r": (1.35, 1.55)}, ratio) == "reproduced"
    assert word("yes", {"r": (1.61, 1.7)}, ratio) == "not reproduced"  # the paper's value is excluded
    assert word("yes", {"r": (1.5, 1.7)}, ratio) == "undecided"  # the number crosses 1.60
    assert word("partly", {"r": (1.2, 1.4)}, ratio) == "partly"
    assert word("undecided", {"r": (1.2, 1.4)}, ratio) == "undecided"
    assert word("undecided", {"r": (0.8, 1.29)}, ratio) == "not reproduced"
    assert [effect_word(r) for r in ("yes", "partly", "no", "undecided", "not testable")] == [
        "reproduced",
        "partly",
        "not reproduced",
        "undecided",
        "not testable",
    ]
    assert word("not testable", {"r": (0.8, 1.0)}, ratio) == "not testable"
    assert word("no", {}, ()) == "not reproduced"
    with pytest.raises(ConfigError, match="cannot word"):
        word("maybe", {}, ())


def test_the_cell_shows_every_number_the_rule_reads():
    # the note as lasa.evidence.verdicts.assess writes it; the paper's number first, with its word
    note = (
        "150 users per point; 98.75% intervals: slope = 0.0131 [0.00828, 0.0177]; r2 = 0.964 [0.786, 0.997]; "
    )
    note += "share_below = 1 [1, 1]. Rule: ..."
    base = claim("straight_line_linear", figure="sim4")
    intervals = {"slope": (0.00828, 0.0177), "r2": (0.786, 0.997), "share_below": (1.0, 1.0)}
    row = Claim(
        **{
            **base.__dict__,
            "reproduced": "undecided",
            "note": note,
            "intervals": intervals,
            "values": {"slope": 0.0131, "r2": 0.964, "share_below": 1.0},
        }
    )
    table = pd.DataFrame([_row(row)], columns=list(CLAIM_COLUMNS)).astype(str)
    cell = render_verdicts(table).splitlines()[4].split("|")[3].strip()
    assert cell.startswith("effect undecided; 0.11 out (0.0131 [0.00828, 0.0177])")
    assert "; 0.98 in (0.964 [0.786, 0.997])" in cell  # no tolerance: in when the interval holds it
    assert "; share_below 1 [1, 1], N = 0" in cell and "r2 0.964" not in cell  # each number once


def _note_row(cid, robot, **intervals):
    """A claims row whose note states each number's interval as lasa.evidence.verdicts.assess does."""
    text = "; ".join(f"{k} = {(lo + hi) / 2:.3g} [{lo:.3g}, {hi:.3g}]" for k, (lo, hi) in intervals.items())
    base = claim(cid.split(".", 1)[1], figure=cid.split(".", 1)[0], robot=robot, verdict="undecided")
    return Claim(**{**base.__dict__, "note": f"150 users per point; 98.75% intervals: {text}. Rule: ..."})


def _mechanism(rows):
    table = pd.DataFrame([_row(c) for c in rows], columns=list(CLAIM_COLUMNS)).astype(str)
    return render_verdicts(table).splitlines()[4].split("|")[6].strip()


def test_a_result_sentence_follows_the_numbers_of_its_rows():
    # the time gap favours LA+SA at beta = 75 and grows on both robots; the error gap narrows on one
    # robot, and on the other LA+SA is worse at beta = 75: that narrowing is not the paper's gap
    rows = [
        _note_row(
            "sim1.gap_narrows",
            "planar5",
            time_narrowing=(-0.4, -0.2),
            time_gap_75=(0.1, 0.2),
            error_narrowing=(0.01, 0.02),
            error_gap_75=(0.02, 0.05),
        ),
        _note_row(
            "sim1.gap_narrows",
            "panda",
            time_narrowing=(-0.4, -0.3),
            time_gap_75=(0.1, 0.3),
            error_narrowing=(0.01, 0.02),
            error_gap_75=(-0.05, -0.02),
        ),
    ]
    assert _mechanism(rows).startswith(
        "the time gap grows (both robots); the error gap narrows (planar5); "
        "at beta = 75 LA+SA is worse, so the error gap is not the paper's (the Panda) ([04]("
    )
    # the same claim with both gaps narrowing: the sentence says so, nothing hand-written is left
    rows = [
        _note_row(
            "sim1.gap_narrows",
            r,
            time_narrowing=(0.1, 0.2),
            time_gap_75=(0.3, 0.4),
            error_narrowing=(0.1, 0.2),
            error_gap_75=(0.2, 0.3),
        )
        for r in ROBOTS
    ]
    narrows = "the time gap narrows (both robots); the error gap narrows (both robots)"
    assert _mechanism(rows).startswith(narrows)
    # a row without the numbers (a hand-made table) states no result, only the mechanism
    rows = [claim("time_ratio", robot=r) for r in ROBOTS]
    assert _mechanism(rows).startswith("the pull is largest far from the goal ([04](")


def _study_row(cid, reproduced, low, high, n, measured="m", note="participant model = planning; n"):
    base = claim(cid.split("@", 1)[0].split(".", 1)[1], figure="study", robot="panda", verdict="undecided")
    values = {"id": cid, "reproduced": reproduced, "ci_low": low, "ci_high": high, "n_users": n}
    return Claim(**{**base.__dict__, **values, "measured": measured, "note": note})


def test_the_studys_sentences_say_what_each_n_tells_and_what_was_cut():
    nan = float("nan")
    h2 = [
        _study_row("study.h2", "undecided", -0.01, 0.05, 10),
        _study_row("study.h2@cohort", "yes", 0.03, 0.06, 40),
    ]
    assert _mechanism(h2).startswith(
        "LA+SA tilts the fork further into the scoop than R+SA; 10 participants cannot tell, 40 tell it"
    )
    h2[0] = _study_row("study.h2", "yes", 0.01, 0.05, 10)
    assert "; 10 and 40 participants alike tell it (" in _mechanism(h2)
    # H2 gated by the compared conditions' completion: the sentence names it, not what each N tells
    gated = "not testable (completion: LA+SA 85%, alignment only on the phases reached); alignment ..."
    h2g = [_study_row("study.h2", "not testable", nan, nan, 10, measured=gated)]
    assert _mechanism(h2g).startswith(
        "the planning participants finish 85% of their LA+SA episodes: alignment is measured only on the "
        "phases they reached ("
    )
    # H3 settled on a censored lower bound: the sentence says the bound already decides it
    low = "censored: lower bound (completion: LA+SA 85%): LA+SA's restricted mean ..."
    h3c = [_study_row("study.h3", "no", 25.0, 88.0, 10, measured=low)]
    assert _mechanism(h3c).startswith("another condition is faster than LA+SA even as a lower bound; 10 ")
    h2 = [
        _study_row("study.h2", "undecided", -0.01, 0.05, 10),
        _study_row("study.h2@cohort", "no", -0.06, -0.03, 40),
    ]
    assert _mechanism(h2).startswith(
        "R+SA tilts the fork further into the scoop than LA+SA; 10 participants cannot"
    )
    cut = "not testable (completion: LA 90%, LA+SA 45%); SA - no SA = ..."
    h1 = [_study_row("study.h1", "not testable", nan, nan, 10, measured=cut)]
    assert _mechanism(h1).startswith(
        "the planning participants finish 90% of their LA episodes and 45% of their LA+SA episodes "
        "within the horizon: the rest are cut there, so Goal Error is censored ("
    )
    h3 = [_study_row("study.h3", "not testable", nan, nan, 10, measured=cut.replace("LA 90%, ", ""))]
    assert _mechanism(h3).startswith(
        "LA+SA finishes 45% of its episodes: the assistance holds planning participants at a bowl ("
    )
    h3 = [
        _study_row("study.h3", "not testable", nan, nan, 10, measured="not testable (completion: R 80%); x")
    ]
    assert _mechanism(h3).startswith("R finishes 80% of its episodes ([11](")  # not LA+SA: no bowl


def test_the_fragile_line_names_the_headline_rows_and_counts_the_readings():
    from lasa.evidence.claims import fragile_line

    table = pd.DataFrame(
        {
            "id": [
                "sim1.time_ratio",
                "sim1.time_ratio",
                "sim1.time_ratio@grasp_set",
                "sim2.sa_trapped@hindsight",
            ],
            "robot": ["panda", "planar5", "panda", "panda"],
            "fragile": ["yes", "no", "yes", "no"],
        }
    )
    line = fragile_line(table)
    assert "`sim1.time_ratio` (panda)" in line and "planar5" not in line
    assert line.endswith("and 1 of the 2 readings' rows (`fragile` in claims.csv).")
    assert "no headline row" in fragile_line(table.assign(fragile="no"))


def test_the_cli_writes_an_out_runs_verdicts_beside_its_claims(tmp_path):
    import shutil
    import subprocess
    import sys
    from pathlib import Path

    shutil.copy(Path(__file__).resolve().parents[1] / "figures" / "claims.csv", tmp_path / "claims.csv")
    subprocess.run([sys.executable, "-m", "lasa.evidence.claims", str(tmp_path / "claims.csv")], check=True)
    committed = Path(__file__).resolve().parents[1] / "figures" / "verdicts.md"
    assert (tmp_path / "verdicts.md").read_text() == committed.read_text()


def test_claims_frame_shows_a_notebooks_rows_in_order():
    rows = [claim("b", verdict="no"), claim("a", robot="panda")]
    shown = claims_frame(rows)
    assert list(shown.columns) == list(SHOWN_COLUMNS) and list(shown.id) == ["sim1.b", "sim1.a"]
    assert list(shown.reproduced) == ["no", "yes"] and list(shown.assistance) == ["point", "point"]
    assert "assistance" not in claims_frame(rows, assistance=False).columns
    assert list(claims_frame(rows, assistance=False).columns) == [
        c for c in SHOWN_COLUMNS if c != "assistance"
    ]
    empty = claims_frame([])
    assert empty.empty and list(empty.columns) == list(SHOWN_COLUMNS)
