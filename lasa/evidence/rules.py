"""The paper's decision rules (:class:`lasa.evidence.decision.Rule`) by claim id: each judges the claim's
shape; the study's (H1-H3) rest on significance tests (:mod:`lasa.evidence.hypotheses`). Each was written
before the results it judges were seen, except where :data:`AFTER_RESULTS` says."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from types import MappingProxyType

from lasa.base.errors import ConfigError
from lasa.evidence.decision import Direction, PaperNumber, Quantity, Rule

_SIGNIFICANCE = 0.05  # the paper's significance level, the study's tests' [-]
COMPLETION_BAR = 0.95  # H1 and H3 are judged only if every condition finishes this share of its episodes [-]
Decide = Callable[[Mapping[str, float]], str]


def _q(name: str, thresholds: tuple[float, ...], meaning: str) -> Quantity:
    return Quantity(name, tuple(float(t) for t in thresholds), meaning)


def _parts(*held: bool) -> str:
    """``yes`` if every part of a claim holds (in the paper's direction), ``partly`` if some, else ``no``."""
    return "yes" if all(held) else "partly" if any(held) else "no"


def _share(name: str, partly_above: float) -> Decide:
    """``yes`` if the share ``name`` is 1 (or more), ``partly`` if above ``partly_above``, else ``no``."""
    return lambda v: "yes" if v[name] >= 1.0 else "partly" if v[name] > partly_above else "no"


def _above(ref: float, *parts: tuple[str, ...]) -> Decide:
    """A part holds when each of its quantities is above ``ref`` (the paper's direction): :func:`_parts`."""
    return lambda v: _parts(*(all(v[name] > ref for name in part) for part in parts))


def _sim4_linear(v: Mapping[str, float]) -> str:
    # two parts: the error grows linearly with the distance; the map lowers it at every cup
    return _parts(v["slope"] > 0.0 and v["r2"] >= 0.9, v["share_below"] >= 1.0)


def _sa_lowers(v: Mapping[str, float]) -> str:
    """H1's tests: ``effect`` (SA - no SA) and ``p``, and per comparison given ``effect <a> - <b>`` and
    its Holm-corrected ``p <a> - <b>``. Yes if all are below 0 with p < .05; partly if the main effect
    is; no otherwise (without comparisons, as the paper's F(1,18), yes or no)."""
    main = v["effect"] < 0.0 and v["p"] < _SIGNIFICANCE
    pairs = [k.removeprefix("effect ") for k in v if k.startswith("effect ")]
    every = all(v[f"effect {k}"] < 0.0 and v[f"p {k}"] < _SIGNIFICANCE for k in pairs)
    return "yes" if main and every else "partly" if main else "no"


def _la_aligns(v: Mapping[str, float]) -> str:
    """H2's test: ``effect`` (scoop alignment LA+SA - R+SA) and its paired t-test's ``p``: yes if above
    0 with p < .05, partly if above 0, no otherwise (also when NaN: too few pairs)."""
    return _parts(v["effect"] > 0.0, v["effect"] > 0.0 and v["p"] < _SIGNIFICANCE)


def _la_sa_fastest(v: Mapping[str, float]) -> str:
    """H3's tests: yes if every ``high <measure> LA+SA - <b>`` (the upper end of a contrast's 95%
    bootstrap interval) is below 0; partly if ``mean LA+SA`` (restricted mean Total Time) is below
    every other ``mean <condition>``; no otherwise."""
    if all(x < 0.0 for k, x in v.items() if k.startswith("high ")):
        return "yes"
    others = [x for k, x in v.items() if k.startswith("mean ") and k != "mean LA+SA"]
    return "partly" if all(v["mean LA+SA"] < x for x in others) else "no"


def _two_parts(
    rule_id: str, text: str, a: Quantity, b: Quantity, ref: float = 0.0, paper: tuple[PaperNumber, ...] = ()
) -> Rule:
    """Two parts, each holding when its quantity is above ``ref``; the paper's sign is the first's."""
    return Rule(rule_id, text, (a, b), _above(ref, (a.name,), (b.name,)), paper, Direction(a.name, +1, ref))


def _every_beta(rule_id: str, text: str, name: str, meaning: str) -> Rule:
    """Yes if the share of betas ``name`` is 1, partly if above one half (:func:`_share`)."""
    return Rule(
        rule_id, text, (_q(name, (0.5, 1.0), meaning),), _share(name, 0.5), (), Direction(name, +1, 0.5)
    )


def _study(rule_id: str, text: str, sign: int, meaning: str, tests: Decide) -> Rule:
    """A hypothesis of the study: a settled ``effect`` on the paper's side (``sign``) of 0 (yes or no;
    partly: its ``tests``)."""

    def decide(v: Mapping[str, float]) -> str:
        return "yes" if sign * v["effect"] > 0.0 else "no"

    effect = (_q("effect", (0.0,), meaning),)
    return Rule(rule_id, text, effect, decide, direction=Direction("effect", sign), tests=tests)


_LINEAR_TEXT = (
    "two parts: the error grows linearly with the distance (slope > 0 and R^2 >= 0.9), and it lies below "
    "the no-map error at every cup; yes if both hold, partly if one"
)
# sim4's lines: least squares through the origin (the paper's form), uncentred R^2 = 1 - SSE / sum(y^2)
_LINEAR = (
    _q("slope", (0.0,), "slope of the line through the origin fitted to the mean error per new cup"),
    _q("r2", (0.9,), "uncentred R^2 of that line over the cups' means (@intercept: the centred one)"),
    _q("share_below", (1.0,), "share of new cups where the map's mean error is below the no-map one"),
)
# The paper's y = 0.11x, R^2 = 0.98 state no tolerance: "in" when our interval holds it and is no wider
# than the slope itself, or than twice R^2's distance to a perfect fit (set after the results: AFTER_RESULTS)
_LINEAR_PAPER = (
    PaperNumber("slope", 0.11, 0.0, "y = 0.11x", max_width=0.11),
    PaperNumber("r2", 0.98, 0.0, "R^2 = 0.98", max_width=0.04),
)
_WIDTH_NOTE = (
    "the widest interval that may read 'in' (0.11 for the slope 0.11, 0.04 for R^2 = 0.98; the tolerance "
    "band's width for the others) was set after the results were seen, when a review found the Panda's R^2 "
    "read 'in' with an interval 0.44 wide; the paper's numbers are compared on the Panda only"
)
_GROWS = Direction("slope", +1)  # the error grows with the new cup's distance
_BAR = f"{100 * COMPLETION_BAR:.0f}%"  # the completion bar, in the rules' words

_PAPER = (
    _every_beta(
        "sim1.final_error",
        "yes if LA+SA's mean final error is below LA's at every beta, partly if at more than half",
        "share_lower",
        "share of betas where LA+SA's mean final error is below LA's",
    ),
    _two_parts(
        "sim1.time_ratio",
        "two parts, LA slower than LA+SA at beta=75 and at beta=1000 (time ratio LA/LA+SA above 1): yes if "
        "both hold, partly if one; the paper's sizes, 1.45 and 1.30 give or take 0.15, are the numbers",
        _q("ratio_75", (1.0,), "mean time LA / LA+SA at beta = 75"),
        _q("ratio_1000", (1.0,), "mean time LA / LA+SA at beta = 1000"),
        1.0,
        (
            PaperNumber("ratio_75", 1.45, 0.15, "beta = 75"),
            PaperNumber("ratio_1000", 1.30, 0.15, "beta = 1000"),
        ),
    ),
    Rule(
        "sim1.gap_narrows",
        "two parts, the time gap (ratio LA/LA+SA - 1) and the final-error gap (LA - LA+SA): each holds if "
        "the gap has the paper's sign at beta=75 (LA+SA better, > 0) and is smaller in size at beta=1000; "
        "yes if both hold, partly if one",
        (
            _q("time_narrowing", (0.0,), "g75 - |g1000| of the time gap g = ratio - 1: > 0 narrows"),
            _q("time_gap_75", (0.0,), "the time gap at beta = 75, ratio - 1: > 0 if LA+SA is faster"),
            _q("error_narrowing", (0.0,), "d75 - |d1000| of the final-error gap d = LA - LA+SA"),
            _q("error_gap_75", (0.0,), "the final-error gap at beta = 75: > 0 if LA+SA ends closer"),
        ),
        _above(0.0, ("time_gap_75", "time_narrowing"), ("error_gap_75", "error_narrowing")),
        direction=Direction("time_narrowing", +1),  # its paper numbers are sim1.time_ratio's
    ),
    _every_beta(
        "sim1.entropy_sa",
        "yes if LA+SA and LA+SA+Entropy are both below LA's final error at every beta, partly if both at "
        "more than half",
        "share_weaker",
        "the smaller of the two shares of betas below LA",
    ),
    _two_parts(
        "sim2.sa_trapped",
        "the paper's two parts: LA+SA's mean final error grows from the smallest N to the largest, and its "
        "mean confidence in the true cup falls; yes if both hold, partly if one",
        _q("error_growth", (0.0,), "LA+SA's mean final error at the largest N minus at the smallest"),
        _q("confidence_drop", (0.0,), "LA+SA's mean confidence b(g*) at the smallest N minus at the largest"),
    ),
    Rule(
        "sim2.entropy_escapes",
        "yes if LA+SA+Entropy's success at the largest N is at least 80% and at least 20 points above "
        "LA+SA's, partly if above",
        (
            _q("success_entropy", (0.8,), "LA+SA+Entropy's success rate at the largest N"),
            _q("margin", (0.0, 0.2), "LA+SA+Entropy's success minus LA+SA's at the largest N"),
        ),
        lambda v: _parts(v["margin"] > 0.0, v["success_entropy"] >= 0.8 and v["margin"] >= 0.2),
        direction=Direction("margin", +1),
    ),
    _two_parts(
        "sim3.entropy_learners",
        "yes if LA+SA+Entropy's mean error over the episode is below LA+SA's for both learners, partly if "
        "for one",
        _q("gain_fast", (0.0,), "fast learner: LA+SA minus LA+SA+Entropy mean error"),
        _q("gain_slow", (0.0,), "slow learner: LA+SA minus LA+SA+Entropy mean error"),
    ),
    Rule("sim4.straight_line_linear", _LINEAR_TEXT, _LINEAR, _sim4_linear, _LINEAR_PAPER, _GROWS),
    Rule("sim4.grasp_linear", _LINEAR_TEXT, _LINEAR, _sim4_linear, _LINEAR_PAPER, _GROWS),
    Rule(
        "sim4.no_map_training_goal",
        "yes if the no-map error grows linearly with the distance (slope > 0 and R^2 >= 0.9); the paper's "
        "size, y = x (slope 1 give or take 0.15), is the number",
        (
            _q("slope", (0.0,), "slope of the line through the origin of the no-map mean error"),
            _q("r2", (0.9,), "uncentred R^2 of that line over the cups' means (@intercept: centred)"),
        ),
        lambda v: _parts(v["slope"] > 0.0 and v["r2"] >= 0.9),  # y = x's shape: its size is the number
        paper=(PaperNumber("slope", 1.0, 0.15, "y = x"),),
        direction=_GROWS,
    ),
    _study(
        "study.h1",
        "the SA main effect on Goal Error (SA - no SA) must be below 0 with p < .05; yes if both pairwise "
        "comparisons are significant too, partly if not; not testable unless every condition finishes at "
        f"least {_BAR} of its episodes (Goal Error is summed over the task's time), except no (censored: "
        "lower bound) when only SA conditions finish fewer and SA's Goal Error, a lower bound, is already "
        "significantly higher",
        -1,
        "SA - no SA, the within-subjects main effect",
        _sa_lowers,
    ),
    _study(
        "study.h2",
        "Dessert scoop alignment LA+SA - R+SA must be above 0: yes if significant (p < .05); not testable "
        f"unless LA+SA and R+SA each finish at least {_BAR} of their episodes (alignment is measured only on "
        "the phases reached)",
        +1,
        "alignment LA+SA - R+SA in the scoop phase",
        _la_aligns,
    ),
    _study(
        "study.h3",
        f"not testable if any condition finishes fewer than {_BAR} of its episodes; else restricted mean "
        "times to the horizon (min(T, horizon) summed over both tasks), LA+SA minus each other condition, "
        "paired bootstrap 95% intervals over participants: yes if all six (Total and Idle Time) lie below 0, "
        "partly if LA+SA has the lowest restricted mean Total Time, else no; when a condition is short of "
        "the bar, no if LA+SA's restricted mean (a lower bound if LA+SA is the one short: censored) is "
        "already above a measured condition's with the interval clear of 0",
        -1,
        "LA+SA's restricted mean Total Time minus the fastest other condition's [s]",
        _la_sa_fastest,
    ),
    Rule(
        "study.likert",
        "Fig. dessert's Likert scales (Easy, Helpful, Precise, Intuitive, Prefer), LA+SA against each "
        "other condition, paired t with Holm's correction: yes if LA+SA is rated higher with p < .05 in "
        "every comparison, partly if in some, no if in none; not testable without people's answers "
        "(simulated participants answer no questionnaire)",
        (_q("share", (0.0, 1.0), "share of scale x condition comparisons with LA+SA rated higher, p < .05"),),
        _share("share", 0.0),
    ),
)
RULES: Mapping[str, Rule] = MappingProxyType({r.id: r for r in _PAPER})  # read-only

# Rules (or their readings) written after some of the results they judge had been seen.
_TWO_WORDS = (
    "split into the effect (the rule, the claim's shape) and the number (the paper's sizes) after an audit "
    "had read this version's verdicts: the rule no longer reads the paper's sizes"
)
# The study's belief, changed after a probe's results were seen (notebook 11 gives the probe's table).
_BELIEF_CAP = (
    "; the study's belief became Javdani et al.'s, no goal above 0.99 (their implementation's "
    "max_prob_any_goal), after a probe outside the package had seen the study's results with a cap: chosen "
    "as the cited method's own value, the uncapped belief kept as the reading @uncapped"
)
_PANDA_NOTE = (
    "the paper's numbers are compared on the Panda only, the robot the paper states them for ('the real "
    "robot simulations'), since a review after the results were seen; planar5 states none"
)
# sim4's fit, moved to the paper's form after issue 47's review had seen the results (the uncentred R^2
# was chosen as that form's, before its verdicts were seen)
_SIM4_ORIGIN = (
    "; the headline fit became the paper's form, a least-squares line through the origin (uncentred R^2), "
    "after issue 47's review had seen the results; the earlier line with an intercept is the reading "
    "@intercept"
)
AFTER_RESULTS: dict[str, str] = {
    "sim1.time_ratio": f"{_TWO_WORDS}; before, yes needed both ratios within 0.15 of the paper's; "
    + _PANDA_NOTE,
    "sim1.gap_narrows": "each part must now narrow in the paper's direction (LA+SA better at beta = 75), "
    "written after an audit saw 'partly' rest on an error gap in which LA+SA is worse",
    "sim2.sa_trapped": "the paper's two parts (final error grows, confidence falls with N) replaced "
    "LA+SA's success rate after an audit had seen that rule's verdicts and the end confidence in the true "
    "cup",
    "sim4.straight_line_linear": "the partly rule was made stricter (the map must help at every cup) after "
    "the first sim4 results: the earlier 'slope <= 0.5' labelled a map worse than none at near cups partly; "
    f"{_TWO_WORDS} (the slope's (0, 0.25] became 0.11's number word); {_WIDTH_NOTE}{_SIM4_ORIGIN}",
    "sim4.grasp_linear": "as sim4.straight_line_linear" + _SIM4_ORIGIN,
    "sim4.no_map_training_goal": f"{_TWO_WORDS}; before, yes needed |slope - 1| <= 0.15; {_PANDA_NOTE}"
    + _SIM4_ORIGIN,
    "study.h1": "the study's rules were written after pilots of 4 and 10 participants; the mean-distance "
    "reading (@mean_distance) after the paper-scale run; H3's completion guard was extended to H1 (a sum "
    "over the task's time, censored like it) after 0.9.0's censored results were seen, before any verdict "
    "of this version; its censored lower bound's no (as H3's) after an audit saw the guard hide a "
    "significant reversal" + _BELIEF_CAP,
    "study.h2": "written after pilots of 4 and 10 participants; the completion gate (LA+SA and R+SA must "
    "each finish 95%) was added after an audit of the paper-scale run saw H2 read yes with 0% LA completion"
    + _BELIEF_CAP,
    "study.h3": "written after pilots of 4 and 10 participants; the test changed after the previous "
    "version's results were seen, because they were censored (no LA or LA+SA episode of the headline "
    "decoder finished within the 150 s horizon): from paired t-tests on times capped at the horizon to "
    "restricted mean times with a paired bootstrap, behind a guard (not testable unless every condition "
    f"finishes at least {_BAR} of its episodes); the censored lower bound's 'no' (for H1 too) was added "
    "after an audit saw the guard hide a significant reversal, before this version's verdicts were seen; its "
    "extension to a measured LA+SA beside another censored condition after this version's first paper-scale "
    "run" + _BELIEF_CAP,
}


def rule(claim_id: str) -> Rule:
    """The paper's rule of a claim id, ``<figure>.<name>[@<reading>]`` (a ConfigError if none)."""
    base = claim_id.split("@", 1)[0]
    if base not in RULES:
        raise ConfigError(f"no rule for claim {claim_id!r}; rules exist for {sorted(RULES)}")
    return RULES[base]
