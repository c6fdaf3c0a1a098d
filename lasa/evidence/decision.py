"""What a decision rule is, and the words its verdicts read.

A claim's verdict (``yes``, ``partly`` or ``no``) is a rule applied to a few numbers
measured on simulated users: a time ratio, a success rate, a slope. Each number is a
:class:`Quantity` that names the thresholds the rule compares it with, so the rule is
piecewise constant between them. That is what lets :mod:`lasa.evidence.verdicts` decide whether a
verdict is *settled*: when every number's interval lies on one side of each of its
thresholds, the rule gives the same verdict everywhere in the box of intervals (checked
by :meth:`Rule.settled`, which evaluates the rule at a point in every cell of that box).
Otherwise the verdict reads ``undecided``. A claim whose yes/partly/no rests on significance
tests (the study's) also has :attr:`Rule.tests`, the verdict from the tests' numbers; its
quantities then only settle it.

A rule judges the claim's *shape*: its direction and significance (LA is slower than LA+SA, the
error grows with distance), never whether a number has the paper's size. The claims table gives
each claim two words: the *effect* (:func:`effect_word`, :data:`WORDS`), what the rule reads, and
the *number* (:meth:`PaperNumber.word`, :data:`NUMBER_WORDS`), for each number the paper states
whether it lies in our interval. The paper's rules themselves are :mod:`lasa.evidence.rules`.
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
    "VERDICTS",
    "UNDECIDED",
    "NOT_TESTABLE",
    "CENSORED",
    "REPRODUCED",
    "PARTLY",
    "NOT_REPRODUCED",
    "WORDS",
    "IN",
    "OUT",
    "NOT_APPLICABLE",
    "NUMBER_WORDS",
    "FRAGILE_FRACTION",
    "PaperNumber",
    "Direction",
    "effect_word",
    "word",
]

VERDICTS = ("yes", "partly", "no")  # what a rule can decide
UNDECIDED = "undecided"  # what a claim reads when its intervals straddle a threshold
# what a claim reads when its test cannot be run on the data: the claim's precondition fails
# (e.g. the episodes it compares were cut at the horizon, too few pairs); never settled, the
# reason in its note
NOT_TESTABLE = "not testable"
# what a settled "not reproduced" carries when it rests on a censored arm: that arm's measure is
# a lower bound (its unfinished episodes would only add to it), already worse than a comparator's
CENSORED = "censored: lower bound"

# Two words per claim (Open Science Collaboration, 2015), the one vocabulary a reader sees.
# The *effect* (:func:`effect_word`): the claim's shape, its direction and significance, as
# the rule reads it (a rule's yes/partly/no judges the shape only, never a number's size):
REPRODUCED = "reproduced"  # the rule reads yes, settled
PARTLY = "partly"  # the rule reads partly, settled: some parts hold, each in the paper's direction
NOT_REPRODUCED = "not reproduced"  # the rule reads no, settled
WORDS = (REPRODUCED, PARTLY, NOT_REPRODUCED, UNDECIDED, NOT_TESTABLE)
_SETTLED_WORD = {"yes": REPRODUCED, "partly": PARTLY, "no": NOT_REPRODUCED}
# The *number* (:meth:`PaperNumber.word`): for each number the paper states, against our interval
IN = "in"  # the paper's number lies in our interval, give or take the rule's tolerance
OUT = "out"  # our interval is clear of the paper's number and its tolerance
NOT_APPLICABLE = "n/a"  # the paper states no number for the claim, or the claim is not testable
NUMBER_WORDS = (IN, OUT, UNDECIDED, NOT_APPLICABLE)
# A verdict is *fragile* (:meth:`Rule.fragile`) when an interval ends within this fraction of its
# width of a value at which a word changes. A fifth of the width is one standard error at the
# verdicts' 98.75% level (the width is 2 x 2.5 SE): about what another draw of the users moves an
# interval's end, and more than another CPU or library moves it (that re-draws only the chaotic
# episodes). Fixed before any verdict was marked with it. [-]
FRAGILE_FRACTION = 0.2


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
    Collaboration, 2015), with the rule's tolerance (:meth:`word`). ``tolerance`` is the one the
    rule applies around this number (0.15 for the time ratios), and 0 where the rule states none.
    ``max_width`` is the widest interval that may read ``in``: a wider one cannot tell the paper's
    number from a value that would change the claim, and reads ``undecided`` (the tolerance band's
    width, 2 x ``tolerance``, where it is left NaN). ``robot`` is the robot the paper states the
    number for: "the real robot simulations", the Panda; on another robot it is not compared.
    """

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
        if not (math.isfinite(low) and math.isfinite(high)):
            return "n/a"
        return "yes" if low <= self.value + self.tolerance and high >= self.value - self.tolerance else "no"

    def word(self, interval: tuple[float, float]) -> str:
        """This number's word (:data:`NUMBER_WORDS`) against our interval.

        ``out`` if the interval misses ``value +- tolerance``; ``n/a`` if the interval is unknown.
        Else ``in`` if the interval is narrow enough to say so (at most :attr:`width_limit`) and,
        with a tolerance, lies inside the band (every value we cannot exclude is within
        tolerance); without one (0: the rule states none) if it contains the value (the Open
        Science Collaboration's criterion). Otherwise ``undecided``.
        """
        low, high = interval
        met = self.inside(interval)
        if met != "yes":
            return OUT if met == "no" else NOT_APPLICABLE
        if high - low > self.width_limit:
            return UNDECIDED
        if self.tolerance == 0.0:
            return IN
        inner = self.value - self.tolerance <= low and high <= self.value + self.tolerance
        return IN if inner else UNDECIDED

    def describe(self, interval: tuple[float, float], measured: float) -> str:
        """``1.45 ± 0.15 (beta = 75): out, 0.961 [0.844, 1.1]``."""
        low, high = interval
        return f"{self.label}: {self.word(interval)}, {measured:.3g} [{low:.3g}, {high:.3g}]"

    @property
    def label(self) -> str:
        """``1.45 ± 0.15 (beta = 75)``: the number, its tolerance and where the paper states it."""
        tol = f" ± {self.tolerance:g}" if self.tolerance else ""
        return f"{self.value:g}{tol} ({self.where})"


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
    # a claim whose yes/partly/no rests on significance tests (the study's): the tests' numbers
    # (effects, p-values) -> "yes" | "partly" | "no"; its quantities then only settle it
    tests: Callable[[Mapping[str, float]], str] | None = None

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

    def tested(self, results: Mapping[str, float]) -> str:
        """The verdict of the claim's significance tests at ``results`` (:attr:`tests`).

        Raises:
            ConfigError: if the rule has no tests, or they return something else.
        """
        if self.tests is None:
            raise ConfigError(f"{self.id}: the rule rests on no tests; its verdict is Rule.verdict")
        out = self.tests(results)
        if out not in VERDICTS:
            raise ConfigError(f"{self.id}: the tests returned {out!r}, not one of {VERDICTS}")
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

    def fragile(self, intervals: Mapping[str, tuple[float, float]]) -> list[str]:
        """``name [low, high] ends d from t`` for each interval end within :data:`FRAGILE_FRACTION`
        of its width of a value at which a word can change: one of the rule's thresholds (the
        effect) or an edge of a number the paper states, ``value ± tolerance`` (the number)."""
        edges: dict[str, list[float]] = {q.name: list(q.thresholds) for q in self.quantities}
        for p in self.paper:
            edges[p.quantity] += [p.value - p.tolerance, p.value + p.tolerance] if p.tolerance else [p.value]
        out = []
        for name, values in edges.items():
            low, high = intervals.get(name, (math.nan, math.nan))
            margin = FRAGILE_FRACTION * (high - low)
            if not (math.isfinite(low) and math.isfinite(high)) or margin <= 0.0:
                continue
            gaps = {t: min(abs(low - t), abs(high - t)) for t in sorted(set(values))}
            out += [
                f"{name} [{low:.3g}, {high:.3g}] ends {gap:.2g} from {t:g}"
                for t, gap in gaps.items()
                if gap < margin
            ]
        return out

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


def effect_word(reading: str) -> str:
    """The effect's word (:data:`WORDS`) of a rule's reading.

    Args:
        reading: What the rule reads at the intervals: ``yes``, ``partly`` or ``no`` when
            settled, else ``undecided``; or ``not testable``.

    Returns:
        ``reproduced``, ``partly`` or ``not reproduced`` for a settled reading; else the
        reading itself.

    Raises:
        ConfigError: if ``reading`` is not a rule's verdict, ``undecided`` or ``not testable``.
    """
    if reading not in (*VERDICTS, UNDECIDED, NOT_TESTABLE):
        raise ConfigError(
            f"cannot word the reading {reading!r}: not one of {(*VERDICTS, UNDECIDED, NOT_TESTABLE)}"
        )
    return _SETTLED_WORD.get(reading, reading)


def word(
    reading: str, intervals: Mapping[str, tuple[float, float]], paper: tuple[PaperNumber, ...] = ()
) -> str:
    """Both words in one (the claims table's ``reproduced`` column, kept for its older readers).

    Args:
        reading: The rule's reading (see :func:`effect_word`).
        intervals: Quantity name -> interval (the row's own level).
        paper: The numbers the paper states (the rule's :attr:`Rule.paper`).

    Returns:
        ``not testable`` as it is; ``not reproduced`` if a number the paper states is ``out``;
        ``undecided`` if the effect reads ``reproduced`` while a number is ``undecided``; else
        the effect's word.

    Raises:
        ConfigError: if ``reading`` is not a rule's verdict, ``undecided`` or ``not testable``.
    """
    effect = effect_word(reading)
    if effect == NOT_TESTABLE:
        return NOT_TESTABLE
    numbers = [p.word(intervals.get(p.quantity, (math.nan, math.nan))) for p in paper]
    if OUT in numbers:
        return NOT_REPRODUCED
    return UNDECIDED if effect == REPRODUCED and UNDECIDED in numbers else effect
