"""The claims table: rows keyed by a stable id, replaced per (figure, robot); the README's copy."""

import pandas as pd
import pytest

from lasa.base.errors import ConfigError
from lasa.evidence.claims import (
    CLAIM_COLUMNS,
    README_MARKERS,
    SHOWN_COLUMNS,
    SUMMARY_MARKERS,
    Claim,
    _row,
    claims_frame,
    numbers_of,
    render_summary,
    render_verdicts,
    sync_readme,
    update_claims,
)
from lasa.evidence.values import VALUES_NAME, read_values


def render(claims, **kwargs):
    """The verdict table of these claims, with their numbers (as claim_values.csv holds them)."""
    table = pd.DataFrame([_row(c) for c in claims], columns=list(CLAIM_COLUMNS)).astype(str)
    return render_verdicts(table, {(c.id, c.robot): numbers_of(c) for c in claims}, **kwargs)


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
    md = path.with_suffix(".md").read_text().split("# Every row of claims.csv\n\n", 1)[1]
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


def test_the_repository_readme_holds_the_committed_verdict_table_and_summary():
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    begin, end = README_MARKERS
    text = (root / "README.md").read_text()
    block = text.split(begin, 1)[1].split(end, 1)[0].strip()
    assert block == (root / "figures" / "verdicts.md").read_text().strip()
    summary = text.split(SUMMARY_MARKERS[0], 1)[1].split(SUMMARY_MARKERS[1], 1)[0].strip()
    assert summary == (root / "figures" / "summary.md").read_text().strip()
    # findings first: the generated summary (at most 10 lines) within the README's first 30 lines
    assert text.index(SUMMARY_MARKERS[1]) < len("\n".join(text.splitlines()[:30]))
    assert 3 <= len(summary.splitlines()) <= 10
    assert len(text.splitlines()) <= 200
    # the set-up named by the commands, the prerequisites before them
    commands = text.split("```bash", 1)[1].split("```", 1)[0]
    assert [line.split()[1] for line in commands.splitlines() if line.startswith("make ")] == [
        "figures",
        "test",
    ]
    assert "make setup" in commands and text.index("**Needs:**") < text.index("```bash") < text.index(begin)
    # every cell of the verdict table short enough to read
    for line in block.splitlines():
        if line.startswith("| ") and not line.startswith("| ---"):
            assert max(len(c.strip()) for c in line.strip("|").split("|")) <= 300, line
    table = pd.read_csv(root / "figures" / "claims.csv", dtype=str, keep_default_na=False)
    values = read_values(pd.read_csv(root / "figures" / VALUES_NAME, dtype=str, keep_default_na=False))
    assert (root / "figures" / "verdicts.md").read_text() == render_verdicts(table, values)  # generated
    assert (root / "figures" / "summary.md").read_text() == render_summary(table, values)


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
    md = render(rows)
    lines = md.strip().splitlines()
    # the count line with the fragile rows, a blank line, header, rule, one claim (claims without
    # rows are left out)
    assert len(lines) == 5
    assert lines[0].startswith(
        "Of 2 paper claims × robot, the effect: 0 reproduced, 0 partly, 1 not reproduced, 1 undecided, "
        "0 not testable. Of the 0 numbers the paper states, on the robot it states them for (the Panda), "
        "the number: 0 in, 0 out, 0 undecided. Fragile (an interval ends within a fifth of its width"
    )
    cells = [c.strip() for c in lines[4].strip("|").split("|")]
    assert cells[1] == "time ratio 1.45 and 1.30"
    assert cells[2].startswith("**effect not reproduced**")
    assert "N = 150" in cells[2] and "settled" in cells[2]
    assert cells[3].startswith("effect undecided") and "settled" not in cells[3]
    # two of the three readings flip it (grasp_set on planar5, the compound one on the Panda)
    assert cells[4] == "2 of 3 ([list](figures/claims.md#sim1time_ratio))"
    assert "(notebooks/04_fixed_expertise.ipynb#what-it-shows-against-the-paper)" in cells[5]
    # claims.md lists them, each with its words
    from lasa.evidence.claims import render_flips

    listed = render_flips(table)
    assert "### sim1.time_ratio" in listed and "2 of 3 readings flip it" in listed
    assert "- `grasp_set`: planar5: effect partly; number n/a" in listed
    assert "- `hindsight+one_step`: panda: effect not reproduced; number n/a" in listed


def _study(cid, reproduced, value, low, high, n, **facts):
    """A study row with its effect and facts, as lasa.experiments.study.claims writes them."""
    base = claim(cid.split("@", 1)[0].split(".", 1)[1], figure="study", robot="panda", verdict="undecided")
    testable = reproduced != "not testable"
    known = {"testable": float(testable), "censored": 0.0} | facts
    return Claim(
        **{
            **base.__dict__,
            "id": cid,
            "reproduced": reproduced,
            "settled": reproduced not in ("undecided", "not testable"),
            "n_users": n,
            "values": {"effect": value},
            "intervals": {"effect": (low, high)},
            "level": 0.95,
            "facts": known,
        }
    )


def test_a_claim_that_is_not_testable_is_rendered_with_its_reason_from_its_numbers(tmp_path):
    from lasa.evidence.claims import VERDICTS
    from lasa.evidence.decision import NOT_TESTABLE

    assert NOT_TESTABLE == "not testable" and NOT_TESTABLE in VERDICTS
    with pytest.raises(ConfigError, match="never settled"):
        Claim(**{**claim("h3", figure="study").__dict__, "reproduced": NOT_TESTABLE, "settled": True})
    nan = float("nan")
    done = {"completion.R": 1.0, "completion.R+SA": 1.0, "completion.LA": 0.0, "completion.LA+SA": 0.0}
    guard = _study("study.h3", NOT_TESTABLE, nan, nan, nan, 10, **done)
    h1 = _study("study.h1", NOT_TESTABLE, nan, nan, nan, 10, difference=-2.04, F=36.4, df1=1, df2=9, p=1e-4)
    h1 = Claim(**{**h1.__dict__, "facts": {**h1.facts, **done, "completion.LA": 0.2}})
    table = update_claims(tmp_path / "claims.csv", [guard, h1]).set_index("id")
    assert table.loc["study.h3", "reproduced"] == NOT_TESTABLE and table.loc["study.h3", "settled"] == "no"
    assert table.loc["study.h3", "ci_low"] == "" and "nan" not in (tmp_path / "claims.md").read_text()
    values = pd.read_csv(tmp_path / VALUES_NAME, dtype=str, keep_default_na=False)
    assert set(values.quantity[values.id == "study.h1"]) >= {
        "effect",
        "difference",
        "F",
        "p",
        "completion.LA",
    }
    assert (
        values.loc[(values.id == "study.h1") & (values.quantity == "completion.LA"), "value"].item() == "0.2"
    )
    md = render_verdicts(table.reset_index().astype(str), read_values(values.astype(str)))
    cells = {
        line.split("|")[1].strip(): line.split("|")[4].strip() for line in md.splitlines()[4:] if "|" in line
    }
    h3 = next(v for k, v in cells.items() if k.startswith("H3: LA+SA"))
    assert (
        h3 == "effect not testable with simulated participants (completion: LA 0%, LA+SA 0%), N = 10; "
        "measured, not judged: no contrast (a compared condition finishes too few episodes)"
    )
    h1_cell = next(v for k, v in cells.items() if k.startswith("H1"))
    assert h1_cell == (
        "effect not testable with simulated participants (completion: LA 20%, LA+SA 0%), N = 10; "
        "measured, not judged: SA lowers Goal Error by -2.04 m s, F(1,9) = 36.4, p < .001"
    )


def _time_ratio(robot, low75, high75, low1000, high1000, reading="undecided"):
    base = claim("time_ratio", robot=robot, verdict=reading)
    intervals = {"ratio_75": (low75, high75), "ratio_1000": (low1000, high1000)}
    values = {k: (lo + hi) / 2 for k, (lo, hi) in intervals.items()}
    return Claim(**{**base.__dict__, "n_users": 150, "intervals": intervals, "values": values})


def test_each_paper_number_gets_its_own_word_beside_the_effect_on_the_panda():
    # the paper: 1.45 at beta = 75 and 1.30 at beta = 1000, each +- 0.15 by the rule, for the Panda
    one = _time_ratio("panda", 0.844, 1.1, 1.34, 1.39)
    row = _row(one)
    assert row["effect"] == "undecided"  # the rule's reading: ratio_75's interval straddles 1
    assert row["number"] == "out; in"  # [0.844, 1.1] misses [1.30, 1.60]; [1.34, 1.39] inside [1.15, 1.45]
    assert row["reproduced"] == "not reproduced"  # both in one word: a number is out
    assert row["paper_in_ci"] == "no; yes"  # 1.30 +- 0.15 meets [1.34, 1.39]
    assert row["direction"] == "no"  # ratio_75's interval straddles 1
    assert row["paper_numbers"] == (
        "1.45 ± 0.15 (beta = 75): out, 0.972 [0.844, 1.1]; 1.3 ± 0.15 (beta = 1000): in, 1.36 [1.34, 1.39]"
    )
    assert str(row["note"]).startswith("Effect undecided; 1.45 out, 1.3 in. ")  # the note's words: the row's
    # planar5: the paper states no number for it; the effect is judged, the numbers are not compared
    other = _row(_time_ratio("planar5", 1.35, 1.55, 1.2, 1.5, reading="yes"))
    assert other["effect"] == "reproduced" and other["number"] == "n/a" and other["paper_numbers"] == ""
    md = render([one, _time_ratio("planar5", 1.35, 1.55, 1.2, 1.5, reading="yes")])
    assert "effect undecided; 1.45 out: 0.972 [0.844, 1.1]; 1.3 in: 1.36 [1.34, 1.39], N = 150" in md
    assert "**effect reproduced**; ratio_75 1.45 [1.35, 1.55]; no paper number for planar5, N = 150" in md
    assert (
        "Of the 2 numbers the paper states, on the robot it states them for (the Panda), the number: "
        "1 in, 1 out, 0 undecided." in md
    )
    assert "nan" not in md


def test_a_number_reads_in_only_when_its_interval_is_narrow_enough():
    from lasa.evidence.decision import PaperNumber

    r2 = PaperNumber("r2", 0.98, 0.0, "R^2 = 0.98", max_width=0.04)
    assert r2.word((0.975, 1.0)) == "in"  # holds 0.98, 0.025 wide
    assert r2.word((0.54, 0.983)) == "undecided"  # holds 0.98, but 0.443 wide: cannot tell
    assert r2.word((0.5, 0.9)) == "out"
    ratio = PaperNumber("r", 1.45, 0.15, "beta = 75")
    assert ratio.width_limit == pytest.approx(0.3)  # the tolerance band's width
    assert ratio.word((1.35, 1.55)) == "in" and ratio.word((1.2, 1.55)) == "undecided"
    with pytest.raises(ConfigError, match="max_width"):
        PaperNumber("slope", 0.11, 0.0, "y = 0.11x")  # no tolerance and no width: nothing could read in


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
    base = claim("grasp_linear", figure="sim4", robot="panda")
    ours = Claim(**{**base.__dict__, "reproduced": "undecided", "intervals": {"slope": (0.05, 0.15)}})
    assert _row(ours)["paper_in_ci"] == "yes; n/a"  # 0.11 in [0.05, 0.15]; R^2's interval unknown
    assert _row(ours)["number"] == "in; n/a"  # no tolerance: in when our interval holds 0.11, 0.1 wide
    md = render([trapped, ours])
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

    for name in ("claims.csv", VALUES_NAME):
        shutil.copy(Path(__file__).resolve().parents[1] / "figures" / name, tmp_path / name)
    subprocess.run([sys.executable, "-m", "lasa.evidence.claims", str(tmp_path / "claims.csv")], check=True)
    committed = Path(__file__).resolve().parents[1] / "figures" / "verdicts.md"
    assert (tmp_path / "verdicts.md").read_text() == committed.read_text()
    assert (tmp_path / "summary.md").read_text() == committed.with_name("summary.md").read_text()


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


def test_the_summary_names_each_claim_under_its_word_with_the_reason():
    def row(cid, robot, verdict, figure="sim1", measured="m"):
        base = claim(cid.split(".", 1)[1], figure=figure, robot=robot, verdict=verdict)
        return Claim(**{**base.__dict__, "measured": measured})

    rows = [
        row("sim1.final_error", "planar5", "no"),
        row("sim1.final_error", "panda", "no"),
        row("sim2.entropy_escapes", "planar5", "yes", "sim2"),
        row("sim2.entropy_escapes", "panda", "undecided", "sim2"),
        row("study.likert", "panda", "not testable", "study", "not testable (no questionnaire)"),
    ]
    table = pd.DataFrame([_row(c) for c in rows], columns=list(CLAIM_COLUMNS)).astype(str)
    lines = render_summary(table, {}).splitlines()
    assert len(lines) <= 10 and lines[0].startswith("**In short.**")
    said = {line.split("**")[1]: line for line in lines[1:]}
    assert said["Reproduced"] == "- **Reproduced** (1): entropy lets users change their mind (sim2; planar5)."
    assert said["Not reproduced"] == (
        "- **Not reproduced** (1): SA lowers the final error (sim1; both robots): "
        "Eq. M2 pulls towards the mid-preference grasp."
    )
    assert said["Undecided"].startswith(
        "- **Undecided** (1): entropy lets users change their mind (sim2; the Panda)"
    )
    assert (
        said["Not testable"]
        == "- **Not testable** (1): H3's Likert ratings (study; the Panda): no questionnaire."
    )
    assert said["The paper's numbers"].startswith("- **The paper's numbers** (0, stated for the Panda)")


def test_the_summary_gives_a_claims_finding_from_its_numbers_and_a_studys_completion():
    from lasa.evidence.values import Number

    gap = Claim(**{**claim("gap_narrows", robot="panda", verdict="no").__dict__, "settled": True})
    h1 = Claim(
        **{
            **claim("h1", figure="study", robot="panda", verdict="not testable").__dict__,
            "measured": "not testable (completion: LA 20%); ...",
        }
    )
    table = pd.DataFrame([_row(gap), _row(h1)], columns=list(CLAIM_COLUMNS)).astype(str)
    iv = {"time_gap_75": (-0.1, 0.1), "time_narrowing": (-0.5, -0.3)}
    iv |= {"error_gap_75": (-0.03, -0.01), "error_narrowing": (-0.03, -0.01)}
    values = {("sim1.gap_narrows", "panda"): {k: Number(sum(v) / 2, *v) for k, v in iv.items()}}
    done = {f"completion.{c}": Number(v) for c, v in (("R", 1.0), ("LA", 0.2), ("LA+SA", 1.0))}
    values[("study.h1", "panda")] = done
    said = render_summary(table, values)
    assert (
        "the LA/LA+SA gap narrows with rationality (sim1; the Panda): the time gap at beta = 75 is unclear "
        "(the Panda), LA+SA is worse in error at beta = 75 (the Panda)."
    ) in said
    assert "H1, SA keeps the goal (study; the Panda): completion LA 20% within the horizon." in said
