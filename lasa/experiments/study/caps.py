"""The eating study against the belief's cap (notebook 11): notebook 10's headline recipe at each cap of
``cap_sweep`` run with the belief at that cap (:func:`run`; without a cap, ``@uncapped``:
:func:`uncapped_claims`); :func:`sweep` gathers completion and H1-H3's effects per cap; :func:`plot`."""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Mapping
from typing import Any

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import seaborn as sns
from matplotlib.figure import Figure

from lasa.base.conditions import CONDITIONS
from lasa.base.config import ControlConfig
from lasa.base.paths import Paths
from lasa.evidence import latent_property, stats
from lasa.evidence.claims import Claim
from lasa.evidence.decision import effect_word
from lasa.evidence.hypotheses import Result, for_member
from lasa.experiments.eating_task import cap_decoder_name, cap_label
from lasa.experiments.study import analysis, claims
from lasa.experiments.study import run as study
from lasa.experiments.study.analysis import pct
from lasa.method.decoder import ActionDecoder
from lasa.pipeline.scaleout import run_jobs
from lasa.world.eating import EatingTask
from lasa.world.record import Episodes

NAME = "study_belief_cap"
# one row per (cap, what): a condition's completion, a claim's measured effect, or the property; cap: its
# value or "none"; word: a claim's effect word, or whether the decoder meets the property rule
_KEYS = ("robot", "cap", "order", "decoder", "n", "kind", "item")
COLUMNS: tuple[str, ...] = (*_KEYS, "value", "low", "high", "p", "word", "settled", "text")


@dataclasses.dataclass(frozen=True)
class CapRun:
    """The study at one cap: its decoder's name, its episodes and tables (:func:`.run.run`)."""

    cap: float | None
    decoder: str
    episodes: Episodes
    frames: dict[str, pd.DataFrame]


def load_decoders(
    paths: Paths, robot: str, headline: str, caps: tuple[float | None, ...]
) -> dict[float | None, tuple[str, ActionDecoder]]:
    """Notebook 10's decoder of the headline's recipe at each cap: ``(name, decoder)`` per cap."""
    names = {cap: cap_decoder_name(headline, cap) for cap in caps}
    return {cap: (name, study.load_decoders(paths, robot, [name], cap)[name]) for cap, name in names.items()}


_Shared = tuple[EatingTask, ControlConfig, study.Config, str]  # and the headline participant model


def _run_cap(shared: _Shared, job: tuple[float | None, str, ActionDecoder, int]) -> CapRun:
    """The study at one cap: the headline model and member, every condition, ``n`` participants."""
    (task, control, config, model), (cap, name, decoder, n) = shared, job
    session = dataclasses.replace(config.session, assistance=config.session.assistance[:1])
    with warnings.catch_warnings():  # a derived run's cohort: the notebook's own config has warned
        warnings.simplefilter("ignore", UserWarning)
        one = dataclasses.replace(
            config, participants=n, participant_models=(model,), session=session, video_participant=0, jobs=1
        )
    control = dataclasses.replace(control, belief_cap=cap)
    episodes, frames = study.run(task, {name: decoder}, control, one, progress=False)
    return CapRun(cap, name, episodes[model][name], frames)


def run(
    task: EatingTask,
    control: ControlConfig,
    decoders: Mapping[float | None, tuple[str, ActionDecoder]],
    config: study.Config,
    model: str,
    progress: bool = True,
) -> dict[float | None, CapRun]:
    """The study with each cap's decoder and belief: ``config.sweep_n`` participants, without a cap all."""
    jobs = [
        (cap, name, decoder, config.participants if cap is None else config.sweep_n)
        for cap, (name, decoder) in decoders.items()
    ]
    jobs.sort(key=lambda job: -job[3])  # the largest first: the workers finish together
    ran = run_jobs(
        _run_cap,
        jobs,
        n_jobs=config.jobs,
        progress=progress,
        desc="study at each cap",
        shared=(task, control, config, model),
    )
    return {r.cap: r for r in ran}


def uncapped_claims(
    runs: Mapping[float | None, CapRun], prop: pd.DataFrame, config: study.Config, horizon: float
) -> list[Claim]:
    """The claims rows of the study without the cap, ``study.<claim>@uncapped[+...]``, unflipped."""
    if None not in runs:
        return []
    r = runs[None]
    return _claims(r.frames, r.decoder, config.participants, config, prop, horizon, cap_label(None))[0]


def _claims(
    frames: dict[str, pd.DataFrame],
    decoder: str,
    n: int,
    config: study.Config,
    prop: pd.DataFrame,
    horizon: float,
    belief: str | None = None,
) -> tuple[list[Claim], dict[tuple, dict[str, Any]]]:
    """One run's :func:`.claims.claims` (unflipped), not testable where its decoder misses the property."""
    reason = claims.untestable_reason(prop[prop.decoder == decoder])
    head = config.session.assistance[:1]
    return claims.claims(
        frames, head, n, (decoder,), horizon=horizon, untestable=reason, belief=belief, flips=False
    )


def label(cap: float | None) -> str:
    """A cap as the sweep's ``cap`` column writes it: ``0.99``, or ``none``."""
    return "none" if cap is None else f"{cap:g}"


def _cap_rows(
    cap: float | None,
    decoder: str,
    time: pd.DataFrame,
    by_key: Mapping[str, Claim],
    result: Result,
    prop: pd.DataFrame,
) -> list[dict[str, object]]:
    """One cap's sweep rows: completion per condition, the claims' (by key) words, effects, the property."""
    n = int(time.participant.nunique())
    base = {"robot": "panda", "cap": label(cap), "order": 0, "decoder": decoder, "n": n}
    blank = base | {"low": np.nan, "high": np.nan, "p": np.nan, "word": "", "settled": False, "text": ""}
    done = time.groupby("condition").completed.mean()
    out = [blank | {"kind": "completion", "item": c, "value": float(done.get(c, np.nan))} for c in CONDITIONS]
    within, phases, total = result["h1_within"], result["h2_phases"], result["h3_total"]
    diff = float(within["mean_sa"] - within["mean_no_sa"])
    h1 = (diff, float(within["ci_low"]), float(within["ci_high"]), float(within["p"]))
    mean, low, high, p, pairs = phases["scoop"]
    r = total.set_index("b").loc["R"]
    h2 = f"LA+SA - R+SA = {mean:+.3f}, paired t, {pairs} pairs, p = {p:.3g}"
    h3 = f"LA+SA - R = {r['diff']:+.1f} s [{r.ci_low:+.1f}, {r.ci_high:+.1f}] (restricted means)"
    effects = {
        "h1": (*h1, f"SA - no SA = {diff:+.2f} m s, {stats.format_f(within)}"),
        "h2": (float(mean), float(low), float(high), float(p), h2),
        "h3": (float(r["diff"]), float(r.ci_low), float(r.ci_high), np.nan, h3),
    }
    for key, (value, low, high, p, text) in effects.items():
        row = by_key.get(key)
        word = "" if row is None else effect_word(row.reproduced)
        said = {"word": word, "settled": row is not None and bool(row.settled)}
        effect = {"value": value, "low": low, "high": high, "p": p, "text": text}
        out.append(base | {"kind": "claim", "item": key} | effect | said)
    mine = prop[prop.decoder == decoder]
    meets = bool(latent_property.holds(mine).any()) if len(mine) else False
    value = float(mine.has_property.sum()) if len(mine) else np.nan
    word = "meets the rule" if meets else "misses the rule"
    out.append(blank | {"kind": "property", "item": "goals with both halves", "value": value, "word": word})
    return out


def sweep(
    runs: Mapping[float | None, CapRun],
    frames: dict[str, pd.DataFrame],
    headline: str,
    model: str,
    prop: pd.DataFrame,
    caps_prop: pd.DataFrame,
    config: study.Config,
    horizon: float,
) -> pd.DataFrame:
    """The sweep's rows (:data:`COLUMNS`), caps in increasing order, no cap last: the study's own from the
    headline run (``frames``, ``prop``), every other from its run (``caps_prop``)."""
    head, n = config.session.assistance[0], config.sweep_n
    mine = {k: for_member(f, head, n, decoder=headline, model=model) for k, f in frames.items()}
    runs_by_cap = {
        config.belief_cap: (headline, mine, prop),
        **{c: (r.decoder, r.frames, caps_prop) for c, r in runs.items()},
    }
    ids = {claims.claim_id(h, 0, head, n > study.PAPER_N): h for h in claims.PAPER_KEYS}
    paper_n = max(n, study.PAPER_N)
    parts: dict[float | None, list[dict[str, object]]] = {}
    for cap, (decoder, tables, table) in runs_by_cap.items():
        first = {k: f[f.participant < n] for k, f in tables.items()}
        rows, analyses = _claims(first, decoder, n, config, table, horizon)
        said = {ids[r.id]: r for r in rows if r.id in ids}
        parts[cap] = _cap_rows(cap, decoder, first["time"], said, analyses[(head, paper_n)], table)
    ordered = sorted(parts, key=lambda c: np.inf if c is None else c)
    out = [dict(row, order=i) for i, c in enumerate(ordered) for row in parts[c]]
    return pd.DataFrame(out, columns=list(COLUMNS))


def stuck(
    task: EatingTask,
    runs: Mapping[float | None, CapRun],
    decoders: Mapping[float | None, tuple[str, ActionDecoder]],
    config: study.Config,
    model: str,
    cap: float | None = None,
) -> pd.DataFrame:
    """Where the unfinished LA episodes of the run at ``cap`` stopped (:func:`.analysis.stuck_episodes`)."""
    r = runs[cap]
    episodes = {model: {r.decoder: r.episodes}}
    return analysis.stuck_episodes(task, episodes, {r.decoder: decoders[cap][1]}, config, [model])


_EFFECTS = {  # how each claim's measured effect reads, its unit and format; its panel's title
    "h1": ("SA − no SA Goal Error", " m s", "{:+.2f}", "H1: SA - no SA, Goal Error [m s]"),
    "h2": ("LA+SA − R+SA scoop alignment", "", "{:+.3f}", "H2: LA+SA - R+SA, scoop alignment"),
    "h3": ("LA+SA − R restricted mean time", " s", "{:+.1f}", "H3: LA+SA - R, restricted mean time [s]"),
}


def plot(frame: pd.DataFrame, study_cap: str = "0.99") -> Figure:
    """Completion per arm, and H1-H3's measured effects with their 95% intervals and words, per cap."""
    sns.set_theme(style="whitegrid")
    caps = frame.drop_duplicates("cap").sort_values("order")
    prop = frame[frame.kind == "property"].set_index("cap")
    ticks = [f"{c}\n{'✓' if prop.loc[c, 'word'] == 'meets the rule' else ''}" for c in caps.cap]
    x = np.arange(len(caps))
    fig, axes = plt.subplots(1, 4, figsize=(17, 4.4))
    done = frame[frame.kind == "completion"]
    for k, cond in enumerate(CONDITIONS):
        part = done[done["item"] == cond].set_index("cap").reindex(caps.cap)
        style = "--" if cond.endswith("+SA") else "-"
        axes[0].plot(x, 100 * part.value.to_numpy(), style, marker="os^v"[k], label=cond, alpha=0.85)
    axes[0].set(ylabel="episodes finished [%]", ylim=(-5, 105), title="completion per arm")
    axes[0].legend(fontsize=8, loc="center left")
    said = frame[frame.kind == "claim"]
    for ax, key in zip(axes[1:], claims.PAPER_KEYS, strict=True):
        part = said[said["item"] == key].set_index("cap").reindex(caps.cap)
        value, low, high = (part[c].to_numpy(dtype=float) for c in ("value", "low", "high"))
        ok = np.isfinite(low) & np.isfinite(high)
        err = [value[ok] - low[ok], high[ok] - value[ok]]
        ax.errorbar(x[ok], value[ok], yerr=err, fmt="none", color="0.4")
        settled = part.settled.fillna(False).astype(bool).to_numpy()
        ax.scatter(x[settled], value[settled], color="C3", zorder=3, label="settled")
        ax.scatter(
            x[~settled], value[~settled], facecolor="white", edgecolor="C3", zorder=3, label="not settled"
        )
        ax.axhline(0.0, color="0.3", lw=0.8)
        ax.set_title(_EFFECTS[key][3])
        for i, word in enumerate(part.word.fillna("")):
            if np.isfinite(value[i]):
                ax.annotate(word, (x[i], value[i]), textcoords="offset points", xytext=(6, 4), fontsize=6.5)
    axes[1].legend(fontsize=8)
    fig.supxlabel("belief cap (bold: the study's; ✓: the cap's decoder meets the property rule)", fontsize=10)
    for ax in axes:
        ax.set_xticks(x, ticks)
        ax.set_xlim(-0.4, len(x) - 0.4)
        for label in ax.get_xticklabels():
            if label.get_text().split("\n")[0] == study_cap:
                label.set_fontweight("bold")
    n = int(said.n.min()) if len(said) else 0
    fig.suptitle(
        f"The eating study against the belief's cap: the headline's recipe trained and run at each cap "
        f"({n} participants, headline participant model and SA)",
        fontsize=11,
    )
    fig.tight_layout()
    return fig


def _effect(row: pd.Series) -> str:
    """A claim's measured effect, 95% interval and word: ``H1 (...) −2.04 m s [−2.80, −1.27]: *word*``."""
    name, unit, fmt, _ = _EFFECTS[str(row["item"])]
    if not np.isfinite(row.value):
        return f"{str(row['item']).upper()} ({name}) not measured: *{row.word}*"
    span = f" [{fmt.format(row.low)}, {fmt.format(row.high)}]" if np.isfinite(row.low) else ""
    text = f"{fmt.format(row.value)}{unit}{span}".replace("-", "−")
    return f"{str(row['item']).upper()} ({name}) {text}: *{row.word}*"


def cap_sentence(frame: pd.DataFrame, cap: str) -> str:
    """What the study measured at one cap of the sweep: completion per arm, then H1-H3 with their words."""
    rows = frame[frame.cap.astype(str) == cap]
    if rows.empty:
        raise ValueError(f"the sweep has no cap {cap!r}; it has {sorted(set(frame.cap.astype(str)))}")
    done = rows[rows.kind == "completion"].set_index("item").value
    finish = ", ".join(f"{c} {pct(done[c])}" for c in CONDITIONS if c in done.index)
    said = rows[rows.kind == "claim"].set_index("item", drop=False)
    effects = "; ".join(_effect(said.loc[c]) for c in claims.PAPER_KEYS if c in said.index)
    n, decoder = int(rows.n.iloc[0]), rows.decoder.iloc[0]
    return f"with `{decoder}` and {n} participants, episodes finished: {finish}. {effects}."


def _caps(caps: list[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    return caps[0] if len(caps) == 1 else f"{', '.join(caps[:-1])} and {caps[-1]}"


def _by_cap(frame: pd.DataFrame, kind: str, column: str, item: str | None = None) -> pd.Series:
    """One kind's (and item's) ``column`` per cap, indexed by the cap as text."""
    rows = frame[(frame.kind == kind) & ((frame["item"] == item) if item else True)]
    return pd.Series(rows[column].to_numpy(), index=rows.cap.astype(str).to_numpy())


def across_caps(frame: pd.DataFrame) -> str:
    """How H1's sign, LA's completion and the property move with the cap, in one sentence."""
    caps = list(dict.fromkeys(frame.sort_values("order").cap.astype(str)))
    h1 = _by_cap(frame, "claim", "value", "h1")
    signs = {
        "lowers Goal Error": [c for c in caps if c in h1.index and h1[c] < 0],
        "raises it": [c for c in caps if c in h1.index and h1[c] >= 0],
    }
    parts = [f"SA {what} at cap {_caps(at)}" for what, at in signs.items() if at]
    la = _by_cap(frame, "completion", "value", "LA")
    parts.append("LA finishes " + ", ".join(f"{pct(la[c])} at {c}" for c in caps if c in la.index))
    prop = _by_cap(frame, "property", "word")
    misses = [c for c in caps if c in prop.index and prop[c] != "meets the rule"]
    meets = f"at every cap but {_caps(misses)}" if misses else "at every cap"
    meets = "at no cap" if len(misses) == len(prop) else meets
    return f"{'; '.join(parts)}. The recipe's decoder meets the property rule {meets}."


def findings(frame: pd.DataFrame, study_cap: str) -> str:
    """The sweep in Markdown bullets: the study's cap (``study_cap``: :func:`label`'s), no cap, every cap."""
    caps = set(frame.cap.astype(str))
    out = [f"- **At the study's cap ({study_cap})**, {cap_sentence(frame, study_cap)}"]
    if "none" in caps and study_cap != "none":
        uncapped = cap_sentence(frame, "none")
        out.append(f"- **Without the cap** (the recipe trained and run uncapped), {uncapped}")
    out.append(f"- **Against the cap** (the figure above): {across_caps(frame)}")
    return "\n".join(out)
