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
"""

from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import pandas as pd

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
from lasa.evidence.findings import effect_of, finding, not_testable_why, stated_numbers
from lasa.evidence.rules import RULES

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
]

README_MARKERS = (
    "<!-- verdicts:begin (generated from figures/verdicts.md by make figures) -->",
    "<!-- verdicts:end -->",
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
    paper = r.paper if r is not None else ()
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


def paper_numbers_of(claim_id: str) -> tuple[PaperNumber, ...]:
    """The numbers the paper states for a claim (its rule's), none if it has no rule."""
    r = RULES.get(claim_id.split("@", 1)[0])
    return r.paper if r is not None else ()


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
    del row["values"], row["value"], row["intervals"]
    row["settled"] = "yes" if claim.settled else "no"
    row.update(criteria(claim))
    lead = note_lead(str(row["effect"]), str(row["number"]), paper_numbers_of(claim.id))
    note = lead + claim.note
    if row["fragile"] == "yes":  # criteria found it so; the note says why
        why = "; ".join(fragile_because(claim))
        note = f"{note.rstrip()} Fragile: {why} (within a fifth of its width)."
    row["note"] = note
    for key in ("ci_low", "ci_high"):
        row[key] = "" if math.isnan(getattr(claim, key)) else f"{getattr(claim, key):.4g}"
    return row


def render_markdown(frame: pd.DataFrame) -> str:
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
    (robots run in parallel).

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
    with locked(path.parent):
        if path.exists():
            old = pd.read_csv(path, dtype=str, keep_default_na=False)
            if list(old.columns) != list(CLAIM_COLUMNS):
                raise ConfigError(
                    f"{path} has columns {list(old.columns)}, expected {list(CLAIM_COLUMNS)}; "
                    "delete it and re-run the figure notebooks"
                )
            covered = pd.MultiIndex.from_frame(new[["figure", "robot"]].drop_duplicates())
            keep = ~pd.MultiIndex.from_frame(old[["figure", "robot"]]).isin(covered)
            table = pd.concat([old.loc[keep], new], ignore_index=True)
        else:
            table = new
        table = table.sort_values(["figure", "robot", "id"], kind="stable").reset_index(drop=True)
        write_csv(path, table)
        write_text(path.with_suffix(".md"), render_markdown(table))
    return table


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
    section: str  # its section that explains the mechanism
    ours: bool = False  # our addition, not a claim of the paper: listed apart, never counted


PAPER_CLAIMS: tuple[PaperClaim, ...] = (
    PaperClaim(
        "sim1.final_error",
        "shared autonomy reduces the final state error (Fig. sim1)",
        "LA+SA below LA at every beta",
        "Eq. M2 pulls towards the mid-preference grasp; a myopic Eq. S1 user never fully resists it (Eq. T4)",
        "04_fixed_expertise",
        "What it shows, against the paper",
    ),
    PaperClaim(
        "sim1.time_ratio",
        "LA takes 45% more time than LA+SA at beta = 75 and 30% more at beta = 1000",
        "time ratio 1.45 and 1.30",
        "the pull is largest far from the goal",
        "04_fixed_expertise",
        "What it shows, against the paper",
    ),
    PaperClaim(
        "sim1.gap_narrows",
        "the gap between LA and LA+SA narrows as the user becomes more rational",
        "45% at beta = 75 -> 30% at beta = 1000",
        "",
        "04_fixed_expertise",
        "What it shows, against the paper",
    ),
    PaperClaim(
        "sim1.entropy_sa",
        "shared autonomy helps with or without the entropy term",
        "LA+SA and LA+SA+Entropy below LA",
        "the entropy decoder keeps inputs towards the other cup, and Eq. M2 pulls to the mid grasp",
        "04_fixed_expertise",
        "What it shows, against the paper",
    ),
    PaperClaim(
        "sim2.sa_trapped",
        "with LA+SA, a user who changes their mind late is stuck at the first goal",
        "final error grows, confidence falls with N",
        "on the Panda the belief stays on the first cup, where the decoder offers no input towards the "
        "true one; on planar5 it turns, but Eq. M2 pulls towards the first cup until it does, and late "
        "changers run out of steps",
        "05_changing_goals",
        "What it shows, against the paper",
    ),
    PaperClaim(
        "sim2.entropy_escapes",
        "the entropy term lets users change their mind",
        "LA+SA+Entropy reaches the new goal",
        "Eq. T6 keeps some input leading to each goal at every belief",
        "05_changing_goals",
        "What it shows, against the paper",
    ),
    PaperClaim(
        "sim3.entropy_learners",
        "entropy improves in-task performance for fast and slow learners",
        "LA+SA+Entropy below LA+SA over time",
        "a learner's early random inputs commit the belief; entropy lets them undo it",
        "06_learning_users",
        "What it shows, against the paper",
    ),
    PaperClaim(
        "sim4.straight_line_linear",
        "with the context map, the error at a new goal grows linearly with its distance",
        "y = 0.11x, R^2 = 0.98",
        "the straight-line map moves the training cup's grasp curve rigidly in joint space, so the mapped "
        "grasps miss the new cup's by a margin that grows with the distance",
        "07_new_goals",
        "What it shows, against the paper",
    ),
    PaperClaim(
        "sim4.grasp_linear",
        "the same, with our grasp-to-grasp context map (not the paper's)",
        "y = 0.11x, R^2 = 0.98",
        "the grasp-to-grasp map is exact at every grasp",
        "07_new_goals",
        "What it shows, against the paper",
        ours=True,
    ),
    PaperClaim(
        "sim4.no_map_training_goal",
        "without the map, the robot only reaches for the training goal",
        "y = x",
        "without the map the robot reaches for the training cup, its error about the cup's distance; a "
        "share of users that grows with the distance ends with the belief on the other training cup, "
        "farther off",
        "07_new_goals",
        "What it shows, against the paper",
    ),
    PaperClaim(
        "study.h1",
        "H1: with shared autonomy users maintain their goals more accurately (Goal Error)",
        "F(1,18) = 29.9, p < .001",
        "",
        "11_eating_study",
        "What it shows, against the paper",
    ),
    PaperClaim(
        "study.h2",
        "H2: latent actions let users execute their preferences (Dessert, scoop)",
        "LA+SA adjusts to scoop; R+SA stays stabbing",
        "",
        "11_eating_study",
        "What it shows, against the paper",
    ),
    PaperClaim(
        "study.h3",
        "H3: LA+SA completes the tasks most efficiently (Total and Idle Time)",
        "LA+SA fastest, p < .05 vs each",
        "",
        "11_eating_study",
        "What it shows, against the paper",
    ),
)


def _cell(row: pd.Series | None) -> str:
    """A robot's cell: both words, the numbers they rest on, N and whether the effect is settled.

    ``effect <word>`` first, then each number the paper states with its word, our value and
    interval (``0.11 out (0.0131 [0.00828, 0.0177])``), then every other number the rule reads
    with its value and interval (from the row's note, as :func:`lasa.evidence.verdicts.assess`
    wrote it). A study row's note states its effect in words with its sign
    (:func:`lasa.evidence.findings.effect_of`): the cell says it, a not-testable one as "measured,
    not judged", and an effect that rests on a censored arm's lower bound reads ``not reproduced
    (censored: lower bound)``. A claim that is not testable reads ``not testable``, N, and why.
    """
    if row is None:
        return "—"
    if row.effect == NOT_TESTABLE:
        why, effect = not_testable_why(row), effect_of(row.note)
        seen = f"; measured, not judged: {effect}" if effect else ""
        return f"effect not testable, N = {row.n_users}" + (f" ({why})" if why else "") + seen
    paper = paper_numbers_of(str(row.id))
    stated = {p.quantity for p in paper}
    numbers = [_paper_number(text) for text in str(row.paper_numbers).split("; ") if text]
    numbers += [f"{name} {text}" for name, text in stated_numbers(row.note) if name not in stated]
    effect = effect_of(row.note)
    if effect:
        numbers.append(effect)
    word = f"{row.effect} ({CENSORED})" if str(row.measured).startswith(CENSORED) else row.effect
    head = f"**effect {word}**" if row.effect != UNDECIDED else f"effect {UNDECIDED}"
    settled = ", settled" if str(row.settled) == "yes" else ""
    return "; ".join([head, *numbers]) + f", N = {row.n_users}{settled}"


def _paper_number(text: str) -> str:
    """``0.11 out (0.0131 [0.00828, 0.0177])`` from ``0.11 (y = 0.11x): out, 0.0131 [0.00828, 0.0177]``."""
    label, _, rest = text.partition(": ")
    value = label.split(" (", 1)[0].split(" ±", 1)[0]
    number_word, _, measured = rest.partition(", ")
    return f"{value} {number_word} ({measured})"


def count_line(table: pd.DataFrame) -> str:
    """``Of 21 paper claims × robot, the effect: 6 reproduced, ...; of the 12 numbers ...: 3 in, ...``."""
    rows = {(r.id, r.robot): r for _, r in table.iterrows()}
    heads = [
        rows[(pc.id, robot)]
        for pc in PAPER_CLAIMS
        if not pc.ours
        for robot in ROBOTS
        if (pc.id, robot) in rows
    ]
    effects = [str(r.effect) for r in heads]
    numbers = [w for r in heads for w in str(r.number).split("; ") if w != NOT_APPLICABLE]
    counts = ", ".join(f"{effects.count(w)} {w}" for w in WORDS)
    stated = ", ".join(f"{numbers.count(w)} {w}" for w in NUMBER_WORDS if w != NOT_APPLICABLE)
    return (
        f"Of {len(effects)} paper claims × robot, the effect: {counts}. "
        f"Of the {len(numbers)} numbers the paper states (× robot), the number: {stated}."
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


def _flips(rows: Mapping[tuple[str, str], pd.Series], claim_id: str) -> str:
    """Every reading (``<id>@<reading>``, compound ones such as ``a+b`` included) whose words differ."""
    flips: dict[str, list[str]] = {}
    for (cid, robot), r in rows.items():
        if cid.startswith(claim_id + "@"):
            head = rows.get((claim_id, robot))
            if head is not None and (r.effect, r.number) != (head.effect, head.number):
                said = words_text(str(r.effect), str(r.number), paper_numbers_of(claim_id))
                flips.setdefault(cid.split("@", 1)[1], []).append(f"{robot}: {said}")
    return "; ".join(f"`{k}` ({'; '.join(v)})" for k, v in flips.items()) or "none"


def render_verdicts(table: pd.DataFrame, link: Callable[[str], str] | None = None) -> str:
    """The verdict table: one row per paper claim, both robots side by side, our additions apart.

    Args:
        table: ``figures/claims.csv`` (as strings).
        link: Notebook stem -> the link target of its page (default
            ``notebooks/<stem>.ipynb``, from the repository root).

    Returns:
        Markdown: a count line of the headline rows' two words, the fragile rows
        (:func:`fragile_line`); then per claim its paper
        number, per robot the effect's word with the numbers it rests on (each number the
        paper states with its own word), the users per point N, the readings whose words
        differ, and what makes the verdict: the result sentences written from the rows'
        numbers (:func:`lasa.evidence.findings.finding`), then the mechanism, with a link to the
        notebook that measures it. Rows that are our additions, not the paper's claims, follow
        in a table of their own.
    """
    head = [
        "| claim (paper) | paper | planar5 | Panda | readings that flip it | mechanism |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    rows = {(r.id, r.robot): r for _, r in table.iterrows()}
    paper, ours = list(head), list(head)
    for pc in PAPER_CLAIMS:
        cells = [_cell(rows.get((pc.id, robot))) for robot in ROBOTS]
        if cells == ["—", "—"]:
            continue
        anchor = pc.section.lower().replace(",", "").replace(" ", "-")
        target = link(pc.notebook) if link is not None else f"notebooks/{pc.notebook}.ipynb"
        said = "; ".join(s for s in (finding(pc.id, rows, ROBOTS), pc.mechanism) if s)
        mech = " ".join(s for s in (said, f"([{pc.notebook[:2]}]({target}#{anchor}))") if s)
        line = f"| {pc.claim} | {pc.paper} | {cells[0]} | {cells[1]} | {_flips(rows, pc.id)} | {mech} |"
        (ours if pc.ours else paper).append(line)
    out = [f"{count_line(table)} {fragile_line(table)}", "", *paper]
    if len(ours) > len(head):
        out += ["", "Our additions, not claims of the paper (not counted above):", "", *ours]
    return "\n".join(out) + "\n"


def write_verdicts(claims_csv: str | os.PathLike[str], out: str | os.PathLike[str]) -> Path:
    """Render ``claims_csv`` as the verdict table into ``out`` (``figures/verdicts.md``)."""
    table = pd.read_csv(claims_csv, dtype=str, keep_default_na=False)
    return write_text(out, render_verdicts(table))


def sync_readme(readme: str | os.PathLike[str], table_md: str | os.PathLike[str]) -> bool:
    """Put the verdict table ``table_md`` between the README's verdict markers.

    ``make figures`` runs this after the notebooks, so the README's table is always the
    last full run's ``figures/verdicts.md``, never a hand-edited copy.

    Returns:
        Whether the README changed.

    Raises:
        ConfigError: if the README lacks either marker (:data:`README_MARKERS`).
    """
    return sync_between(readme, README_MARKERS, Path(table_md).read_text())


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
