"""The hand-written results in the README agree with the committed figures.

The README's "What does not reproduce, and why" follows its generated table: prose written by
people from a paper-scale run. (The notebooks generate their result sentences from the run's data;
tests/test_findings.py checks the functions that write them.)
Each number or word there that a result decides is paired here with the committed CSV it comes
from: a re-run of ``make figures`` that moves it fails this test until the sentence is
rewritten. Each check first finds its sentence, so a rewritten sentence needs its check
rewritten too.
"""

from __future__ import annotations

import functools
from pathlib import Path

import pandas as pd

from lasa.evidence.findings import stated_numbers

ROOT = Path(__file__).resolve().parents[1]
FIGURES = ROOT / "figures"


@functools.cache
def _claims() -> pd.DataFrame:
    return pd.read_csv(FIGURES / "claims.csv", dtype=str).set_index(["id", "robot"])


def _row(cid: str, robot: str = "panda") -> pd.Series:
    return _claims().loc[(cid, robot)]


def _number(cid: str, robot: str, name: str) -> tuple[float, float, float]:
    """(value, low, high) of the number ``name`` a row's rule reads, as its note states it."""
    text = dict(stated_numbers(_row(cid, robot).note))[name]  # "<value> [<low>, <high>]"
    value, interval = text.split(" [")
    low, high = interval.rstrip("]").split(", ")
    return float(value), float(low), float(high)


def _done(cid: str) -> str:
    """A study row's completion list, ``R 100%, R+SA 100%, LA 96.2%, LA+SA 81.2%``."""
    return _row(cid).measured.split("completion: ")[-1]


def _shares(cid: str) -> dict[str, str]:
    """A study row's completion per condition, as its CSV writes it: ``{"R": "100%", ...}``."""
    return dict(part.rsplit(" ", 1) for part in _done(cid).split(", "))


def _readme_why() -> str:
    """The README's hand-written paragraph "What does not reproduce, and why"."""
    text = (ROOT / "README.md").read_text()
    start = text.index("**What does not reproduce, and why.**")
    return " ".join(text[start : text.index("\n\n", start)].split())


def test_readme_time_ratios() -> None:
    why = _readme_why()
    robots = ("planar5", "panda")
    at_75 = [_number("sim1.time_ratio", r, "ratio_75") for r in robots]
    at_1000 = [_number("sim1.time_ratio", r, "ratio_1000") for r in robots]
    assert all(low < 1 < high for _, low, high in at_75)  # "no clear time"
    assert f"(ratio {at_75[0][0]:.2f} on planar5, {at_75[1][0]:.2f} on the Panda, not 1.45)" in why
    assert all(low > 1 for _, low, _ in at_1000)
    more = [f"{100 * (v - 1):.0f}%" for v, _, _ in at_1000]
    assert f"take {more[0]} and {more[1]} more time without it, against the paper's 30%" in why


def test_readme_new_goals() -> None:
    why = _readme_why()
    robots = ("planar5", "panda")
    slopes = [_number("sim4.straight_line_linear", r, "slope") for r in robots]
    assert all(_row("sim4.straight_line_linear", r).number.startswith("out") for r in robots)
    assert all(low > 0 and not low <= 0.11 <= high for _, low, high in slopes)  # grows, but not at 0.11
    said = f"with\nslope {slopes[0][0]:.2g} (planar5) and {slopes[1][0]:.2g} (Panda), not 0.11"
    assert " ".join(said.split()) in why
    no_map = [_number("sim4.no_map_training_goal", r, "slope") for r in robots]
    assert all(low > 1 + 0.15 for _, low, _ in no_map)  # above y = x, beyond its tolerance
    assert all(_row("sim4.no_map_training_goal", r).number == "out" for r in robots)
    assert f"without the map it grows faster than y = x ({no_map[0][0]:.2g} and {no_map[1][0]:.2g})" in why
    assert "ends with the belief on the other training cup" in why


def test_readme_study() -> None:
    why = _readme_why()
    assert _shares("study.h3")["LA"] == "20%" and _row("study.h1").reproduced == "not testable"
    assert "LA participants finish 20% of their episodes in the 150 s horizon, so H1 is not testable" in why
    assert "F(1,9) = 36.4" in _row("study.h1").measured and "SA lowers Goal Error (F(1,9) = 36.4)" in why
    assert _row("study.h2").reproduced == "not reproduced" and "H2 and H3 are not reproduced" in why
    assert _row("study.h3").reproduced == "not reproduced" and "H2 and H3 are not reproduced" in why
    assert "SA - no SA = +0.24 m s" in _row("study.h1@uncapped").measured
    assert "without the cap (`@uncapped`) SA raises Goal Error instead" in why


def test_readme_final_error() -> None:
    assert "a myopic Eq. S1 user ends farther from their own grasp (sim1's final error" in _readme_why()
    for robot in ("planar5", "panda"):
        assert _row("sim1.final_error", robot).reproduced == "not reproduced"
        assert _row("sim1.entropy_sa", robot).reproduced == "not reproduced"
