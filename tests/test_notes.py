"""Every row of the committed claims table: its note's words and numbers are the row's own.

A note is generated from its row (lasa.evidence.claims._row, lasa.evidence.verdicts.assess,
sequential and the study's rows); these checks read the note back and hold it against the row's
columns, so a sentence that contradicts its own row fails here.
"""

import math
import re
from pathlib import Path

import pandas as pd
import pytest

from lasa.base.config import ASSISTANCE
from lasa.evidence.claims import paper_numbers_of, words_text
from lasa.evidence.decision import NOT_TESTABLE, NUMBER_WORDS, UNDECIDED, WORDS
from lasa.evidence.values import VALUES_NAME, read_values

ROOT = Path(__file__).resolve().parents[1]
TABLE = pd.read_csv(ROOT / "figures" / "claims.csv", dtype=str, keep_default_na=False)
ROWS = {(r.id, r.robot): r for r in TABLE.itertuples(index=False)}
VALUES = read_values(pd.read_csv(ROOT / "figures" / VALUES_NAME, dtype=str, keep_default_na=False))
# how lasa.evidence.verdicts.assess states a number in a note: "<name> = <value> [<low>, <high>]"
_STATED = re.compile(r"(\w+) = (\S+) \[(\S+), ([^\]]+)\]")
_READINGS = re.compile(r"(?:Readings|Members) with other words(?: \(at \d+ users\))?: (.*?)\. (?=[A-Z0-9])")
_READING = re.compile(r"([\w+]+) \((effect [^()]*)\)")


def _close(text: str, number: str) -> bool:
    """Whether ``text`` (a note's ``.3g``) and ``number`` (the column's ``.4g``) are one number."""
    a, b = float(text), float(number)
    return math.isclose(a, b, rel_tol=5e-3, abs_tol=1e-9) or (a == b)


@pytest.fixture(params=sorted(ROWS), ids=lambda k: f"{k[0]}-{k[1]}")
def row(request):
    return ROWS[request.param]


def test_the_note_begins_with_the_rows_two_words(row):
    assert row.effect in WORDS
    assert all(w in NUMBER_WORDS for w in row.number.split("; "))
    said = words_text(row.effect, row.number, paper_numbers_of(row.id, row.robot))
    assert row.note.startswith(said[0].upper() + said[1:] + ". ")


def test_each_paper_numbers_word_is_the_number_columns(row):
    described = [part.split(": ", 1)[1].split(", ", 1)[0] for part in row.paper_numbers.split("; ") if part]
    assert "; ".join(described) == (row.number if described else "")


def test_the_intervals_the_note_states_are_the_rows_numbers(row):
    numbers = VALUES.get((row.id, row.robot), {})
    if row.figure == "study":
        effect = numbers.get("effect")
        if row.effect != NOT_TESTABLE:
            low, high = re.search(r"95% interval of the effect \[(\S+), (\S+)\]", row.note).groups()
            assert _close(low, row.ci_low) and _close(high, row.ci_high)
            assert _close(low, str(effect.low)) and _close(high, str(effect.high))
        return
    stated = _STATED.findall(row.note)
    assert [name for name, *_ in stated] == [k for k in numbers if numbers[k].interval is not None]
    for name, value, low, high in stated:  # the note's sentence and claim_values.csv: one number each
        n = numbers[name]
        assert _close(value, str(n.value)) and _close(low, str(n.low)) and _close(high, str(n.high))
    first = numbers[stated[0][0]]  # the rule's first quantity: the row's value
    assert _close(str(first.low), row.ci_low) and _close(str(first.high), row.ci_high)
    assert first.level == pytest.approx(0.9875) and first.n == int(row.n_users)


def test_settled_and_undecided_sentences_follow_the_effect(row):
    settled, open_ = (
        "The effect is settled at look" in row.note,
        "The effect is undecided at look" in row.note,
    )
    assert settled <= (row.settled == "yes") and open_ <= (row.effect == UNDECIDED)
    if row.figure != "study" and "@" not in row.id:  # a headline row says where its looks stopped
        assert settled != open_
    assert ("Undecided: " in row.note) == (row.effect == UNDECIDED)
    assert (row.settled == "yes") == (row.effect not in (UNDECIDED, NOT_TESTABLE))
    if row.effect == NOT_TESTABLE:
        assert f"{NOT_TESTABLE} (" in row.note or f"{NOT_TESTABLE} (" in row.measured


def test_the_readings_a_note_names_have_the_words_it_gives_them(row):
    found = _READINGS.search(row.note)
    if "@" in row.id:
        return
    named = dict(_READING.findall(found.group(1))) if found else {}
    for reading, words in named.items():
        other = ROWS[(f"{row.id}@{reading}", row.robot)]
        said = words_text(other.effect, other.number, paper_numbers_of(row.id, row.robot))
        # the study's rows state no paper number (n/a): their notes name the effect alone
        assert words == (said.split("; ")[0] if row.figure == "study" else said)
    # the sims compare the other shared-autonomy members, the study every other reading
    same = "Every reading gives" if row.figure == "study" else "Every other member gives"
    if same in row.note:
        assert not named
        own = words_text(row.effect, row.number, paper_numbers_of(row.id, row.robot))
        others = [o for (cid, rb), o in ROWS.items() if rb == row.robot and cid.startswith(row.id + "@")]
        if row.figure != "study":
            others = [o for o in others if o.id.split("@", 1)[1] in ASSISTANCE]
        assert all(words_text(o.effect, o.number, paper_numbers_of(row.id, row.robot)) == own for o in others)


def test_no_hand_written_reason_is_left_in_a_note():
    assert not TABLE.note.str.contains("Likely reason").any()
    assert not TABLE.note.str.contains("Joint-space distances").any()
