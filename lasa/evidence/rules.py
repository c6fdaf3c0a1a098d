"""Every claim's decision rule, with its thresholds, in one place.

A claim's verdict (``yes``, ``partly`` or ``no``) is a rule applied to a few numbers
measured on simulated users: a time ratio, a success rate, a slope. Each number is a
:class:`Quantity` that names the thresholds the rule compares it with, so the rule is
piecewise constant between them. That is what lets :mod:`lasa.evidence.verdicts` decide whether a
verdict is *settled*: when every number's interval lies on one side of each of its
thresholds, the rule gives the same verdict everywhere in the box of intervals (checked
by :meth:`Rule.settled`, which evaluates the rule at a point in every cell of that box).
Otherwise the verdict reads ``undecided``.

A claim of your own gets its rule with :func:`register_rule`: then
:func:`lasa.evidence.verdicts.assess` judges it like the paper's (``docs/extending.md``).

For example the time ratio of Fig. sim1 must be within 0.15 of 1.45 at beta = 75, so its
thresholds are 1.30 and 1.60, and 1.0 for ``partly`` (LA is slower at all).

The rules were written before the results they judge were first seen, with the
exceptions that :data:`AFTER_RESULTS` names. Putting them here changed none of them;
it only made their thresholds explicit.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable, Mapping

from lasa.base.errors import ConfigError

__all__ = [
    "Quantity",
    "Rule",
    "RULES",
    "AFTER_RESULTS",
    "rule",
    "register_rule",
    "VERDICTS",
    "UNDECIDED",
    "NOT_TESTABLE",
    "REPRODUCED",
    "PARTLY",
    "NOT_REPRODUCED",
    "WORDS",
    "PaperNumber",
    "Direction",
    "word",
]

VERDICTS = ("yes", "partly", "no")  # what a rule can decide
UNDECIDED = "undecided"  # what a claim reads when its intervals straddle a threshold
# what a claim reads when its test cannot be run on the data: the claim's precondition fails
# (e.g. the episodes it compares were cut at the horizon, too few pairs); never settled, the
# reason in its note
NOT_TESTABLE = "not testable"

# The verdict words of the claims table, the one vocabulary a reader sees (:func:`word`):
REPRODUCED = "reproduced"  # the rule reads yes, settled
PARTLY = "partly"  # the rule reads partly, settled
# the rule reads no, settled; or a number the paper states lies outside our interval
# (give or take the rule's tolerance), whatever the rule reads
NOT_REPRODUCED = "not reproduced"
WORDS = (REPRODUCED, PARTLY, NOT_REPRODUCED, UNDECIDED, NOT_TESTABLE)
_SETTLED_WORD = {"yes": REPRODUCED, "partly": PARTLY, "no": NOT_REPRODUCED}


@dataclasses.dataclass(frozen=True)
class Quantity:
    """One number a verdict rests on, and the thresholds its rule compares it with."""

    name: str  # key in ``Claim.values``
    thresholds: tuple[float, ...]  # every value at which the rule's verdict can change
    meaning: str  # what the number is, in words


@dataclasses.dataclass(frozen=True)
class PaperNumber:
    """A number the paper states, the quantity that measures it, and the rule's tolerance.

    The replication criterion "the paper's value lies inside our interval" (Open Science
    Collaboration, 2015), with the rule's tolerance: the paper's value is *in* our interval
    when the band ``value +- tolerance`` meets it. ``tolerance`` is the one the rule applies
    around this number (0.15 for the time ratios), and 0 where the rule states none: a rule
    that accepts a range (a slope in (0, 0.25]) states no tolerance around the paper's value.
    """

    quantity: str  # the rule's quantity that measures it
    value: float  # the paper's number
    tolerance: float  # the rule's tolerance around it; 0 where the rule states none
    where: str  # where the paper states it, e.g. "beta = 75"

    def inside(self, interval: tuple[float, float]) -> str:
        """``yes`` if ``value +- tolerance`` meets the interval, ``no`` if not, ``n/a`` if unknown."""
        low, high = interval
        if not (math.isfinite(low) and math.isfinite(high)):
            return "n/a"
        return "yes" if low <= self.value + self.tolerance and high >= self.value - self.tolerance else "no"

    def word(self, interval: tuple[float, float]) -> str:
        """This number's verdict: the interval inside the band, outside it, or across its edge."""
        low, high = interval
        if self.inside(interval) == "n/a":
            return NOT_TESTABLE
        if self.inside(interval) == "no":
            return NOT_REPRODUCED
        inner = self.value - self.tolerance <= low and high <= self.value + self.tolerance
        return REPRODUCED if inner else UNDECIDED

    def describe(self, interval: tuple[float, float], measured: float) -> str:
        """``1.45 ± 0.15 (beta = 75): not reproduced, 0.961 [0.844, 1.1]``."""
        tol = f" ± {self.tolerance:g}" if self.tolerance else ""
        low, high = interval
        return (
            f"{self.value:g}{tol} ({self.where}): {self.word(interval)}, "
            f"{measured:.3g} [{low:.3g}, {high:.3g}]"
        )


@dataclasses.dataclass(frozen=True)
class Direction:
    """The sign the paper gives an effect, for the criterion "same direction, interval clear of null"."""

    quantity: str  # the rule's quantity that carries the effect
    sign: int  # +1: the paper's effect is above ``null``; -1: below
    null: float = 0.0  # no effect (1 for a ratio, one half for a share of conditions)

    def __post_init__(self) -> None:
        if self.sign not in (-1, 1):
            raise ConfigError(f"{self.quantity}: a direction's sign is +1 or -1, got {self.sign!r}")

    def judge(self, interval: tuple[float, float]) -> str:
        """``yes`` if the interval lies on the paper's side of ``null``; ``n/a`` if unknown; else ``no``."""
        low, high = interval
        if not (math.isfinite(low) and math.isfinite(high)):
            return "n/a"
        clear = low > self.null if self.sign > 0 else high < self.null
        return "yes" if clear else "no"


@dataclasses.dataclass(frozen=True)
class Rule:
    """A claim's decision rule: numbers -> verdict, piecewise constant between thresholds."""

    id: str  # the claim id, "<figure>.<name>"
    text: str  # the rule in words, as the claims table states it
    quantities: tuple[Quantity, ...]  # the first is the headline number (``Claim.value``)
    decide: Callable[[Mapping[str, float]], str]  # values -> "yes" | "partly" | "no"
    paper: tuple[PaperNumber, ...] = ()  # the numbers the paper states, each with its quantity
    direction: Direction | None = None  # the paper's sign of the effect, None if it states none

    def verdict(self, values: Mapping[str, float]) -> str:
        """The rule's verdict at these values.

        Raises:
            ConfigError: if a quantity is missing, or the rule returns something else.
        """
        missing = [q.name for q in self.quantities if q.name not in values]
        if missing:
            raise ConfigError(f"{self.id}: the rule needs {missing}, got {sorted(values)}")
        out = self.decide(values)
        if out not in VERDICTS:
            raise ConfigError(f"{self.id}: the rule returned {out!r}, not one of {VERDICTS}")
        return out

    def verdicts_in(self, intervals: Mapping[str, tuple[float, float]]) -> set[str]:
        """Every verdict the rule gives inside the box of ``intervals`` (name -> (low, high)).

        The rule only compares each number with its thresholds, so one point per cell
        between consecutive thresholds (and the thresholds themselves) covers the box.
        """
        axes = []
        for q in self.quantities:
            low, high = intervals[q.name]
            if not (math.isfinite(low) and math.isfinite(high)):
                return set(VERDICTS)  # an unknown interval decides nothing
            inner = sorted(t for t in q.thresholds if low <= t <= high)
            cuts = [low, *inner, high]
            points = set(cuts) | {(a + b) / 2 for a, b in itertools.pairwise(cuts)}
            axes.append(sorted(points))
        names = [q.name for q in self.quantities]
        return {self.verdict(dict(zip(names, p, strict=True))) for p in itertools.product(*axes)}

    def settled(self, intervals: Mapping[str, tuple[float, float]]) -> bool:
        """Whether every point of the box of ``intervals`` gives the same verdict."""
        return len(self.verdicts_in(intervals)) == 1

    def __post_init__(self) -> None:
        names = {q.name for q in self.quantities}
        extra = [p.quantity for p in self.paper if p.quantity not in names]
        if self.direction is not None and self.direction.quantity not in names:
            extra.append(self.direction.quantity)
        if extra:
            raise ConfigError(
                f"{self.id}: paper numbers or direction name {extra}, not quantities {sorted(names)}"
            )

    def straddled(self, intervals: Mapping[str, tuple[float, float]]) -> list[str]:
        """``name [low, high] reaches t`` for each threshold inside (or at the end of) an interval."""
        out = []
        for q in self.quantities:
            low, high = intervals[q.name]
            inner = [t for t in q.thresholds if low <= t <= high and low < high]
            if inner:
                ts = ", ".join(f"{t:g}" for t in inner)
                out.append(f"{q.name} [{low:.3g}, {high:.3g}] reaches {ts}")
        return out


def word(
    reading: str, intervals: Mapping[str, tuple[float, float]], paper: tuple[PaperNumber, ...] = ()
) -> str:
    """The claims table's verdict word (:data:`WORDS`): the strongest thing that is settled.

    Args:
        reading: What the rule reads at the intervals: ``yes``, ``partly`` or ``no`` when
            settled, else ``undecided``; or ``not testable``.
        intervals: Quantity name -> interval (the row's own level).
        paper: The numbers the paper states (the rule's :attr:`Rule.paper`).

    Returns:
        ``not testable`` as it is; ``not reproduced`` if a number the paper states lies
        outside its interval (give or take the rule's tolerance: :meth:`PaperNumber.inside`),
        whatever the rule reads; else the settled reading's word, or ``undecided``.

    Raises:
        ConfigError: if ``reading`` is not a rule's verdict, ``undecided`` or ``not testable``.
    """
    if reading not in (*VERDICTS, UNDECIDED, NOT_TESTABLE):
        raise ConfigError(
            f"cannot word the reading {reading!r}: not one of {(*VERDICTS, UNDECIDED, NOT_TESTABLE)}"
        )
    if reading == NOT_TESTABLE:
        return NOT_TESTABLE
    if any(p.inside(intervals.get(p.quantity, (math.nan, math.nan))) == "no" for p in paper):
        return NOT_REPRODUCED
    return _SETTLED_WORD.get(reading, UNDECIDED)


def _q(name: str, thresholds: tuple[float, ...], meaning: str) -> Quantity:
    return Quantity(name, tuple(float(t) for t in thresholds), meaning)


def _sim1_final_error(v: Mapping[str, float]) -> str:
    return "yes" if v["share_lower"] >= 1.0 else "partly" if v["share_lower"] > 0.5 else "no"


def _sim1_time_ratio(v: Mapping[str, float]) -> str:
    r75, r1000 = v["ratio_75"], v["ratio_1000"]
    if abs(r75 - 1.45) <= 0.15 and abs(r1000 - 1.30) <= 0.15:
        return "yes"
    return "partly" if r75 > 1.0 and r1000 > 1.0 else "no"


def _both_or_one(a: str, b: str) -> Callable[[Mapping[str, float]], str]:
    def decide(v: Mapping[str, float]) -> str:
        ok = [v[a] > 0.0, v[b] > 0.0]
        return "yes" if all(ok) else "partly" if any(ok) else "no"

    return decide


def _sim1_entropy_sa(v: Mapping[str, float]) -> str:
    return "yes" if v["share_weaker"] >= 1.0 else "partly" if v["share_weaker"] > 0.5 else "no"


def _sim2_trapped(v: Mapping[str, float]) -> str:
    return "yes" if v["success_sa"] < 0.5 else "partly" if v["drop_sa"] >= 0.2 else "no"


def _sim2_escapes(v: Mapping[str, float]) -> str:
    if v["success_entropy"] >= 0.8 and v["margin"] >= 0.2:
        return "yes"
    return "partly" if v["margin"] > 0.0 else "no"


def _sim4_linear(v: Mapping[str, float]) -> str:
    helps = v["share_below"] >= 1.0
    linear = v["r2"] >= 0.9 and 0.0 < v["slope"] <= 0.25
    return "yes" if linear and helps else "partly" if helps else "no"


def _sim4_no_map(v: Mapping[str, float]) -> str:
    slope, r2 = v["slope"], v["r2"]
    if abs(slope - 1.0) <= 0.15 and r2 >= 0.9:
        return "yes"
    return "partly" if r2 >= 0.9 and 0.5 <= slope <= 1.5 else "no"


def _effect_below_zero(v: Mapping[str, float]) -> str:
    # the study's tests: a settled effect below zero is the paper's direction; the
    # full yes/partly split comes from the pairwise tests (lasa.figures.study)
    return "yes" if v["effect"] < 0.0 else "no"


def _effect_above_zero(v: Mapping[str, float]) -> str:
    return "yes" if v["effect"] > 0.0 else "no"


_LINEAR_TEXT = (
    "yes if R^2 >= 0.9, slope in (0, 0.25] and below the no-map error at every cup; "
    "partly if below it at every cup; else no"
)
_LINEAR = (
    _q("slope", (0.0, 0.25), "slope of the mean error per new cup against its distance"),
    _q("r2", (0.9,), "R^2 of that line over the cups' means"),
    _q("share_below", (1.0,), "share of new cups where the map's mean error is below the no-map one"),
)
# The paper's Fig. sim4 line, y = 0.11x with R^2 = 0.98: the rule accepts a range of slopes,
# (0, 0.25], and states no tolerance around 0.11 (our axes are joint-space distances; a slope
# is unitless either way)
_LINEAR_PAPER = (PaperNumber("slope", 0.11, 0.0, "y = 0.11x"), PaperNumber("r2", 0.98, 0.0, "R^2 = 0.98"))
_GROWS = Direction("slope", +1)  # the error grows with the new cup's distance

RULES: dict[str, Rule] = {
    r.id: r
    for r in (
        Rule(
            "sim1.final_error",
            "yes if LA+SA's mean final error is below LA's at every beta, partly if at more than half",
            (_q("share_lower", (0.5, 1.0), "share of betas where LA+SA's mean final error is below LA's"),),
            _sim1_final_error,
            direction=Direction("share_lower", +1, 0.5),
        ),
        Rule(
            "sim1.time_ratio",
            "yes if both time ratios LA/LA+SA lie within 0.15 of the paper's (1.45 at beta=75, 1.30 at "
            "beta=1000), partly if both exceed 1",
            (
                _q("ratio_75", (1.0, 1.30, 1.60), "mean time LA / LA+SA at beta = 75"),
                _q("ratio_1000", (1.0, 1.15, 1.45), "mean time LA / LA+SA at beta = 1000"),
            ),
            _sim1_time_ratio,
            paper=(
                PaperNumber("ratio_75", 1.45, 0.15, "beta = 75"),
                PaperNumber("ratio_1000", 1.30, 0.15, "beta = 1000"),
            ),
            direction=Direction("ratio_75", +1, 1.0),
        ),
        Rule(
            "sim1.gap_narrows",
            "yes if both the time gap |ratio - 1| and the final-error gap |LA - LA+SA| shrink from "
            "beta=75 to beta=1000, partly if one does",
            (
                _q("time_narrowing", (0.0,), "|r75 - 1| - |r1000 - 1|: > 0 if the time gap narrows"),
                _q("error_narrowing", (0.0,), "|d75| - |d1000| of the final-error difference"),
            ),
            _both_or_one("time_narrowing", "error_narrowing"),
            direction=Direction("time_narrowing", +1),  # its paper numbers are sim1.time_ratio's
        ),
        Rule(
            "sim1.entropy_sa",
            "yes if LA+SA and LA+SA+Entropy are both below LA's final error at every beta, partly if "
            "both at more than half",
            (_q("share_weaker", (0.5, 1.0), "the smaller of the two shares of betas below LA"),),
            _sim1_entropy_sa,
            direction=Direction("share_weaker", +1, 0.5),
        ),
        Rule(
            "sim2.sa_trapped",
            "yes if LA+SA's success at the largest N is below 50%, partly if it falls by at least 20 "
            "points from the smallest N",
            (
                _q("success_sa", (0.5,), "LA+SA's success rate at the largest N"),
                _q("drop_sa", (0.2,), "LA+SA's success at the smallest N minus at the largest"),
            ),
            _sim2_trapped,
            direction=Direction("success_sa", -1, 0.5),
        ),
        Rule(
            "sim2.entropy_escapes",
            "yes if LA+SA+Entropy's success at the largest N is at least 80% and at least 20 points "
            "above LA+SA's, partly if above",
            (
                _q("success_entropy", (0.8,), "LA+SA+Entropy's success rate at the largest N"),
                _q("margin", (0.0, 0.2), "LA+SA+Entropy's success minus LA+SA's at the largest N"),
            ),
            _sim2_escapes,
            direction=Direction("margin", +1),
        ),
        Rule(
            "sim3.entropy_learners",
            "yes if LA+SA+Entropy's mean error over the episode is below LA+SA's for both learners, "
            "partly if for one",
            (
                _q("gain_fast", (0.0,), "fast learner: LA+SA minus LA+SA+Entropy mean error"),
                _q("gain_slow", (0.0,), "slow learner: LA+SA minus LA+SA+Entropy mean error"),
            ),
            _both_or_one("gain_fast", "gain_slow"),
            direction=Direction("gain_fast", +1),
        ),
        Rule("sim4.straight_line_linear", _LINEAR_TEXT, _LINEAR, _sim4_linear, _LINEAR_PAPER, _GROWS),
        Rule("sim4.grasp_linear", _LINEAR_TEXT, _LINEAR, _sim4_linear, _LINEAR_PAPER, _GROWS),
        Rule(
            "sim4.no_map_training_goal",
            "yes if |slope - 1| <= 0.15 and R^2 >= 0.9, partly if R^2 >= 0.9 and slope in [0.5, 1.5]",
            (
                _q("slope", (0.5, 0.85, 1.15, 1.5), "slope of the no-map mean error against distance"),
                _q("r2", (0.9,), "R^2 of that line over the cups' means"),
            ),
            _sim4_no_map,
            paper=(PaperNumber("slope", 1.0, 0.15, "y = x"),),
            direction=_GROWS,
        ),
        Rule(
            "study.h1",
            "the SA main effect on Goal Error (SA - no SA) must be below 0 with p < .05; yes if both "
            "pairwise comparisons are significant too, partly if not; not testable unless every condition "
            "finishes at least 95% of its episodes (Goal Error is summed over the task's time)",
            (_q("effect", (0.0,), "SA - no SA, the within-subjects main effect"),),
            _effect_below_zero,
            direction=Direction("effect", -1),
        ),
        Rule(
            "study.h2",
            "Dessert scoop alignment LA+SA - R+SA must be above 0: yes if significant (p < .05)",
            (_q("effect", (0.0,), "alignment LA+SA - R+SA in the scoop phase"),),
            _effect_above_zero,
            direction=Direction("effect", +1),
        ),
        Rule(
            "study.h3",
            "not testable if any condition finishes fewer than 95% of its episodes; else restricted mean "
            "times to the horizon (min(T, horizon) summed over both tasks), LA+SA minus each other "
            "condition, paired bootstrap 95% intervals over participants: yes if all six (Total and "
            "Idle Time) lie below 0, partly if LA+SA has the lowest restricted mean Total Time, else no",
            (
                _q(
                    "effect",
                    (0.0,),
                    "LA+SA's restricted mean Total Time minus the fastest other condition's [s]",
                ),
            ),
            _effect_below_zero,
            direction=Direction("effect", -1),
        ),
    )
}

# Rules (or readings) written after some of the results they judge had been seen.
AFTER_RESULTS: dict[str, str] = {
    "sim4.straight_line_linear": "the partly rule was made stricter (the map must help at every cup) after "
    "the first sim4 results: the earlier 'slope <= 0.5' labelled a map worse than none at near cups partly",
    "sim4.grasp_linear": "as sim4.straight_line_linear",
    "study.h1": "the study's rules were written after pilots of 4 and 10 participants; the mean-distance "
    "reading (@mean_distance) after the paper-scale run; H3's completion guard was extended to H1 (a sum "
    "over the task's time, censored like it) after 0.9.0's censored results were seen, before any verdict "
    "of this version",
    "study.h2": "written after pilots of 4 and 10 participants",
    "study.h3": "written after pilots of 4 and 10 participants; the test changed after the previous "
    "version's results were seen, because they were censored (no LA or LA+SA episode of the headline "
    "decoder finished within the 150 s horizon): from paired t-tests on times capped at the horizon to "
    "restricted mean times with a paired bootstrap, behind a guard (not testable unless every condition "
    "finishes at least 95% of its episodes)",
}


def rule(claim_id: str) -> Rule:
    """The rule of a claim id, ``<figure>.<name>`` or ``<figure>.<name>@<reading>``.

    Raises:
        ConfigError: if the claim has no rule here.
    """
    base = claim_id.split("@", 1)[0]
    if base not in RULES:
        raise ConfigError(f"no rule for claim {claim_id!r}; rules exist for {sorted(RULES)}")
    return RULES[base]


_PAPER_RULES = frozenset(RULES)  # the paper's claims' rules, which register_rule never replaces


def register_rule(new: Rule, *, replace: bool = False) -> Rule:
    """Add the rule of a claim of your own to :data:`RULES`, from outside the package.

    Then :func:`rule` finds it, for ``<id>`` and every ``<id>@<reading>``, and
    :func:`lasa.evidence.verdicts.assess` gives its claims intervals and settles them.

    Args:
        new: The rule; its id is ``<figure>.<name>``, as its claims' ids.
        replace: Replace a rule registered under that id before (never a paper claim's).

    Returns:
        The rule.

    Raises:
        ConfigError: if the id is not ``<figure>.<name>``, has no quantity, or is taken
            (a paper claim's always, another only unless ``replace``).
    """
    figure, _, name = new.id.partition(".")
    if not figure or not name or " " in new.id or "@" in new.id:
        raise ConfigError(f"a rule's id must be '<figure>.<name>' without spaces or '@', got {new.id!r}")
    if not new.quantities:
        raise ConfigError(f"{new.id}: a rule reads at least one quantity")
    if new.id in RULES and (new.id in _PAPER_RULES or not replace):
        raise ConfigError(
            f"a rule for {new.id!r} exists already"
            + ("" if new.id in _PAPER_RULES else "; pass replace=True")
        )
    RULES[new.id] = new
    return new
