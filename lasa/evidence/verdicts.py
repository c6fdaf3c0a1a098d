"""Verdicts decided by user-bootstrap intervals (:func:`assess`: **settled** when every interval clears each
threshold, else ``undecided``), with users added by a group-sequential :class:`Looks` where a headline verdict
is open (:func:`sequential`). The design: ``docs/method-notes.md``."""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pandas as pd

from lasa.base.config import NO_ASSISTANCE  # defined once, in the base; re-exported here
from lasa.base.errors import ConfigError
from lasa.evidence.claims import Claim, criteria, words_text
from lasa.evidence.decision import UNDECIDED

N_BOOT = 1000  # bootstrap resamples per interval: a 98.75% percentile interval has ~6 resamples per tail [-]
# The least evidence a settled verdict may rest on (:func:`shortfall`), fixed in advance.
MIN_USERS = 60  # users per point (fewer gave zero-width intervals) [-]
MIN_TAIL = 5  # resamples beyond each bound of a percentile interval [-]
ALPHA = 0.05  # family-wise error of a verdict over all its looks [-]
USER = "seed"  # the column naming a simulated user, the unit a bootstrap resamples

Evaluate = Callable[[pd.DataFrame], list[Claim]]


@dataclasses.dataclass(frozen=True)
class Looks:
    """Users per point: a first look, blocks after it, a cap (fixed before the results)."""

    first: int = 60  # users per point at the first look, every pair and member [-]
    block: int = 30  # users added per later look, the headline member's pairs only [-]
    cap: int = 150  # most users per point [-]

    def __post_init__(self) -> None:
        check_looks(self.first, self.block, self.cap)

    @property
    def sizes(self) -> tuple[int, ...]:
        """Users per point at each possible look: first, first + block, ..., cap."""
        out = [self.first]
        while out[-1] < self.cap:
            out.append(min(out[-1] + self.block, self.cap))
        return tuple(out)

    @property
    def level(self) -> float:
        """Each look's interval level, 1 - ALPHA / K (Bonferroni over the K looks)."""
        return 1.0 - ALPHA / len(self.sizes)


def check_looks(first: int, block: int, cap: int) -> None:
    """Positive integers with ``first <= cap``, else a ConfigError naming the setting."""
    for name, value in (("users", first), ("block", block), ("cap", cap)):
        if int(value) != value or value < 1:
            raise ConfigError(f"{name} must be a positive integer, got {value!r}")
    if first > cap:
        raise ConfigError(f"users (the first look, {first}) must not exceed cap ({cap})")


def block_seed(seed: int, block: int) -> int:
    """Look ``block``'s new users' seed: ``seed`` for the first, else ``SeedSequence([seed, block])``'s."""
    if block == 0:
        return int(seed)
    return int(np.random.SeedSequence([int(seed), int(block)]).generate_state(1)[0])


def block_users(looks: Looks, block: int) -> tuple[int, int]:
    """(first user index, number of users) of look ``block``'s new users."""
    start = looks.sizes[block - 1] if block else 0
    return start, looks.sizes[block] - start


def bootstrap_frames(frame: pd.DataFrame, n_boot: int, seed: int, unit: str = USER) -> Iterator[pd.DataFrame]:
    """``n_boot`` resamples of ``frame``'s users (``unit``) with replacement, each draw a new id."""
    codes, units = pd.factorize(frame[unit], sort=True)
    order = np.argsort(codes, kind="stable")
    starts = np.searchsorted(codes[order], np.arange(len(units) + 1))
    rng = np.random.default_rng(seed)
    for _ in range(n_boot):
        picks = rng.integers(0, len(units), len(units))
        rows = np.concatenate([order[starts[p] : starts[p + 1]] for p in picks])
        sample = frame.iloc[rows].copy()
        sample[unit] = np.repeat(np.arange(len(picks)), starts[picks + 1] - starts[picks])
        yield sample


def group_means(
    frame: pd.DataFrame, keys: list[str], metric: str, counts: np.ndarray, unit: str = USER
) -> dict[tuple[Any, ...], np.ndarray]:
    """Group label (tuple of ``keys``' values) -> mean of ``metric`` in each resample (R,), without
    building them: sum_u c_u S_ug / sum_u c_u N_ug (S, N: each user's sum and count in the group)."""
    users = pd.factorize(frame[unit], sort=True)[0]
    grouped = frame.groupby(keys, sort=True)
    groups = grouped.ngroup().to_numpy()
    labels = list(grouped.groups)
    n_users, n_groups = counts.shape[1], len(labels)
    sums, sizes = np.zeros((n_users, n_groups)), np.zeros((n_users, n_groups))
    np.add.at(sums, (users, groups), frame[metric].to_numpy(dtype=float))
    np.add.at(sizes, (users, groups), 1.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        means = (counts @ sums) / (counts @ sizes)
    return {(k if isinstance(k, tuple) else (k,)): means[:, i] for i, k in enumerate(labels)}


# a figure's vectorized bootstrap: (frame, counts) -> claim id -> number name -> values (R,)
BootValues = Callable[[pd.DataFrame, np.ndarray], dict[str, dict[str, np.ndarray]]]


def min_resamples(level: float) -> int:
    """The fewest resamples a settled verdict at ``level`` rests on: :data:`MIN_TAIL` beyond each bound."""
    if not 0.0 < level < 1.0:
        raise ConfigError(f"level must lie in (0, 1), got {level!r}")
    return math.ceil(round(MIN_TAIL / ((1.0 - level) / 2.0), 6))


def shortfall(
    n_users: int, n_boot: int | None, level: float, min_users: int = MIN_USERS, unit: str = "users"
) -> str:
    """Why a verdict on ``n_users`` (``unit``) and ``n_boot`` resamples (None: a t interval) at
    ``level`` cannot be settled ("it rests on 4 users, fewer than the 60 ..."); "" if it can."""
    parts = []
    if n_users < min_users:
        parts.append(f"on {n_users} {unit}, fewer than the {min_users} a settled verdict needs")
    least = min_resamples(level)
    if n_boot is not None and n_boot < least:
        parts.append(f"on {n_boot} resamples, fewer than the {least} a {100 * level:.4g}% interval needs")
    return ("it rests " + ", and ".join(parts)) if parts else ""


def _fmt(x: float) -> str:
    return f"{x:.3g}" if math.isfinite(x) else "nan"


def assess(
    evaluate: Evaluate,
    frame: pd.DataFrame,
    n_boot: int = N_BOOT,
    seed: int = 0,
    level: float = 0.95,
    fast: BootValues | None = None,
    min_users: int = MIN_USERS,
) -> list[Claim]:
    """The claims of ``evaluate`` on ``frame``, with intervals at ``level`` over resamples of users,
    ``undecided`` where one straddles a threshold or the evidence falls short (:func:`shortfall`); ``fast``
    (:func:`group_means`) gives the same numbers on the same resamples, else ``evaluate`` runs on each."""
    n_users = int(frame[USER].nunique())
    short = shortfall(n_users, n_boot, level, min_users)  # a ConfigError for a level outside (0, 1)
    point = evaluate(frame)
    samples: dict[str, dict[str, list[float]]] = {c.id: {k: [] for k in c.values} for c in point}
    if fast is not None:
        rng = np.random.default_rng(seed)  # bootstrap_frames' resamples, as how often each user is drawn
        counts = [np.bincount(rng.integers(0, n_users, n_users), minlength=n_users) for _ in range(n_boot)]
        boot = fast(frame, np.stack(counts))
        samples = {
            cid: {k: [float(x) for x in boot.get(cid, {}).get(k, [])] for k in s}
            for cid, s in samples.items()
        }
    else:
        for sample in bootstrap_frames(frame, n_boot, seed):
            for c in evaluate(sample):
                for k, v in c.values.items():
                    if c.id in samples and k in samples[c.id]:
                        samples[c.id][k].append(v)
    return [_judged(c, samples[c.id], level, n_users, short) for c in point]


def _judged(c: Claim, samples: dict[str, list[float]], level: float, n_users: int, short: str = "") -> Claim:
    r = c.judged_by
    if r is None:
        raise ConfigError(f"no rule for claim {c.id!r}; give it one (Claim.rule)")
    if c.reproduced != r.verdict(c.values):
        raise ConfigError(f"{c.id}: verdict {c.reproduced!r} is not its rule's at {dict(c.values)}")
    tail = 100.0 * (1.0 - level) / 2.0
    intervals: dict[str, tuple[float, float]] = {}
    for q in r.quantities:
        boot = np.asarray(samples[q.name], dtype=float)
        boot = boot[np.isfinite(boot)]
        bounds = np.percentile(boot, [tail, 100.0 - tail]) if len(boot) else np.full(2, np.nan)
        intervals[q.name] = (float(bounds[0]), float(bounds[1]))
    settled = r.settled(intervals) and not short
    text = "; ".join(
        f"{k} = {_fmt(c.values[k])} [{_fmt(lo)}, {_fmt(hi)}]" for k, (lo, hi) in intervals.items()
    )
    lead = f"{n_users} users per point; {100 * level:.4g}% intervals: {text}. "
    if not settled:
        why = short or "; ".join(r.straddled(intervals)) or "an interval is unknown"
        lead += f"Undecided: {why}; the point estimates read {c.reproduced!r}. "
    head = r.quantities[0].name  # the headline number: Claim.value and its interval
    (low, high), verdict = intervals[head], c.reproduced if settled else UNDECIDED
    out = dataclasses.replace(c, value=float(c.values[head]), ci_low=low, ci_high=high, n_users=n_users)
    note = lead + f"Rule: {r.text}. " + c.note
    return dataclasses.replace(
        out, settled=settled, intervals=intervals, level=level, reproduced=verdict, note=note
    )


def with_reading(claim_id: str, reading: str) -> str:
    """``<id>@<reading>``, or ``<id>@<readings>+<reading>`` for an id that names a reading already."""
    return f"{claim_id}{'+' if '@' in claim_id else '@'}{reading}"


def _words(c: Claim) -> str:
    said = criteria(c)
    return words_text(said["effect"], said["number"], c.stated)


def member_frame(frame: pd.DataFrame, assistance: str) -> pd.DataFrame:
    """The rows of member ``assistance``, with the unassisted (LA) rows of the users it ran (later
    looks run the headline member only), so the member is compared on paired users."""
    own = frame["assistance"] == assistance
    shared = frame["assistance"] == NO_ASSISTANCE
    if own.any() and USER in frame:
        shared &= frame[USER].isin(frame.loc[own, USER].unique())
    return frame[own | shared]


@dataclasses.dataclass(frozen=True)
class Sequential:
    """The outcome of :func:`sequential`: every look's rows, the claims, and each look's headline verdicts."""

    frame: pd.DataFrame
    claims: list[Claim]
    looks: pd.DataFrame


def sequential(
    run_block: Callable[[int, tuple[str, ...]], pd.DataFrame],
    evaluate: Evaluate,
    assistance: tuple[str, ...],
    default: str,
    looks: Looks = Looks(),
    n_boot: int = N_BOOT,
    seed: int = 0,
    fast: BootValues | None = None,
    min_users: int = MIN_USERS,
) -> Sequential:
    """Add users in blocks until every headline verdict is settled or the cap is reached: the first look runs
    every member of ``assistance``, later ones only ``default``, the headline member; ``run_block(look,
    members)`` returns the rows of that look's new users (:func:`block_users`), LA rows labelled ``none``."""
    if default not in assistance:
        raise ConfigError(f"the headline member {default!r} is not among the members {assistance}")
    judge = functools.partial(
        assess, evaluate, n_boot=n_boot, seed=seed, level=looks.level, fast=fast, min_users=min_users
    )
    frame = run_block(0, assistance).assign(look=0)
    log = []
    for look, size in enumerate(looks.sizes):
        if look > 0:
            frame = pd.concat([frame, run_block(look, (default,)).assign(look=look)], ignore_index=True)
        head = judge(member_frame(frame, default))
        when = {"look": look, "users": size}
        log += [when | {"id": c.id, "reproduced": c.reproduced, "settled": c.settled} for c in head]
        # the stopping rule reads the headline claims only, never a figure's own readings
        if all(c.settled for c in head if "@" not in c.id):
            break
    others = {m: judge(member_frame(frame[frame.look == 0], m)) for m in assistance if m != default}
    rows: list[Claim] = []
    for i, c in enumerate(head):
        flips = [f"{m} ({_words(o[i])})" for m, o in others.items() if _words(o[i]) != _words(c)]
        same = "Every other member gives the same words. " if others else ""
        where = f"Members with other words (at {looks.first} users): {'; '.join(flips)}. " if flips else same
        at = f"look {look + 1} of {len(looks.sizes)}"
        cap = f", the cap ({looks.cap} users)" if look + 1 == len(looks.sizes) else ""
        stop = f"The effect is settled at {at}. " if c.settled else f"The effect is undecided at {at}{cap}. "
        rows.append(dataclasses.replace(c, assistance=default, note=stop + where + c.note))
    for m, claims in others.items():
        rows += [dataclasses.replace(c, id=with_reading(c.id, m), assistance=m) for c in claims]
    return Sequential(frame=frame, claims=rows, looks=pd.DataFrame(log))
