"""Decision rules and the words their verdicts read: a :class:`Rule` maps a few numbers to ``yes``, ``partly``
or ``no``, piecewise constant between thresholds, so a box of intervals can settle it. It judges the claim's
shape (the *effect*), never a number's size (the *number*, :meth:`PaperNumber.word`)."""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable, Mapping

from lasa.base.errors import ConfigError

VERDICTS = ("yes", "partly", "no")  # what a rule can decide
UNDECIDED = "undecided"  # what a claim reads when its intervals straddle a threshold
# the claim's test cannot run on the data (a precondition fails); never settled, the reason in its note
NOT_TESTABLE = "not testable"
# a settled "not reproduced" resting on a censored condition: its measure a lower bound, already worse
CENSORED = "censored: lower bound"

# The effect's words (Open Science Collaboration, 2015): the claim's shape as the rule reads it
REPRODUCED = "reproduced"  # the rule reads yes, settled
PARTLY = "partly"  # the rule reads partly, settled: some parts hold, each in the paper's direction
NOT_REPRODUCED = "not reproduced"  # the rule reads no, settled
WORDS = (REPRODUCED, PARTLY, NOT_REPRODUCED, UNDECIDED, NOT_TESTABLE)
_SETTLED_WORD = {"yes": REPRODUCED, "partly": PARTLY, "no": NOT_REPRODUCED}
# The number's words: each number the paper states, against our interval
IN = "in"  # the paper's number lies in our interval, give or take the rule's tolerance
OUT = "out"  # our interval is clear of the paper's number and its tolerance
NOT_APPLICABLE = "n/a"  # the paper states no number for the claim, or the claim is not testable
NUMBER_WORDS = (IN, OUT, UNDECIDED, NOT_APPLICABLE)
# fragile: an interval ends within this fraction of its width (one SE at 98.75%) of a word's change [-]
FRAGILE_FRACTION = 0.2


def _known(interval: tuple[float, float]) -> bool:
    return math.isfinite(interval[0]) and math.isfinite(interval[1])


@dataclasses.dataclass(frozen=True)
class Quantity:
    """One number a verdict rests on, and the thresholds its rule compares it with."""

    name: str  # key in ``Claim.values``
    thresholds: tuple[float, ...]  # every value at which the rule's verdict can change
    meaning: str  # what the number is, in words


@dataclasses.dataclass(frozen=True)
class PaperNumber:
    """A number the paper states, the quantity that measures it, and the rule's tolerance."""

    quantity: str  # the rule's quantity that measures it
    value: float  # the paper's number
    tolerance: float  # the rule's tolerance around it; 0 where the rule states none
    where: str  # where the paper states it, e.g. "beta = 75"
    max_width: float = math.nan  # the widest interval that may read "in"; NaN: 2 x tolerance
    robot: str = "panda"  # the robot the paper states it for

    def __post_init__(self) -> None:
        if not self.width_limit > 0.0:
            raise ConfigError(f"{self.quantity}: a paper number needs a tolerance or a max_width > 0")

    @property
    def width_limit(self) -> float:
        """The widest interval that may read ``in``: ``max_width``, else the tolerance band's width."""
        return self.max_width if math.isfinite(self.max_width) else 2.0 * self.tolerance

    def inside(self, interval: tuple[float, float]) -> str:
        """``yes`` if ``value +- tolerance`` meets the interval, ``no`` if not, ``n/a`` if unknown."""
        low, high = interval
        met = low <= self.value + self.tolerance and high >= self.value - self.tolerance
        return "n/a" if not _known(interval) else "yes" if met else "no"

    def word(self, interval: tuple[float, float]) -> str:
        """``out`` if the interval misses ``value +- tolerance``, ``n/a`` if unknown; ``in`` if at most
        :attr:`width_limit` wide and in the band (without one: holding the value); else ``undecided``."""
        low, high = interval
        met = self.inside(interval)
        if met != "yes":
            return OUT if met == "no" else NOT_APPLICABLE
        band = self.value - self.tolerance <= low and high <= self.value + self.tolerance
        return IN if high - low <= self.width_limit and (self.tolerance == 0.0 or band) else UNDECIDED

    def describe(self, interval: tuple[float, float], measured: float) -> str:
        """``1.45 ± 0.15 (beta = 75): out, 0.961 [0.844, 1.1]``: the number, its tolerance, where the paper
        states it, its word and our measure and interval."""
        tol = f" ± {self.tolerance:g}" if self.tolerance else ""
        said = f"{self.word(interval)}, {measured:.3g} [{interval[0]:.3g}, {interval[1]:.3g}]"
        return f"{self.value:g}{tol} ({self.where}): {said}"


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
        clear = interval[0] > self.null if self.sign > 0 else interval[1] < self.null
        return "n/a" if not _known(interval) else "yes" if clear else "no"


@dataclasses.dataclass(frozen=True)
class Rule:
    """A claim's decision rule: numbers -> verdict, piecewise constant between thresholds."""

    id: str  # the claim id, "<figure>.<name>"
    text: str  # the rule in words, as the claims table states it
    quantities: tuple[Quantity, ...]  # the first is the headline number (``Claim.value``)
    decide: Callable[[Mapping[str, float]], str]  # values -> "yes" | "partly" | "no"
    paper: tuple[PaperNumber, ...] = ()  # the numbers the paper states, each with its quantity
    direction: Direction | None = None  # the paper's sign of the effect, None if it states none
    # the tests' numbers (effects, p-values) -> "yes" | "partly" | "no", for a claim resting on tests
    tests: Callable[[Mapping[str, float]], str] | None = None

    def __post_init__(self) -> None:
        figure, _, name = self.id.partition(".")
        if not figure or not name or " " in self.id or "@" in self.id:
            raise ConfigError(f"a rule's id must be '<figure>.<name>' without spaces or '@', got {self.id!r}")
        if not self.quantities:
            raise ConfigError(f"{self.id}: a rule reads at least one quantity")
        named = [p.quantity for p in self.paper] + ([self.direction.quantity] if self.direction else [])
        names = {q.name for q in self.quantities}
        if extra := [n for n in named if n not in names]:
            raise ConfigError(
                f"{self.id}: paper numbers or direction name {extra}, not quantities {sorted(names)}"
            )

    def _checked(self, out: str, who: str) -> str:
        if out not in VERDICTS:
            raise ConfigError(f"{self.id}: the {who} returned {out!r}, not one of {VERDICTS}")
        return out

    def verdict(self, values: Mapping[str, float]) -> str:
        """The rule's verdict at these values (a ConfigError if a quantity is missing)."""
        if missing := [q.name for q in self.quantities if q.name not in values]:
            raise ConfigError(f"{self.id}: the rule needs {missing}, got {sorted(values)}")
        return self._checked(self.decide(values), "rule")

    def tested(self, results: Mapping[str, float]) -> str:
        """The verdict of the claim's significance tests at ``results`` (a ConfigError without tests)."""
        if self.tests is None:
            raise ConfigError(f"{self.id}: the rule rests on no tests; its verdict is Rule.verdict")
        return self._checked(self.tests(results), "tests")

    def verdicts_in(self, intervals: Mapping[str, tuple[float, float]]) -> set[str]:
        """Every verdict the rule gives inside the box of ``intervals``: one point per cell and threshold."""
        axes = []
        for q in self.quantities:
            low, high = intervals[q.name]
            if not _known((low, high)):
                return set(VERDICTS)  # an unknown interval decides nothing
            cuts = [low, *sorted(t for t in q.thresholds if low <= t <= high), high]
            axes.append(sorted(set(cuts) | {(a + b) / 2 for a, b in itertools.pairwise(cuts)}))
        names = [q.name for q in self.quantities]
        return {self.verdict(dict(zip(names, p, strict=True))) for p in itertools.product(*axes)}

    def settled(self, intervals: Mapping[str, tuple[float, float]]) -> bool:
        """Whether every point of the box of ``intervals`` gives the same verdict."""
        return len(self.verdicts_in(intervals)) == 1

    def fragile(self, intervals: Mapping[str, tuple[float, float]]) -> list[str]:
        """``name [low, high] ends d from t`` for each interval end within :data:`FRAGILE_FRACTION`
        of its width of a threshold or an edge ``value ± tolerance`` of a paper number."""
        edges: dict[str, list[float]] = {q.name: list(q.thresholds) for q in self.quantities}
        for p in self.paper:
            edges[p.quantity] += [p.value - p.tolerance, p.value + p.tolerance] if p.tolerance else [p.value]
        out = []
        for name, values in edges.items():
            low, high = intervals.get(name, (math.nan, math.nan))
            margin = FRAGILE_FRACTION * (high - low)
            if _known((low, high)) and margin > 0.0:
                gaps = {t: min(abs(low - t), abs(high - t)) for t in sorted(set(values))}
                near = [(t, gap) for t, gap in gaps.items() if gap < margin]
                out += [f"{name} [{low:.3g}, {high:.3g}] ends {gap:.2g} from {t:g}" for t, gap in near]
        return out

    def straddled(self, intervals: Mapping[str, tuple[float, float]]) -> list[str]:
        """``name [low, high] reaches t`` for each threshold inside (or at the end of) an interval."""
        out = []
        for q in self.quantities:
            low, high = intervals[q.name]
            if inner := [f"{t:g}" for t in q.thresholds if low <= t <= high and low < high]:
                out.append(f"{q.name} [{low:.3g}, {high:.3g}] reaches {', '.join(inner)}")
        return out


def effect_word(verdict: str) -> str:
    """The effect's word (:data:`WORDS`) for a verdict; a ConfigError for none of them."""
    if verdict not in (known := (*VERDICTS, UNDECIDED, NOT_TESTABLE)):
        raise ConfigError(f"cannot word the verdict {verdict!r}: not one of {known}")
    return _SETTLED_WORD.get(verdict, verdict)


def word(
    verdict: str, intervals: Mapping[str, tuple[float, float]], paper: tuple[PaperNumber, ...] = ()
) -> str:
    """Both words in one (the ``reproduced`` column): ``not reproduced`` if a paper number is ``out``,
    ``undecided`` if the effect is ``reproduced`` while a number is ``undecided``, else the effect's."""
    effect = effect_word(verdict)
    if effect == NOT_TESTABLE:
        return NOT_TESTABLE
    numbers = [p.word(intervals.get(p.quantity, (math.nan, math.nan))) for p in paper]
    if OUT in numbers:
        return NOT_REPRODUCED
    return UNDECIDED if effect == REPRODUCED and UNDECIDED in numbers else effect
