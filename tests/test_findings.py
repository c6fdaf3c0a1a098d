"""The notebooks' generated result sentences state their data's numbers, and flip with the data.

Each table here is built by hand; each sentence is checked for the numbers and words the table
decides (issue 47: no result number is typed in a notebook's Markdown).
"""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import lasa  # noqa: F401  (pins the kernels before numpy loads)
from lasa.base.errors import ConfigError
from lasa.evidence import latent_property
from lasa.evidence.claims import Claim
from lasa.experiments import (
    eating_task,
    entropy_ablation,
    latent_map,
    sim1,
    sim2,
    sim3,
)
from lasa.experiments.study import analysis as study_analysis
from lasa.experiments.study import caps as study_caps

ROOT = Path(__file__).resolve().parents[1]
BUDGET = {"11_eating_study.ipynb": 2000}  # words of Markdown per notebook; the rest 1,200 (issue 47)


def _cap_rows(cap: str, order: int, h1: float, la: float, meets: bool) -> list[dict[str, object]]:
    base = dict(robot="panda", cap=cap, order=order, decoder=f"d{cap}", n=10)
    done = [
        dict(base, kind="completion", item=c, value=v) for c, v in (("R", 1.0), ("LA", la), ("LA+SA", 0.85))
    ]
    claims = [
        dict(base, kind="claim", item="h1", value=h1, low=h1 - 0.5, high=h1 + 0.5, word="not testable"),
        dict(base, kind="claim", item="h3", value=55.3, low=25.6, high=88.8, word="not reproduced"),
    ]
    word = "meets the rule" if meets else "misses the rule"
    return [*done, *claims, dict(base, kind="property", item="goals with both halves", value=4, word=word)]


def _sweep() -> pd.DataFrame:
    rows = _cap_rows("0.9", 0, -1.0, 0.2, False) + _cap_rows("0.99", 1, -2.0, 0.15, True)
    return pd.DataFrame(rows + _cap_rows("none", 2, 0.24, 1.0, True), columns=list(study_caps.COLUMNS))


def test_cap_findings_state_the_sweeps_numbers() -> None:
    text = study_caps.findings(_sweep(), "0.99")
    assert "**At the study's cap (0.99)**, with `d0.99` and 10 participants" in text
    assert "R 100%, LA 15%, LA+SA 85%" in text
    assert "H1 (SA − no SA Goal Error) −2.00 m s [−2.50, −1.50]: *not testable*" in text
    assert "**Without the cap**" in text and "+55.3 s [+25.6, +88.8]: *not reproduced*" in text
    assert "SA lowers Goal Error at cap 0.9 and 0.99; SA raises it at cap none" in text
    assert "LA finishes 20% at 0.9, 15% at 0.99, 100% at none" in text
    assert "meets the property rule at every cap but 0.9." in text


def test_cap_findings_flip_with_the_data() -> None:
    sweep = _sweep()
    sweep.loc[(sweep["item"] == "h1"), "value"] *= -1
    sweep.loc[sweep.kind == "property", "word"] = "meets the rule"
    text = study_caps.across_caps(sweep)
    assert "SA lowers Goal Error at cap none; SA raises it at cap 0.9 and 0.99" in text
    assert text.endswith("meets the property rule at every cap.")
    with pytest.raises(ValueError, match="no cap '0.5'"):
        study_caps.cap_sentence(sweep, "0.5")


def test_completion_sentence_names_the_conditions_below_the_bar() -> None:
    done = pd.DataFrame(
        {
            "model": "planning",
            "decoder": ["none", "dec", "none", "dec", "other"],
            "assistance": ["none", "none", "hindsight", "hindsight", "hindsight"],
            "condition": ["R", "LA", "R+SA", "LA+SA", "LA+SA"],
            "episodes": 80,
            "finished": [1.0, 0.2625, 1.0, 0.975, 0.1],
        }
    )
    text = study_analysis.completion_sentence(done, "planning", "dec", "hindsight")
    assert "80 episodes per condition: R 100%, LA 26.2%, R+SA 100%, LA+SA 97.5%; LA below the 95%" in text
    done.loc[1, "finished"] = 0.96
    assert "every condition at or above the 95%" in study_analysis.completion_sentence(
        done, "planning", "dec", "hindsight"
    )


def test_switch_sentence_against_herlant() -> None:
    shares = pd.DataFrame(
        {
            "model": "planning",
            "participants_of": "cohort",
            "condition": ["R", "R+SA", "R+SA"],
            "assistance": ["none", "hindsight", "grasp_set"],
            "switch_share": [0.132, 0.127, 0.5],
            "ci_low": [0.126, 0.12, 0.4],
            "ci_high": [0.137, 0.133, 0.6],
        }
    )
    text = study_analysis.switch_sentence(shares, "planning", "hindsight")
    assert "13.2% [12.6%, 13.7%] (R) and 12.7% [12%, 13.3%] (R+SA)" in text and ": below Herlant" in text
    assert "50%" not in text  # another member's share is not this one's
    other = study_analysis.switch_sentence(shares, "planning", "grasp_set")
    assert "50% [40%, 60%] (R+SA)" in other and ": partly below and partly above Herlant" in other


def _prop(decoder: str, stay: list[float], leave: float = 15.0) -> pd.DataFrame:
    goals = ["rice", "middle", "icing", "plate"]
    stays = [s >= 0.5 for s in stay]
    return pd.DataFrame(
        dict(
            source="eating",
            robot="panda",
            task="eating",
            decoder=decoder,
            goal=goals,
            n_inputs=64,
            stay_share=stay,
            theta_range=0.9,
            stroke_range=0.9,
            from_home=0.3,
            all_reached=True,
            leave_min=leave,
            leave_la_min=leave,
            stay_holds=stays,
            leave_holds=True,
            has_property=stays,
        )  # fmt: skip
    )


def test_property_sentence_names_who_meets_the_rule() -> None:
    prop = pd.concat([_prop("a", [0.6, 0.55, 0.5, 0.7], 17), _prop("b", [0.3, 0.42, 0.2, 0.1])])
    text = eating_task.property_sentence(prop)
    assert "1 of 2 readings meet the rule: `a`; the rule ranks `a` first" in text
    assert "at least 50% of the 64 inputs stay at every goal, and at least 17 reach" in text
    assert "`b` misses the stay half at every goal (at most 42% of the inputs stay at a goal)" in text
    none = eating_task.property_sentence(_prop("b", [0.3, 0.42, 0.2, 0.1]))
    assert none.startswith("None of the 1 readings meets the rule; the best reading is `b`.")


def test_caps_sentence_names_the_missing_goal() -> None:
    caps = pd.concat([_prop("c0.9", [0.56, 0.5, 0.5, 0.48]), _prop("c0.95", [0.6, 0.55, 0.56, 0.53])])
    text = eating_task.caps_sentence(caps)
    assert "the rule is met by `c0.95`; `c0.9` misses the stay half at the plate." in text


def _claim(cid: str, values: dict[str, float], intervals: dict[str, tuple[float, float]], word: str) -> Claim:
    return Claim(id=cid, claim="", figure="sim1", paper="", measured="", reproduced=word, note="",
                 robot="panda", n_users=150, values=values, intervals=intervals)  # fmt: skip


def test_sim1_findings_state_the_ratios_and_gaps() -> None:
    ratio = _claim("sim1.time_ratio", {"ratio_75": 1.02, "ratio_1000": 1.31},
                   {"ratio_75": (0.95, 1.1), "ratio_1000": (1.2, 1.5)}, "undecided")  # fmt: skip
    gap = _claim("sim1.gap_narrows", {"error_gap_75": -0.021, "time_gap_75": 0.02},
                 {"error_gap_75": (-0.03, -0.012), "time_gap_75": (-0.05, 0.1)}, "no")  # fmt: skip
    text = sim1.findings([ratio, gap], "panda")
    assert "(panda, 150 users per point)" in text
    assert "1.02 [0.95, 1.10] at β = 75 (its interval contains 1)" in text
    assert "1.31 [1.20, 1.50] at β = 1000 (LA is slower than LA+SA)" in text
    assert "the claim reads *undecided*" in text
    assert "−0.021 [−0.030, −0.012] (LA+SA ends farther from s*)" in text
    assert "0.02 [−0.05, 0.10] (its interval contains 0)" in text
    flipped = _claim("sim1.gap_narrows", {"error_gap_75": 0.021, "time_gap_75": 0.2},
                     {"error_gap_75": (0.01, 0.03), "time_gap_75": (0.1, 0.3)}, "yes")  # fmt: skip
    text = sim1.findings([ratio, flipped], "panda")
    assert "(LA+SA ends closer to s*)" in text and "(LA+SA is faster)" in text
    assert "the claim reads *yes*" in text


def _words(notebook: Path) -> int:
    cells = json.loads(notebook.read_text())["cells"]
    return sum(len(re.findall(r"\S+", "".join(c["source"]))) for c in cells if c["cell_type"] == "markdown")


@pytest.mark.parametrize("notebook", sorted((ROOT / "notebooks").glob("*.ipynb")), ids=lambda p: p.name)
def test_notebook_prose_within_budget(notebook: Path) -> None:
    """Each notebook reads as a short paper section: its Markdown within ~1,200 words (11: ~2,000)."""
    budget = BUDGET.get(notebook.name, 1200)
    assert _words(notebook) <= budget, f"{notebook.name}: {_words(notebook)} words of Markdown > {budget}"


SUCCEED = {
    "LA": {0: 4, 20: 0, 100: 2},
    "LA+SA": {0: 4, 20: 4, 100: 1},
    "LA+SA+Entropy": {0: 4, 20: 4, 100: 4},
}


def _sim2_head(succeed: dict[str, dict[int, int]] = SUCCEED) -> pd.DataFrame:
    """Four users per method and N; user u succeeds when u < the count; errors and confidences by hand."""
    rows = []
    for method, counts in succeed.items():
        for n, k in counts.items():
            for u in range(4):
                rows.append(
                    dict(
                        robot="planar5",
                        method=method,
                        change_step=n,
                        seed=u,
                        success=u < k,
                        final_error=0.05 if u < k else 0.3 + 0.1 * u,
                        confidence=0.999998,
                        assistance="none" if method == "LA" else "point",
                        look=0,
                    )  # fmt: skip
                )
    head = pd.DataFrame(rows)
    sa_late = (head.method == "LA+SA") & (head.change_step == 100)
    head.loc[sa_late & (head.seed == 3), "confidence"] = 0.2
    la_20 = (head.method == "LA") & (head.change_step == 20)
    head.loc[la_20, "confidence"] = [0.0001, 0.0002, 0.0003, 0.00045]
    return head


def _sim2_after(head: pd.DataFrame, reach: float = 60.0) -> pd.DataFrame:
    """sim2.after_the_change's columns on _sim2_head's rows (horizon 170)."""
    after = head.assign(steps_left=170 - head.change_step, away_at_n=0.1, belief_at_n=0.001, turn=5.0,
                        reach=np.where(head.success, reach, np.nan), still=False,
                        wrong_error=0.9)  # fmt: skip
    after.loc[after.method == "LA+SA+Entropy", "turn"] = 8.0
    sa_late = (after.method == "LA+SA") & (after.change_step == 100)
    after.loc[sa_late, "turn"] = [10.0, 30.0, 40.0, np.nan]
    after.loc[sa_late, "wrong_error"] = [0.9, 0.5, 0.05, 0.6]
    after.loc[sa_late, "still"] = [False, False, True, False]
    after.loc[(after.method == "LA") & (after.change_step == 20), "still"] = True
    return after


def _trapped(drop: float, low: float, high: float) -> Claim:
    return Claim(id="sim2.sa_trapped", claim="", figure="sim2", paper="", measured="", reproduced="yes",
                 note="", robot="planar5", n_users=60, values={"error_growth": 0.49, "confidence_drop": drop},
                 intervals={"error_growth": (0.4, 0.58), "confidence_drop": (low, high)})  # fmt: skip


def test_sim2_claim_sentence_counts_the_parts_that_hold() -> None:
    text = sim2.claim_sentence(_trapped(0.18, 0.1, 0.26), (0, 120))
    assert "(planar5, 60 users per point).** From N = 0 to N = 120" in text
    assert "error grows by 0.49 [0.40, 0.58], and its mean confidence" in text
    assert "in the true cup falls by 0.18 [0.10, 0.26]: both parts hold" in text
    assert "both parts hold; the claim reads *yes*" in text
    text = sim2.claim_sentence(_trapped(-0.05, -0.1, 0.02), (0, 120))
    assert "the true cup rises by 0.05 [−0.02, 0.10] (its interval contains 0): one part holds" in text
    with pytest.raises(ConfigError, match="reads sim2.sa_trapped"):
        sim2.claim_sentence(_claim("sim1.time_ratio", {}, {}, "yes"), (0, 120))


def test_sim2_success_sentence_says_which_way_each_share_moves() -> None:
    text = sim2.success_sentence(_sim2_head())
    assert text.startswith("- **Success at N = 0, 20, 100.** ")
    assert "LA 100%, 0%, 50% (falls from 100% to 50%)" in text
    assert "LA+SA 100%, 100%, 25% (falls from 100% to 25%)" in text
    assert "LA+SA+Entropy 100%, 100%, 100% (stays at 100%)" in text
    rising = {**SUCCEED, "LA": {0: 1, 20: 2, 100: 3}}
    assert "LA 25%, 50%, 75% (rises from 25% to 75%)" in sim2.success_sentence(_sim2_head(rising))


def test_sim2_belief_sentence_follows_or_stays() -> None:
    head = _sim2_head()
    text = sim2.belief_sentence(head, _sim2_after(head), 0.1)
    assert (
        "**LA+SA's belief follows the user.** Its median end confidence in the true cup is at least 0.999998"
        in text
    )
    assert "at N = 100 the mean end confidence is 0.8, median 0.999998" in text
    assert "(25% of its users at N = 100 end with b(g*) below one half)" in text
    assert "passes 0.5 in 5 steps under LA, in 35 steps under LA+SA, in 8 steps under LA+SA+Entropy" in text
    assert "reach the true cup a median 60 steps after N (over every N), fewer than the 70 left" in text
    assert "Its 3 unsuccessful users there (of 4) end at final errors 0.40 to 0.60 (median 0.50)" in text
    assert "1 of them end within 0.1 of the wrong cup's grasp, and 33% stand still." in text
    assert "more than the 70 left" in sim2.belief_sentence(head, _sim2_after(head, reach=90.0), 0.1)
    stays = head.copy()
    stays.loc[(stays.method == "LA+SA") & (stays.change_step > 0), "confidence"] = 1e-5
    text = sim2.belief_sentence(stays, _sim2_after(stays), 0.1)
    assert "**LA+SA's belief stays with the wrong cup.** From N = 20 on its median end confidence" in text
    assert (
        "is at most 1.0e-05;" in text
        and "(100% of its users at N = 100 end with b(g*) below one half)" in text
    )


def test_sim2_dip_sentence_finds_the_lowest_success() -> None:
    head = _sim2_head()
    text = sim2.dip_sentence(head, _sim2_after(head))
    assert "**LA's success is lowest at N = 20, not at the largest N:** 0 of 4 users succeed" in text
    assert "succeed, with 150 steps left. The unsuccessful end at" in text
    assert (
        "final errors 0.30 to 0.60 (mean 0.45) with an end confidence in the true cup of at most 0.00045"
        in text
    )
    assert "a median 0.10 from home and b(g*) = 0.001; 100% of the unsuccessful stand still" in text
    falling = _sim2_head({**SUCCEED, "LA": {0: 4, 20: 3, 100: 2}})
    text = sim2.dip_sentence(falling, _sim2_after(falling))
    assert "lowest at the largest N:** 2 of 4 users succeed, with 70 steps left" in text


def test_sim2_findings_reads_the_robots_headline_row() -> None:
    head = _sim2_head()
    other = dataclasses.replace(_trapped(0.18, 0.1, 0.26), assistance="grasp_set", reproduced="no")
    text = sim2.findings([other, _trapped(0.18, 0.1, 0.26)], head, _sim2_after(head), 0.1)
    assert text.count("\n- **") == 3 and "the claim reads *yes*" in text and "From N = 0 to N = 100" in text
    with pytest.raises(ConfigError, match="one sim2.sa_trapped row for planar5 under 'point', got 0"):
        sim2.findings([other], head, _sim2_after(head), 0.1)


def _cup_rows(stay: list[float], leave: list[float], home: list[float]) -> pd.DataFrame:
    """A latent_property.summary of one cup decoder, two cups, 64 inputs each."""
    table = pd.DataFrame(
        dict(
            source="cups-panda",
            robot="panda",
            task="cups",
            decoder="LA",
            goal=["left", "right"],
            n_inputs=64,
            stay_share=stay,
            theta_min=0.0,
            theta_max=[1.0, 0.4],
            theta_range=[1.0, 0.4],
            stroke_range=0.0,
            from_home=home,
            all_reached=min(home) > 0,
            leave_min=leave,
            leave_la_min=leave,
        )
    )
    table["stay_holds"] = latent_property.stay_holds(table)
    table["leave_holds"] = table.leave_min >= latent_property.LEAVE_COUNT
    return table.assign(has_property=latent_property.has_property(table))


def test_property_findings_say_which_half_holds_at_each_cup() -> None:
    text = latent_map.property_findings(_cup_rows([1.0, 0.75], [0.0, 9.0], [31 / 64, 28 / 64]))
    assert (
        "**At the left cup** (confident belief): 64 of 64 stick deflections stay, reaching θ from 0.00"
        in text
    )
    assert "to 1.00, so the stay half holds; from its mid-preference grasp 0 reach another cup" in text
    assert "(the leave half asks for 7 of 64), so it does not hold." in text
    assert (
        "**At the right cup** (confident belief): 48 of 64" in text
        and "to 0.40, so the stay half does not" in text
    )
    assert "9 reach another cup under LA+SA (the leave half asks for 7 of 64), so it holds." in text
    assert (
        "59 of 64 inputs reach a cup (31 at the left cup, 28 at the right cup); every cup is reached." in text
    )
    assert "at 0 of 2 cups, so it does not meet the rule." in text
    good = latent_map.property_findings(_cup_rows([1.0, 0.75], [8.0, 9.0], [0.5, 0.0]))
    assert "not every cup is reached" in good and "at 0 of 2 cups" in good
    full = _cup_rows([1.0, 0.75], [8.0, 9.0], [0.5, 0.5]).assign(theta_range=1.0, theta_max=1.0)
    full = full.assign(stay_holds=True).pipe(lambda t: t.assign(has_property=latent_property.has_property(t)))
    assert "at 2 of 2 cups, so it meets the rule." in latent_map.property_findings(full)
    with pytest.raises(ConfigError, match="one decoder's rows"):
        latent_map.property_findings(full.assign(decoder=["a", "b"]))


def _lambdas(recon: float) -> pd.DataFrame:
    return pd.DataFrame(
        {
            "lambda": [0.0, 0.1, 1.0],
            "entropy_confident": [0.012, 0.676, 0.691],
            "recon_error": [0.00131, recon, 0.00178],
            "val_error": [0.0045, 0.00398, 0.0045],
        }
    )


def test_entropy_findings_compare_the_chosen_lambda_with_the_control() -> None:
    text = entropy_ablation.findings(_lambdas(0.00119), 0.1, 2)
    assert (
        "**The rule chooses λ = 0.1.** At confident contexts its mean entropy of p is 0.676 nats, 98%" in text
    )
    assert "the control's is 0.012 (2%)" in text
    assert "reconstruction error is 0.00119 (rad/s)², 0.91× the control's 0.00131 (below it)" in text
    assert "held out, 0.00398 against 0.0045." in text
    assert "1.15× the control's 0.00131 (above it)" in entropy_ablation.findings(_lambdas(0.0015), 0.1, 2)
    with pytest.raises(ConfigError, match="must hold lambda = 0 and 0.3"):
        entropy_ablation.findings(_lambdas(0.0015), 0.3, 2)


def _learners(gain_slow: float, low: float, high: float) -> tuple[Claim, pd.DataFrame]:
    """A sim3 claims row and its episodes: two users per learner and method, errors by hand."""
    fast = {"LA": 0.5, "LA+SA": 0.4, "LA+SA+Entropy": 0.3}
    slow = {"LA": 0.6, "LA+SA": 0.5, "LA+SA+Entropy": 0.5 - gain_slow}
    errors = {**{("fast", m): e for m, e in fast.items()}, **{("slow", m): e for m, e in slow.items()}}
    head = pd.DataFrame(
        [
            dict(
                robot="panda",
                learner=learner,
                method=method,
                seed=u,
                error=error + (0.01 if u else -0.01),
                assistance="none" if method == "LA" else "point",
            )
            for (learner, method), error in errors.items()
            for u in range(2)
        ]
    )
    claim = Claim(id="sim3.entropy_learners", claim="", figure="sim3", paper="", measured="",
                  reproduced="partly", note="", robot="panda", n_users=60,
                  values={"gain_fast": 0.1, "gain_slow": gain_slow},
                  intervals={"gain_fast": (0.05, 0.15), "gain_slow": (low, high)})  # fmt: skip
    return claim, head


def test_sim3_findings_state_each_learners_gain() -> None:
    claim, head = _learners(-0.02, -0.05, 0.01)
    other = dataclasses.replace(claim, assistance="hindsight", reproduced="yes")
    text = sim3.findings([other, claim], head)
    assert (
        "**The fast learner.** Mean error over the episode: LA 0.500, LA+SA 0.400, LA+SA+Entropy 0.300."
        in text
    )
    assert "The entropy term lowers LA+SA's (gain LA+SA − LA+SA+Entropy +0.100 [+0.050, +0.150])." in text
    assert "LA+SA+Entropy 0.520. The entropy term raises LA+SA's" in text
    assert "(gain LA+SA − LA+SA+Entropy −0.020 [−0.050, +0.010]; its interval contains 0)." in text
    assert (
        "**The claim (panda, 60 users per point)** reads *partly*: the term lowers the mean error for the"
        in text
    )
    assert "for the fast learner only." in text
    claim, head = _learners(0.04, 0.01, 0.07)
    assert "lowers the mean error for both learners." in sim3.findings([claim], head)
    with pytest.raises(ConfigError, match="one sim3.entropy_learners row for panda under 'point', got 0"):
        sim3.findings([other], head)
