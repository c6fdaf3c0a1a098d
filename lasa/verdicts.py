"""Verdicts with their uncertainty: a bootstrap interval, agreement across draws, one row per reading.

A claim's verdict is a rule applied to the means of a sweep of simulated users, so it
inherits their randomness. Three things make it a result rather than a draw:

1. *An interval.* Each claim names the number its verdict rests on (``Claim.value``);
   :func:`assess` resamples the users with replacement (all rows of a user together, so
   the pairing of methods on the same user survives) and recomputes it, giving a
   percentile 95% interval.
2. *Agreement across draws.* A sweep holds ``n_draws`` independent draws of users (the
   frame's ``draw`` column; each draw is a complete sweep of its own). The verdict is
   recomputed on each draw alone, and ``seeds_agree`` says how many agree with the
   verdict of all draws pooled (for example ``5/5``).
3. *Every reading.* A sweep run under every member of the shared-autonomy family
   (:mod:`lasa.assistance`) gives one row per member, ``<id>@<member>``, and a headline
   row ``<id>`` under the default member whose note lists every member's verdict, so a
   reader sees at once whether a verdict is about the paper or about one convention.

``LA`` rows carry ``assistance == "none"`` (alpha = 0: no assistance acts) and are shared
by every member's comparison.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator

import numpy as np
import pandas as pd

from lasa.claims import Claim
from lasa.errors import ConfigError

__all__ = ["NO_ASSISTANCE", "N_BOOT", "assess", "by_member", "member_frame", "member_of", "bootstrap_frames"]

NO_ASSISTANCE = "none"  # the assistance label of rows without assistance (LA, alpha = 0)
N_BOOT = 400  # bootstrap resamples per interval [-]

Evaluate = Callable[[pd.DataFrame], list[Claim]]


def bootstrap_frames(
    frame: pd.DataFrame, n_boot: int, seed: int, unit: str = "seed"
) -> Iterator[pd.DataFrame]:
    """``n_boot`` resamples of ``frame``, drawing its users (``unit``) with replacement.

    A user drawn twice appears twice, under two new ids, so rules that average per user
    (``groupby(unit)``) count it twice instead of merging it.
    """
    codes, units = pd.factorize(frame[unit], sort=True)
    order = np.argsort(codes, kind="stable")
    starts = np.searchsorted(codes[order], np.arange(len(units) + 1))
    rng = np.random.default_rng(seed)
    for _ in range(n_boot):
        picks = rng.integers(0, len(units), len(units))
        rows = np.concatenate([order[starts[p] : starts[p + 1]] for p in picks])
        sizes = starts[picks + 1] - starts[picks]
        sample = frame.iloc[rows].copy()
        sample[unit] = np.repeat(np.arange(len(picks)), sizes)
        yield sample


def assess(
    evaluate: Evaluate, frame: pd.DataFrame, n_boot: int = N_BOOT, seed: int = 0, unit: str = "seed"
) -> list[Claim]:
    """Claims of ``evaluate`` on ``frame``, with their interval and their agreement across draws.

    Args:
        evaluate: A figure's rules: frame -> claims (each with its ``value``).
        frame: Every draw's rows; a ``draw`` column numbers the draws (one draw if absent).
        n_boot: Bootstrap resamples.
        seed: Seed of the resampling.
        unit: The column naming a user: the resampled unit.

    Returns:
        ``evaluate(frame)``'s claims with ``ci_low``, ``ci_high`` and ``seeds_agree`` set.
    """
    headline = evaluate(frame)
    draws = sorted(frame["draw"].unique()) if "draw" in frame else [0]
    per_draw = (
        [{c.id: c.reproduced for c in evaluate(frame[frame["draw"] == d])} for d in draws]
        if "draw" in frame
        else [{c.id: c.reproduced for c in headline}]
    )
    values: dict[str, list[float]] = {c.id: [] for c in headline}
    for sample in bootstrap_frames(frame, n_boot, seed, unit):
        for c in evaluate(sample):
            if c.id in values:
                values[c.id].append(c.value)
    out = []
    for c in headline:
        v = np.asarray(values[c.id], dtype=float)
        v = v[np.isfinite(v)]
        low, high = np.percentile(v, [2.5, 97.5]) if len(v) else (np.nan, np.nan)
        agree = sum(d.get(c.id) == c.reproduced for d in per_draw)
        out.append(
            dataclasses.replace(
                c, ci_low=float(low), ci_high=float(high), seeds_agree=f"{agree}/{len(per_draw)}"
            )
        )
    return out


def member_of(frame: pd.DataFrame) -> str:
    """The assistance member of a one-member frame (``none`` if it holds unassisted rows only)."""
    names = (
        [m for m in dict.fromkeys(frame["assistance"]) if m != NO_ASSISTANCE] if "assistance" in frame else []
    )
    if len(names) > 1:
        raise ConfigError(f"the frame mixes assistance members {names}; select one (member_frame)")
    return names[0] if names else NO_ASSISTANCE


def member_frame(frame: pd.DataFrame, member: str) -> pd.DataFrame:
    """The rows of one assistance member, with the unassisted rows (LA) every member shares."""
    return frame[frame["assistance"].isin([member, NO_ASSISTANCE])]


def by_member(
    evaluate: Evaluate, frame: pd.DataFrame, default: str, n_boot: int = N_BOOT, seed: int = 0
) -> list[Claim]:
    """A headline row per claim under ``default``, and a labelled row per member in ``frame``.

    Args:
        evaluate: A figure's rules (see :func:`assess`).
        frame: Rows of every member (``assistance``), LA rows labelled ``none``.
        default: The headline member.
        n_boot: Bootstrap resamples per row.
        seed: Seed of the resampling.

    Raises:
        ConfigError: if the default member has no rows.
    """
    members = [m for m in dict.fromkeys(frame["assistance"]) if m != NO_ASSISTANCE]
    if default not in members:
        raise ConfigError(f"the headline member {default!r} has no rows; members present: {members}")
    rows = {m: assess(evaluate, member_frame(frame, m), n_boot, seed) for m in members}
    out: list[Claim] = []
    for i, head in enumerate(rows[default]):
        summary = ", ".join(f"{m} {rows[m][i].reproduced} ({rows[m][i].seeds_agree})" for m in members)
        same = len({rows[m][i].reproduced for m in members}) == 1
        lead = (
            f"Headline under the default reading ({default}). "
            + ("Same verdict under every reading: " if same else "The verdict depends on the reading: ")
            + summary
            + ". "
        )
        out.append(dataclasses.replace(head, assistance=default, note=lead + head.note))
        for m in members:
            c = rows[m][i]
            out.append(dataclasses.replace(c, id=f"{c.id}@{m}", assistance=m))
    return out
