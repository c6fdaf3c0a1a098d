"""The claims table: for each claim of the paper, did it reproduce?

Each figure notebook evaluates its claims from the data behind its figure and writes
its rows into ``figures/claims.csv`` (and the same table as ``figures/claims.md``, which
the README's table is generated from). Each row has a stable ``id`` (``sim1.final_error``),
so a claim can be reworded without leaving its old row behind: a figure's run replaces
every row of that (figure, robot) and leaves the others. Rows are unique by (id, robot).
``assistance`` names the reading of shared autonomy the row was measured under
(``point``: Eq. M2 towards one pose per goal). Each claim has a headline row, ``<figure>.<name>``,
measured under the default reading, and one row per member of the family,
``<figure>.<name>@<member>`` (:mod:`lasa.evidence.verdicts`). ``ci_low`` and ``ci_high`` bound the
number the verdict rests on (a 95% interval over users or participants: a bootstrap, or for the
study's H1 and H2 a paired t interval), and ``n_users`` says how many users or participants it rests on. A
:class:`Claim` holds its rule's reading, ``yes``, ``partly`` or ``no`` (``undecided`` when an
interval straddles a threshold; ``not testable`` when the claim's test cannot run on the data,
with the reason in ``measured`` or ``note``). Each row carries two words (Open Science
Collaboration, 2015): ``effect``, the claim's shape as the rule reads it
(:data:`lasa.evidence.decision.WORDS`), and ``number``, for each number the paper states whether
it lies in our interval give or take the rule's tolerance (``in``/``out``/``undecided``, joined
by ``; ``; ``n/a`` where the paper states none). ``reproduced`` keeps both in one word for older
readers (:func:`lasa.evidence.decision.word`), and ``settled`` says whether the intervals decide
the effect. Every sentence of a row's ``note`` is generated from the row's own numbers and words
(:func:`note_lead`), never written by hand; a claim that does not reproduce is a result,
reported with its measured value.

Beside the table, ``claim_values.csv`` holds the numbers as data (:mod:`lasa.evidence.values`,
:func:`value_rows`): every quantity a rule reads with its value, interval, level and N, and the
study's facts. The verdict table (:func:`render_verdicts`, ``figures/verdicts.md``), the README's
summary (:func:`render_summary`) and the list of readings that flip a claim (:func:`render_flips`,
the head of ``claims.md``) are written from the two files, never from a note's prose.
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import pandas as pd

from lasa.base import journal
from lasa.base.errors import ConfigError
from lasa.base.io import locked, sync_between, write_csv, write_text
from lasa.evidence.decision import (
    CENSORED,
    NOT_APPLICABLE,
    NOT_TESTABLE,
    NUMBER_WORDS,
    UNDECIDED,
    WORDS,
    PaperNumber,
    effect_word,
    word,
)
from lasa.evidence.findings import completion_text, finding, on_robots, short_arms, study_effect
from lasa.evidence.rules import RULES
from lasa.evidence.values import VALUE_COLUMNS, VALUES_NAME, Number, Numbers, Values, read_values, reading_of

__all__ = [
    "fragile_because",
    "fragile_line",
    "Claim",
    "PaperClaim",
    "PAPER_CLAIMS",
    "update_claims",
    "render_markdown",
    "render_verdicts",
    "sync_readme",
    "CLAIM_COLUMNS",
    "README_MARKERS",
    "SHOWN_COLUMNS",
    "claims_frame",
    "SUMMARY_MARKERS",
    "numbers_of",
    "value_rows",
    "paper_numbers_of",
    "stated_elsewhere",
    "effect_text",
    "flips",
    "by_key",
    "render_flips",
    "render_summary",
]

README_MARKERS = (
    "<!-- verdicts:begin (generated from figures/verdicts.md by make figures) -->",
    "<!-- verdicts:end -->",
)
SUMMARY_MARKERS = (
    "<!-- summary:begin (generated from figures/claims.csv by make figures) -->",
    "<!-- summary:end -->",
)

CLAIM_COLUMNS = (
    "id",
    "claim",
    "figure",
    "robot",
    "assistance",
    "paper",
    "measured",
    "ci_low",
    "ci_high",
    "reproduced",
    "settled",
    "paper_in_ci",
    "direction",
    "paper_numbers",
    "effect",
    "number",
    "n_users",
    "fragile",
    "note",
)
VERDICTS = ("yes", "partly", "no", UNDECIDED, NOT_TESTABLE)  # what Claim.reproduced holds
ROBOTS = ("planar5", "panda")  # the verdict table's robot columns, in order


@dataclasses.dataclass(frozen=True)
class Claim:
    """One row of the claims table."""

    id: str  # stable key, "<figure>.<name>": survives a rewording of ``claim``
    claim: str  # the paper's claim, in a sentence
    figure: str  # the figure it belongs to, e.g. "sim1"
    paper: str  # what the paper reports
    measured: str  # what we measured
    reproduced: str  # "yes", "partly", "no"; "undecided" (an interval straddles a threshold); "not testable"
    note: str  # how the verdict was decided, and the likely reason if not "yes"
    robot: str  # the robot it was measured on
    assistance: str = "point"  # the shared-autonomy reading: Eq. M2 towards one pose per goal
    value: float = math.nan  # the number the verdict rests on (``measured`` names it first)
    ci_low: float = math.nan  # bootstrap 95% interval of ``value`` (lasa.evidence.verdicts)
    ci_high: float = math.nan
    settled: bool = False  # every interval clear of its rule's thresholds (lasa.evidence.verdicts)
    n_users: int = 0  # simulated users (or participants) per point the verdict rests on
    values: Mapping[str, float] = dataclasses.field(default_factory=dict)  # the rule's numbers
    # each of the rule's numbers' interval, at the row's level (lasa.evidence.verdicts)
    intervals: Mapping[str, tuple[float, float]] = dataclasses.field(default_factory=dict)
    level: float = math.nan  # the intervals' level (0.9875 under the sims' sequential design)
    # numbers a sentence reads beside the rule's, without an interval: the study's test statistics
    # and each condition's completion (``completion.LA``), keyed as in ``claim_values.csv``
    facts: Mapping[str, float] = dataclasses.field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.id.startswith(f"{self.figure}.") or " " in self.id:
            raise ConfigError(f"claim id must be '<figure>.<name>' without spaces, got {self.id!r}")
        if self.reproduced not in VERDICTS:
            raise ConfigError(f"reproduced must be one of {VERDICTS}, got {self.reproduced!r}")
        if self.reproduced == NOT_TESTABLE and self.settled:
            raise ConfigError(f"{self.id}: a claim that is not testable is never settled")


# what a notebook shows of its claims (claims_frame): the row, its reading, its evidence, its verdict
SHOWN_COLUMNS = ("id", "assistance", "n_users", "measured", "ci_low", "ci_high", "reproduced", "settled")


def claims_frame(claims: Sequence[Claim], assistance: bool = True) -> pd.DataFrame:
    """A notebook's claims, one row each, in the columns of :data:`SHOWN_COLUMNS`.

    Args:
        claims: The claims, in the order to show them.
        assistance: Show the ``assistance`` column (the study's ids name their reading already).
    """
    columns = [c for c in SHOWN_COLUMNS if assistance or c != "assistance"]
    if not claims:
        return pd.DataFrame(columns=columns)
    return pd.DataFrame([c.__dict__ for c in claims])[columns]


def criteria(claim: Claim) -> dict[str, str]:
    """The row's two words and its replication criteria (Open Science Collaboration, 2015).

    Returns:
        ``effect``: the rule's reading in words (:func:`lasa.evidence.decision.effect_word`);
        ``number``: per number the paper states its word (:meth:`PaperNumber.word`), joined by
        ``; ``, ``n/a`` where it states none or the claim is not testable; ``reproduced``: both in
        one word (:func:`lasa.evidence.decision.word`); ``paper_in_ci``: per number
        the paper states, ``yes``/``no`` (its value, give or take the rule's tolerance, inside our
        interval), joined by ``; ``, or ``n/a`` where it states none; ``direction``: ``yes`` if our
        effect's interval lies on the paper's side of no effect, ``no`` if not, ``n/a`` where the
        paper gives no sign or the claim is not testable; ``paper_numbers``: each paper number
        with its own verdict and our value and interval; ``fragile``: ``yes`` if an interval ends
        near a value at which a word changes (:func:`fragile_because`), else ``no``.
    """
    r = RULES.get(claim.id.split("@", 1)[0])
    paper = paper_numbers_of(claim.id, claim.robot)
    testable = claim.reproduced != NOT_TESTABLE
    nan = (math.nan, math.nan)
    found = [(p, claim.intervals.get(p.quantity, nan)) for p in paper] if testable else []
    direction = r.direction if r is not None else None
    return {
        "effect": effect_word(claim.reproduced),
        "number": _numbers_word([p.word(iv) for p, iv in found]),
        "reproduced": word(claim.reproduced, claim.intervals, paper),
        "paper_in_ci": "; ".join(p.inside(iv) for p, iv in found) or "n/a",
        "direction": direction.judge(claim.intervals.get(direction.quantity, nan))
        if direction is not None and testable
        else "n/a",
        "paper_numbers": "; ".join(
            p.describe(iv, float(claim.values.get(p.quantity, math.nan))) for p, iv in found
        ),
        "fragile": "yes" if fragile_because(claim) else "no",
    }


def fragile_because(claim: Claim) -> list[str]:
    """Why the row's words are fragile (:meth:`lasa.evidence.decision.Rule.fragile`); none if they
    are not, or if the claim has no rule or is not testable."""
    r = RULES.get(claim.id.split("@", 1)[0])
    if r is None or claim.reproduced == NOT_TESTABLE:
        return []
    return r.fragile(claim.intervals)


def _numbers_word(words: list[str]) -> str:
    """The ``number`` column: each paper number's word joined by ``; ``; ``n/a`` if none is known."""
    return "; ".join(words) if any(w != NOT_APPLICABLE for w in words) else NOT_APPLICABLE


def paper_numbers_of(claim_id: str, robot: str) -> tuple[PaperNumber, ...]:
    """The numbers the paper states for a claim on ``robot`` (its rule's), none if it has no rule
    or states them for another robot (:attr:`lasa.evidence.decision.PaperNumber.robot`)."""
    r = RULES.get(claim_id.split("@", 1)[0])
    return tuple(p for p in r.paper if p.robot == robot) if r is not None else ()


def stated_elsewhere(claim_id: str, robot: str) -> bool:
    """Whether the paper states numbers for this claim, but for another robot than ``robot``."""
    r = RULES.get(claim_id.split("@", 1)[0])
    return r is not None and bool(r.paper) and not paper_numbers_of(claim_id, robot)


def numbers_of(claim: Claim) -> dict[str, Number]:
    """A claim's numbers as ``claim_values.csv`` holds them (:mod:`lasa.evidence.values`)."""
    nan = (math.nan, math.nan)
    out = {
        k: Number(float(v), *claim.intervals.get(k, nan), level=claim.level, n=claim.n_users)
        for k, v in claim.values.items()
    }
    return out | {k: Number(float(v), n=claim.n_users) for k, v in claim.facts.items()}


def words_text(effect: str, number: str, paper: tuple[PaperNumber, ...]) -> str:
    """``effect undecided; 1.45 out, 1.3 in``: a row's two words, each number named by its value."""
    numbers = number.split("; ")
    if number == NOT_APPLICABLE or len(numbers) != len(paper):
        return f"effect {effect}; number {number}"
    return f"effect {effect}; " + ", ".join(f"{p.value:g} {w}" for p, w in zip(paper, numbers, strict=True))


def note_lead(effect: str, number: str, paper: tuple[PaperNumber, ...]) -> str:
    """The sentence a row's note begins with: its two words, ``Effect reproduced; 0.11 out.``."""
    text = words_text(effect, number, paper)
    return text[0].upper() + text[1:] + ". "


def _row(claim: Claim) -> dict[str, object]:
    """A claim as a table row: the interval to 4 significant digits, empty where unknown.

    Its note begins with the row's two words (:func:`note_lead`).
    """
    row: dict[str, object] = {f.name: getattr(claim, f.name) for f in dataclasses.fields(claim)}
    del row["values"], row["value"], row["intervals"], row["level"], row["facts"]
    row["settled"] = "yes" if claim.settled else "no"
    row.update(criteria(claim))
    lead = note_lead(str(row["effect"]), str(row["number"]), paper_numbers_of(claim.id, claim.robot))
    note = lead + claim.note
    if row["fragile"] == "yes":  # criteria found it so; the note says why
        why = "; ".join(fragile_because(claim))
        note = f"{note.rstrip()} Fragile: {why} (within a fifth of its width)."
    row["note"] = note
    for key in ("ci_low", "ci_high"):
        row[key] = "" if math.isnan(getattr(claim, key)) else f"{getattr(claim, key):.4g}"
    return row


def render_markdown(frame: pd.DataFrame) -> str:
    """``claims.md``: the readings that flip each headline (:func:`render_flips`), then the claims
    table as a GitHub-flavoured Markdown table."""
    return render_flips(frame) + "\n# Every row of claims.csv\n\n" + _markdown_table(frame)


def _markdown_table(frame: pd.DataFrame) -> str:
    """The claims table as a GitHub-flavoured Markdown table."""
    cols = list(CLAIM_COLUMNS)
    lines = ["| " + " | ".join(cols) + " |", "| " + " | ".join("---" for _ in cols) + " |"]
    for _, row in frame.iterrows():
        cells = [str(row[c]).replace("|", "\\|").replace("\n", " ") for c in cols]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def update_claims(path: str | os.PathLike[str], claims: list[Claim]) -> pd.DataFrame:
    """Replace the rows of these claims' (figure, robot) pairs in the CSV at ``path``.

    Every row of a (figure, robot) that ``claims`` covers is dropped first, so a claim
    that a figure no longer makes leaves the table; rows of other figures and robots are
    kept. The ``.md`` twin is rewritten from the result. Runs under the folder lock
    (robots run in parallel). Under a notebook run's write journal (:mod:`lasa.base.journal`), the
    (figure, robot) pairs are recorded, so that a failed run restores its own rows of both CSVs.

    Args:
        path: The claims CSV, e.g. ``figures/claims.csv``; created if missing.
        claims: The rows to write; (id, robot) must be unique among them.

    Returns:
        The whole table after the update, ordered by figure, robot and id.

    Raises:
        ConfigError: if two claims share an (id, robot), or the file has other columns.
    """
    path = Path(path)
    new = pd.DataFrame([_row(c) for c in claims], columns=list(CLAIM_COLUMNS))
    if new.duplicated(["id", "robot"]).any():
        dup = new.loc[new.duplicated(["id", "robot"]), "id"].tolist()
        raise ConfigError(f"claim ids must be unique per robot, repeated: {dup}")
    numbers = pd.DataFrame([v for c in claims for v in value_rows(c)], columns=list(VALUE_COLUMNS))
    with locked(path.parent):
        for table_path, rows in ((path, new), (path.with_name(VALUES_NAME), numbers)):
            journal.note_rows(table_path, rows[["figure", "robot"]], sort=["figure", "robot", "id"])
        table = _replace(path, new, CLAIM_COLUMNS)
        write_csv(path, table)
        write_csv(path.with_name(VALUES_NAME), _replace(path.with_name(VALUES_NAME), numbers, VALUE_COLUMNS))
        write_text(path.with_suffix(".md"), render_markdown(table))
    return table


def _replace(path: Path, new: pd.DataFrame, columns: Sequence[str]) -> pd.DataFrame:
    """The table at ``path`` with the rows of ``new``'s (figure, robot) pairs replaced by ``new``'s.

    Ordered by figure, robot and id (stable: a row's quantities keep their order).

    Raises:
        ConfigError: if the file has other columns than ``columns``.
    """
    if not path.exists():
        table = new
    else:
        old = pd.read_csv(path, dtype=str, keep_default_na=False)
        if list(old.columns) != list(columns):
            raise ConfigError(
                f"{path} has columns {list(old.columns)}, expected {list(columns)}; "
                "delete it and re-run the figure notebooks"
            )
        covered = pd.MultiIndex.from_frame(new[["figure", "robot"]].drop_duplicates())
        keep = ~pd.MultiIndex.from_frame(old[["figure", "robot"]]).isin(covered)
        table = pd.concat([old.loc[keep], new], ignore_index=True)
    return table.sort_values(["figure", "robot", "id"], kind="stable").reset_index(drop=True)


def _number_text(x: float) -> str:
    """A number as claim_values.csv writes it: 6 significant digits, empty if unknown."""
    return f"{x:.6g}" if math.isfinite(x) else ""


def value_rows(claim: Claim) -> list[dict[str, object]]:
    """The claim's rows of ``claim_values.csv`` (:mod:`lasa.evidence.values`): each rule quantity
    with its value and interval at the claim's level, then each fact."""
    head = {"id": claim.id, "robot": claim.robot, "figure": claim.figure, "reading": reading_of(claim.id)}
    out = []
    for name, value in claim.values.items():
        low, high = claim.intervals.get(name, (math.nan, math.nan))
        known = math.isfinite(low) and math.isfinite(high)
        level = _number_text(claim.level) if known else ""
        cells = {"value": _number_text(value), "low": _number_text(low), "high": _number_text(high)}
        out.append(head | {"quantity": name} | cells | {"level": level, "n": claim.n_users})
    for name, value in claim.facts.items():
        cells = {"value": _number_text(value), "low": "", "high": "", "level": ""}
        out.append(head | {"quantity": name} | cells | {"n": claim.n_users})
    return out


@dataclasses.dataclass(frozen=True)
class PaperClaim:
    """One row of the verdict table: a claim of the paper, and where it is measured."""

    id: str  # the headline row's id in claims.csv
    claim: str  # the claim, in the paper's words
    paper: str  # the paper's number
    # what makes our verdict, in a line: the mechanism only, never a result (the verdict table
    # writes each result sentence from the rows' numbers: lasa.evidence.findings)
    mechanism: str
    notebook: str  # the notebook (file stem) that measures it
    short: str  # the claim in a few words, for the README's summary
    why: str = ""  # why it does not reproduce where it does not, in a few words (the summary's)
    section: str = "What it shows, against the paper"  # its section that explains the mechanism
    ours: bool = False  # our addition, not a claim of the paper: listed apart, never counted


PAPER_CLAIMS: tuple[PaperClaim, ...] = (
    PaperClaim(
        "sim1.final_error",
        "shared autonomy reduces the final state error (Fig. sim1)",
        "LA+SA below LA at every beta",
        "Eq. M2 pulls towards the mid-preference grasp; a myopic Eq. S1 user never fully resists it (Eq. T4)",
        "04_fixed_expertise",
        "SA lowers the final error (sim1)",
        "Eq. M2 pulls towards the mid-preference grasp",
    ),
    PaperClaim(
        "sim1.time_ratio",
        "LA takes 45% more time than LA+SA at beta = 75 and 30% more at beta = 1000",
        "time ratio 1.45 and 1.30",
        "the pull is largest far from the goal",
        "04_fixed_expertise",
        "LA is slower than LA+SA (sim1)",
    ),
    PaperClaim(
        "sim1.gap_narrows",
        "the gap between LA and LA+SA narrows as the user becomes more rational",
        "45% at beta = 75 -> 30% at beta = 1000",
        "",
        "04_fixed_expertise",
        "the LA/LA+SA gap narrows with rationality (sim1)",
    ),
    PaperClaim(
        "sim1.entropy_sa",
        "shared autonomy helps with or without the entropy term",
        "LA+SA and LA+SA+Entropy below LA",
        "the entropy decoder keeps inputs towards the other cup, and Eq. M2 pulls to the mid grasp",
        "04_fixed_expertise",
        "SA helps with and without entropy (sim1)",
        "Eq. M2 pulls to the mid grasp",
    ),
    PaperClaim(
        "sim2.sa_trapped",
        "with LA+SA, a user who changes their mind late is stuck at the first goal",
        "final error grows, confidence falls with N",
        "the belief holds the first cup (Panda), or Eq. M2 pulls there until it turns (planar5)",
        "05_changing_goals",
        "a late change of mind is stuck with LA+SA (sim2)",
    ),
    PaperClaim(
        "sim2.entropy_escapes",
        "the entropy term lets users change their mind",
        "LA+SA+Entropy reaches the new goal",
        "Eq. T6 keeps some input leading to each goal at every belief",
        "05_changing_goals",
        "entropy lets users change their mind (sim2)",
    ),
    PaperClaim(
        "sim3.entropy_learners",
        "entropy improves in-task performance for fast and slow learners",
        "LA+SA+Entropy below LA+SA over time",
        "a learner's early random inputs commit the belief; entropy lets them undo it",
        "06_learning_users",
        "entropy helps learning users (sim3)",
    ),
    PaperClaim(
        "sim4.straight_line_linear",
        "with the context map, the error at a new goal grows linearly with its distance",
        "y = 0.11x, R^2 = 0.98",
        "the straight-line map moves the grasp curve rigidly in joint space, missing the new cup's grasps",
        "07_new_goals",
        "with the map, the error grows linearly with distance (sim4)",
        "the straight-line map misses the new cup's grasps by a margin",
    ),
    PaperClaim(
        "sim4.grasp_linear",
        "the same, with our grasp-to-grasp context map (not the paper's)",
        "y = 0.11x, R^2 = 0.98",
        "the grasp-to-grasp map is exact at every grasp",
        "07_new_goals",
        "our grasp-to-grasp map (sim4)",
        ours=True,
    ),
    PaperClaim(
        "sim4.no_map_training_goal",
        "without the map, the robot only reaches for the training goal",
        "y = x",
        "without the map the robot reaches for the training cup; some users' belief ends on the other one",
        "07_new_goals",
        "without the map, the robot reaches the training goal (sim4)",
    ),
    PaperClaim(
        "study.h1",
        "H1: with shared autonomy users maintain their goals more accurately (Goal Error)",
        "F(1,18) = 29.9, p < .001",
        "",
        "11_eating_study",
        "H1, SA keeps the goal (study)",
    ),
    PaperClaim(
        "study.h2",
        "H2: latent actions let users execute their preferences (Dessert, scoop)",
        "LA+SA adjusts to scoop; R+SA stays stabbing",
        "",
        "11_eating_study",
        "H2, LA lets users scoop (study)",
    ),
    PaperClaim(
        "study.h3",
        "H3: LA+SA completes the tasks most efficiently (Total and Idle Time)",
        "LA+SA fastest, p < .05 vs each",
        "",
        "11_eating_study",
        "H3, LA+SA is fastest (study)",
    ),
    PaperClaim(
        "study.likert",
        "H3, subjective: users rate LA+SA above the other conditions (Fig. dessert, Likert)",
        "LA+SA higher, t-tests p < .05",
        "simulated participants answer no questionnaire; people's sessions are judged in notebook 11",
        "11_eating_study",
        "H3's Likert ratings (study)",
    ),
)


_PEOPLE = "simulated participants"  # who the study's rows rest on: never people, in this package


def effect_text(row: pd.Series, numbers: Numbers) -> str:
    """A row's effect word, a study row's saying that its participants are simulated.

    ``not reproduced by simulated participants``: the study's verdicts are not a replication with
    people, and their word says so; ``(censored: lower bound)`` where the effect rests on one (the
    row's ``censored`` fact).
    """
    censored = numbers.get("censored")
    bound = censored is not None and censored.value == 1.0
    said = f"{row.effect} ({CENSORED})" if bound else str(row.effect)
    if str(row.figure) != "study":
        return said
    return f"{said} {'with' if row.effect in (UNDECIDED, NOT_TESTABLE) else 'by'} {_PEOPLE}"


def _interval_text(number: Number) -> str:
    """``0.0358 [0.0296, 0.042]``; the value alone where the interval is unknown."""
    iv = number.interval
    return f"{number.value:.3g}" + (f" [{iv[0]:.3g}, {iv[1]:.3g}]" if iv is not None else "")


def _cell(row: pd.Series | None, numbers: Numbers) -> str:
    """A robot's cell: the effect word, the key number with its interval, N, and whether settled.

    Each number the paper states for this robot with its word and our value
    (``0.11 out: 0.0358 [0.0296, 0.042]``), or, where it states none, the rule's first quantity
    (the number the verdict rests on); on a robot the paper states no number for, the claim's
    numbers are not compared (``no paper number for planar5``). A study row gives its effect in
    words from its numbers (:func:`lasa.evidence.findings.study_effect`), a not-testable one as
    "measured, not judged" with the completion that stopped it.
    """
    if row is None:
        return "—"
    head = f"effect {effect_text(row, numbers)}"
    if row.figure == "study":
        effect = study_effect(str(row.id), numbers)
        if row.effect == NOT_TESTABLE:
            short = short_arms(numbers)
            why = f" (completion: {completion_text(short)})" if short else f" ({_untestable_why(row)})"
            seen = f"; measured, not judged: {effect}" if effect else ""
            return f"{head}{why}, N = {row.n_users}{seen}"
        said = [effect] if effect else []
    else:
        paper = paper_numbers_of(str(row.id), str(row.robot))
        words = str(row.number).split("; ")
        said = [
            f"{p.value:g} {w}: {_interval_text(numbers[p.quantity])}"
            for p, w in zip(paper, words, strict=False)
            if p.quantity in numbers
        ]
        rule_of = RULES.get(str(row.id).split("@", 1)[0])
        if not said and rule_of is not None and rule_of.quantities[0].name in numbers:
            first = rule_of.quantities[0].name
            said = [f"{first} {_interval_text(numbers[first])}"]
        if stated_elsewhere(str(row.id), str(row.robot)):
            said.append(f"no paper number for {row.robot}")
    bold = row.effect not in (UNDECIDED, NOT_TESTABLE)
    settled = ", settled" if str(row.settled) == "yes" else ""
    return "; ".join([f"**{head}**" if bold else head, *said]) + f", N = {row.n_users}{settled}"


def _heads(table: pd.DataFrame) -> list[pd.Series]:
    """The headline rows of the paper's claims (not our additions), in the verdict table's order."""
    rows = by_key(table)
    return [rows[(pc.id, r)] for pc in PAPER_CLAIMS if not pc.ours for r in ROBOTS if (pc.id, r) in rows]


def count_line(table: pd.DataFrame) -> str:
    """``Of 21 paper claims × robot, the effect: 8 reproduced, ...; of the 5 numbers ...: 1 in, ...``.

    The numbers are counted on the robot the paper states them for (the Panda).
    """
    heads = _heads(table)
    effects = [str(r.effect) for r in heads]
    numbers = [w for r in heads for w in str(r.number).split("; ") if w != NOT_APPLICABLE]
    counts = ", ".join(f"{effects.count(w)} {w}" for w in WORDS)
    stated = ", ".join(f"{numbers.count(w)} {w}" for w in NUMBER_WORDS if w != NOT_APPLICABLE)
    return (
        f"Of {len(effects)} paper claims × robot, the effect: {counts}. Of the {len(numbers)} numbers "
        f"the paper states, on the robot it states them for (the Panda), the number: {stated}."
    )


def fragile_line(table: pd.DataFrame) -> str:
    """The sentence naming the table's fragile headline rows, and counting the readings' ones."""
    heads = {pc.id for pc in PAPER_CLAIMS}
    fragile = table[table.fragile.astype(str) == "yes"]
    named = [f"`{r.id}` ({r.robot})" for _, r in fragile.iterrows() if r.id in heads]
    readings = table[table.id.astype(str).str.contains("@", regex=False)]
    shaky = int((readings.fragile.astype(str) == "yes").sum())
    lead = (
        "Fragile (an interval ends within a fifth of its width, one standard error, of a value at which "
        "a word changes; another CPU, seed or library version may flip them): "
    )
    said = ", ".join(named) if named else "no headline row"
    return f"{lead}{said}; and {shaky} of the {len(readings)} readings' rows (`fragile` in claims.csv)."


def by_key(table: pd.DataFrame) -> dict[tuple[str, str], pd.Series]:
    """The claims table's rows by (id, robot)."""
    return {(r.id, r.robot): r for _, r in table.iterrows()}


def flips(rows: Mapping[tuple[str, str], pd.Series], claim_id: str) -> tuple[dict[str, list[str]], int]:
    """The readings of a claim whose words differ from its headline's, and how many readings it has.

    Args:
        rows: The claims table's rows by (id, robot) (:func:`by_key`).
        claim_id: The headline row's id.

    Returns:
        ``{reading: ["<robot>: effect <word>; <numbers' words>", ...]}`` (compound readings such as
        ``a+b`` included), and the number of distinct readings of the claim.
    """
    out: dict[str, list[str]] = {}
    readings = set()
    for (cid, robot), r in rows.items():
        if cid.startswith(claim_id + "@"):
            readings.add(cid.split("@", 1)[1])
            head = rows.get((claim_id, robot))
            if head is not None and (r.effect, r.number) != (head.effect, head.number):
                said = words_text(str(r.effect), str(r.number), paper_numbers_of(claim_id, str(robot)))
                out.setdefault(cid.split("@", 1)[1], []).append(f"{robot}: {said}")
    return out, len(readings)


def _anchor(claim_id: str) -> str:
    """The GitHub anchor of a claim's heading in claims.md (``### sim1.final_error``)."""
    return claim_id.replace(".", "").lower()


def render_flips(table: pd.DataFrame) -> str:
    """Claims.md's first section: per paper claim, every reading whose words differ from the headline's."""
    out = [
        "# Readings that flip a headline",
        "",
        "Other readings of what the paper leaves open, whose words differ from the headline's "
        "(reading names: the README's *Reading names*).",
    ]
    rows = by_key(table)
    for pc in PAPER_CLAIMS:
        flipped, n = flips(rows, pc.id)
        if not n:
            continue
        out += ["", f"### {pc.id}", "", f"{pc.claim}: {len(flipped)} of {n} readings flip it.", ""]
        out += [f"- `{k}`: {'; '.join(v)}" for k, v in flipped.items()] or ["- none"]
    return "\n".join(out) + "\n"


def _flips_cell(rows: Mapping[tuple[str, str], pd.Series], claim_id: str, claims_md: str) -> str:
    """``3 of 8 ([list](figures/claims.md#sim1final_error))``: the count of readings that flip it."""
    flipped, n = flips(rows, claim_id)
    if not n:
        return "none"
    return f"{len(flipped)} of {n}" + (f" ([list]({claims_md}#{_anchor(claim_id)}))" if flipped else "")


def render_verdicts(
    table: pd.DataFrame,
    values: Values,
    link: Callable[[str], str] | None = None,
    claims_md: str = "figures/claims.md",
) -> str:
    """The verdict table: one row per paper claim, both robots side by side, our additions apart.

    Args:
        table: ``figures/claims.csv`` (as strings).
        values: Its numbers (``figures/claim_values.csv``, :func:`lasa.evidence.values.read_values`).
        link: Notebook stem -> the link target of its page (default
            ``notebooks/<stem>.ipynb``, from the repository root).
        claims_md: Where the list of readings that flip a claim is (from the page's folder).

    Returns:
        Markdown: a count line of the headline rows' two words, the fragile rows
        (:func:`fragile_line`); then per claim its paper number, per robot its cell (:func:`_cell`),
        how many readings flip it (listed in claims.md), and what makes the verdict: the result
        sentences written from the rows' numbers (:func:`lasa.evidence.findings.finding`), then
        the mechanism, with a link to the notebook that measures it. Rows that are our
        additions, not the paper's claims, follow in a table of their own.
    """
    head = [
        "| claim (paper) | paper | planar5 | Panda | readings that flip it | mechanism |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    rows = by_key(table)
    paper, ours = list(head), list(head)
    for pc in PAPER_CLAIMS:
        cells = [_cell(rows.get((pc.id, r)), values.get((pc.id, r), {})) for r in ROBOTS]
        if cells == ["—", "—"]:
            continue
        anchor = pc.section.lower().replace(",", "").replace(" ", "-")
        target = link(pc.notebook) if link is not None else f"notebooks/{pc.notebook}.ipynb"
        said = "; ".join(s for s in (finding(pc.id, values, ROBOTS), pc.mechanism) if s)
        mech = " ".join(s for s in (said, f"([{pc.notebook[:2]}]({target}#{anchor}))") if s)
        flipped = _flips_cell(rows, pc.id, claims_md)
        line = f"| {pc.claim} | {pc.paper} | {cells[0]} | {cells[1]} | {flipped} | {mech} |"
        (ours if pc.ours else paper).append(line)
    out = [f"{count_line(table)} {fragile_line(table)}", "", *paper]
    if len(ours) > len(head):
        out += ["", "Our additions, not claims of the paper (not counted above):", "", *ours]
    return "\n".join(out) + "\n"


def render_summary(table: pd.DataFrame, values: Values) -> str:
    """The README's summary under its title, at most 10 lines, from the headline rows and their numbers.

    One line per effect word that some paper claim reads: each claim by its short name with the
    robots it reads so on, and for ``not reproduced`` and ``not testable`` the one-line reason:
    the claim's finding on those robots, written from its numbers (:func:`lasa.evidence.findings.finding`),
    else its mechanism (:attr:`PaperClaim.why`); why a row is not testable. Then the count of the
    paper's numbers on the Panda.
    """
    rows = by_key(table)
    by_word: dict[str, list[str]] = {}
    for pc in PAPER_CLAIMS:
        if pc.ours:
            continue
        words: dict[str, list[str]] = {}
        for robot in ROBOTS:
            if (pc.id, robot) in rows:
                words.setdefault(str(rows[(pc.id, robot)].effect), []).append(robot)
        for w, robots in words.items():
            where = on_robots(robots)
            said = f"{pc.short[:-1]}; {where})" if pc.short.endswith(")") else f"{pc.short} ({where})"
            why = finding(pc.id, values, robots) or pc.why
            if w == "not reproduced" and why:
                said += f": {why.replace('; ', ', ')}"
            if w == NOT_TESTABLE:
                short = short_arms(values.get((pc.id, robots[0]), {}))
                done = f"completion {completion_text(short)} within the horizon" if short else ""
                said += f": {done or _untestable_why(rows[(pc.id, robots[0])])}"
            by_word.setdefault(w, []).append(said)
    lines = [
        "**In short.** What reproduced, claim by claim (sims 1–4: simulated users; the study: "
        "simulated participants, not a replication with people; words and N: [the verdicts](#the-verdicts)):"
    ]
    for w in WORDS:
        if w in by_word:
            lines.append(f"- **{w.capitalize()}** ({len(by_word[w])}): " + "; ".join(by_word[w]) + ".")
    numbers = [w for r in _heads(table) for w in str(r.number).split("; ") if w != NOT_APPLICABLE]
    stated = ", ".join(f"{numbers.count(w)} {w}" for w in NUMBER_WORDS if w != NOT_APPLICABLE)
    lines.append(f"- **The paper's numbers** ({len(numbers)}, stated for the Panda): {stated}.")
    return "\n".join(lines) + "\n"


def _untestable_why(row: pd.Series) -> str:
    """Why a headline row is not testable, in a line: its ``measured`` when that says why."""
    if str(row.measured).startswith(f"{NOT_TESTABLE} (") and "completion" not in str(row.measured):
        return str(row.measured)[len(NOT_TESTABLE) + 2 :].split(")", 1)[0]
    return "too few episodes finish within the horizon"


def write_verdicts(claims_csv: str | os.PathLike[str], out: str | os.PathLike[str]) -> Path:
    """Render ``claims_csv`` (and its ``claim_values.csv``) as the verdict table into ``out``
    (``figures/verdicts.md``), its summary beside it (``summary.md``), and claims.md afresh."""
    claims_csv = Path(claims_csv)
    table = pd.read_csv(claims_csv, dtype=str, keep_default_na=False)
    values = read_values(pd.read_csv(claims_csv.with_name(VALUES_NAME), dtype=str, keep_default_na=False))
    write_text(claims_csv.with_suffix(".md"), render_markdown(table))
    write_text(Path(out).with_name("summary.md"), render_summary(table, values))
    return write_text(out, render_verdicts(table, values))


def sync_readme(readme: str | os.PathLike[str], table_md: str | os.PathLike[str]) -> bool:
    """Put the verdict table ``table_md`` between the README's verdict markers, and its summary
    (``summary.md`` beside it) between the summary markers.

    ``make figures`` runs this after the notebooks, so the README's table and summary are always
    the last full run's, never a hand-edited copy.

    Returns:
        Whether the README changed.

    Raises:
        ConfigError: if the README lacks a marker (:data:`README_MARKERS`, :data:`SUMMARY_MARKERS`).
    """
    summary = Path(table_md).with_name("summary.md")
    changed = sync_between(readme, SUMMARY_MARKERS, summary.read_text()) if summary.exists() else False
    return sync_between(readme, README_MARKERS, Path(table_md).read_text()) or changed


if __name__ == "__main__":
    import sys

    if len(sys.argv) not in (2, 3):
        raise SystemExit("usage: python -m lasa.evidence.claims [README.md] figures/claims.csv")
    csv = Path(sys.argv[-1]).with_suffix(".csv")
    verdicts = write_verdicts(csv, csv.with_name("verdicts.md"))
    if len(sys.argv) == 2:  # an OUT= or QUICK run: its verdicts.md beside its claims, no README
        print(f"{verdicts} written")
        raise SystemExit(0)
    readme = Path(sys.argv[1])
    changed = sync_readme(readme, verdicts)
    print(f"{verdicts} written; {readme}: verdict table {'updated' if changed else 'already current'}")
