"""The claims table (``figures/claims.csv``, numbers in ``claim_values.csv``): did each claim reproduce? A
row, keyed by (id, robot) with id ``<figure>.<name>[@<reading>]``, carries two words (Open Science
Collaboration, 2015): ``effect``, the claim's shape by its rule, and ``number``, whether each paper number
lies in our interval. The verdict table and README summary are written from the two files."""

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
    Rule,
    effect_word,
    word,
)
from lasa.evidence.findings import completion_text, finding, on_robots, short_conditions, study_effect
from lasa.evidence.rules import RULES
from lasa.evidence.values import VALUE_COLUMNS, VALUES_NAME, Number, Numbers, Values, read_values, reading_of

README_MARKERS = (
    "<!-- verdicts:begin (generated from figures/verdicts.md by make figures) -->",
    "<!-- verdicts:end -->",
)
SUMMARY_MARKERS = (
    "<!-- summary:begin (generated from figures/claims.csv by make figures) -->",
    "<!-- summary:end -->",
)

CLAIM_COLUMNS = tuple(
    "id claim figure robot assistance paper measured ci_low ci_high reproduced settled paper_in_ci "
    "direction paper_numbers effect number n_users fragile note".split()
)
VERDICTS = ("yes", "partly", "no", UNDECIDED, NOT_TESTABLE)  # what Claim.reproduced holds
ROBOTS = ("planar5", "panda")  # the verdict table's robot columns, in order
_NAN = (math.nan, math.nan)


@dataclasses.dataclass(frozen=True)
class Claim:
    """One row of the claims table; a claim of your own carries its :class:`Rule` in ``rule``."""

    id: str  # stable key, "<figure>.<name>": survives a rewording of ``claim``
    claim: str  # the paper's claim, in a sentence
    figure: str  # the figure it belongs to, e.g. "sim1"
    paper: str  # what the paper reports
    measured: str  # what we measured
    reproduced: str  # "yes", "partly", "no"; "undecided" (an interval straddles a threshold); "not testable"
    note: str  # how the verdict was decided, and the likely reason if not "yes"
    robot: str  # the robot it was measured on
    assistance: str = "point"  # the shared-autonomy member: Eq. M2 towards one pose per goal
    value: float = math.nan  # the number the verdict rests on (``measured`` names it first)
    ci_low: float = math.nan  # its interval (lasa.evidence.verdicts)
    ci_high: float = math.nan
    settled: bool = False  # every interval clear of its rule's thresholds (lasa.evidence.verdicts)
    n_users: int = 0  # simulated users (or participants) per point the verdict rests on
    values: Mapping[str, float] = dataclasses.field(default_factory=dict)  # the rule's numbers
    # each of the rule's numbers' interval, at the row's level (lasa.evidence.verdicts)
    intervals: Mapping[str, tuple[float, float]] = dataclasses.field(default_factory=dict)
    level: float = math.nan  # the intervals' level (0.9875 under the sims' sequential design)
    # numbers a sentence reads beside the rule's, without an interval (test statistics, ``completion.LA``)
    facts: Mapping[str, float] = dataclasses.field(default_factory=dict)
    rule: Rule | None = None  # a claim of your own's rule; None: the paper's, by id

    def __post_init__(self) -> None:
        if not self.id.startswith(f"{self.figure}.") or " " in self.id:
            raise ConfigError(f"claim id must be '<figure>.<name>' without spaces, got {self.id!r}")
        if self.reproduced not in VERDICTS:
            raise ConfigError(f"reproduced must be one of {VERDICTS}, got {self.reproduced!r}")
        if self.reproduced == NOT_TESTABLE and self.settled:
            raise ConfigError(f"{self.id}: a claim that is not testable is never settled")
        base = self.id.split("@", 1)[0]
        if self.rule is not None and (self.rule.id != base or RULES.get(base, self.rule) is not self.rule):
            raise ConfigError(
                f"{self.id}: its rule is {self.rule.id!r}, or a paper rule for {base!r} exists already"
            )

    @property
    def judged_by(self) -> Rule | None:
        """The claim's rule: its own, else the paper's for its id (None if neither)."""
        return self.rule if self.rule is not None else RULES.get(self.id.split("@", 1)[0])

    @property
    def stated(self) -> tuple[PaperNumber, ...]:
        """The numbers the paper states for this claim on its robot (its rule's)."""
        return paper_numbers_of(self.id, self.robot, self.rule)


SHOWN_COLUMNS = ("id", "assistance", "n_users", "measured", "ci_low", "ci_high", "reproduced", "settled")


def claims_frame(claims: Sequence[Claim], assistance: bool = True) -> pd.DataFrame:
    """A notebook's claims in the columns of :data:`SHOWN_COLUMNS` (``assistance`` False: without it)."""
    columns = [c for c in SHOWN_COLUMNS if assistance or c != "assistance"]
    return pd.DataFrame([c.__dict__ for c in claims], columns=columns)


def paper_numbers_of(claim_id: str, robot: str, rule: Rule | None = None) -> tuple[PaperNumber, ...]:
    """The numbers ``rule`` (None: the paper's for the id) states for a claim on ``robot``."""
    r = rule if rule is not None else RULES.get(claim_id.split("@", 1)[0])
    return tuple(p for p in r.paper if p.robot == robot) if r is not None else ()


def criteria(claim: Claim) -> dict[str, str]:
    """The row's two words and replication criteria (``n/a`` where not testable), by column."""
    r, paper = claim.judged_by, claim.stated
    testable = claim.reproduced != NOT_TESTABLE
    found = [(p, claim.intervals.get(p.quantity, _NAN)) for p in paper] if testable else []
    direction = r.direction if r is not None and testable else None
    numbers = [p.word(iv) for p, iv in found]
    said = [p.describe(iv, float(claim.values.get(p.quantity, math.nan))) for p, iv in found]
    return {
        "effect": effect_word(claim.reproduced),
        "number": "; ".join(numbers) if any(w != NOT_APPLICABLE for w in numbers) else NOT_APPLICABLE,
        "reproduced": word(claim.reproduced, claim.intervals, paper),
        "paper_in_ci": "; ".join(p.inside(iv) for p, iv in found) or "n/a",
        "direction": direction.judge(claim.intervals.get(direction.quantity, _NAN)) if direction else "n/a",
        "paper_numbers": "; ".join(said),
        "fragile": "yes" if r is not None and testable and r.fragile(claim.intervals) else "no",
    }


def numbers_of(claim: Claim) -> dict[str, Number]:
    """A claim's numbers as ``claim_values.csv`` holds them."""
    return {
        k: Number(float(v), *claim.intervals.get(k, _NAN), level=claim.level, n=claim.n_users)
        for k, v in claim.values.items()
    } | {k: Number(float(v), n=claim.n_users) for k, v in claim.facts.items()}


def words_text(effect: str, number: str, paper: tuple[PaperNumber, ...]) -> str:
    """``effect undecided; 1.45 out, 1.3 in``: a row's two words, each number named by its value."""
    numbers = number.split("; ")
    if number == NOT_APPLICABLE or len(numbers) != len(paper):
        return f"effect {effect}; number {number}"
    return f"effect {effect}; " + ", ".join(f"{p.value:g} {w}" for p, w in zip(paper, numbers, strict=True))


def _row(claim: Claim) -> dict[str, object]:
    row: dict[str, object] = {c: getattr(claim, c) for c in CLAIM_COLUMNS if hasattr(claim, c)}
    row |= {"settled": "yes" if claim.settled else "no"} | criteria(claim)
    said = words_text(str(row["effect"]), str(row["number"]), claim.stated)  # "Effect reproduced; 0.11 out. "
    note = f"{said[0].upper()}{said[1:]}. {claim.note}"
    if row["fragile"] == "yes" and (r := claim.judged_by) is not None:
        near = "; ".join(r.fragile(claim.intervals))
        note = f"{note.rstrip()} Fragile: {near} (within a fifth of its width)."
    row["note"] = note
    for key in ("ci_low", "ci_high"):
        row[key] = "" if math.isnan(getattr(claim, key)) else f"{getattr(claim, key):.4g}"
    return row


def render_markdown(frame: pd.DataFrame) -> str:
    """``claims.md``: the readings that flip each headline (:func:`render_flips`), then every row."""
    cols = list(CLAIM_COLUMNS)
    rows = [[str(row[c]).replace("|", "\\|").replace("\n", " ") for c in cols] for _, row in frame.iterrows()]
    lines = ["| " + " | ".join(cells) + " |" for cells in (cols, ["---"] * len(cols), *rows)]
    return render_flips(frame) + "\n# Every row of claims.csv\n\n" + "\n".join(lines) + "\n"


def update_claims(path: str | os.PathLike[str], claims: list[Claim]) -> pd.DataFrame:
    """Replace the rows of these claims' (figure, robot) pairs in the CSV at ``path``, ``claim_values.csv``
    and the ``.md`` twin, under the folder lock and the run's write journal; return the whole table."""
    path = Path(path)
    new = pd.DataFrame([_row(c) for c in claims], columns=list(CLAIM_COLUMNS))
    if dup := new.loc[new.duplicated(["id", "robot"]), "id"].tolist():
        raise ConfigError(f"claim ids must be unique per robot, repeated: {dup}")
    numbers = pd.DataFrame([v for c in claims for v in _value_rows(c)], columns=list(VALUE_COLUMNS))
    with locked(path.parent):
        for table_path, rows in ((path, new), (path.with_name(VALUES_NAME), numbers)):
            journal.note_rows(table_path, rows[["figure", "robot"]], sort=["figure", "robot", "id"])
        table = _replace(path, new, CLAIM_COLUMNS)
        write_csv(path, table)
        write_csv(path.with_name(VALUES_NAME), _replace(path.with_name(VALUES_NAME), numbers, VALUE_COLUMNS))
        write_text(path.with_suffix(".md"), render_markdown(table))
    return table


def _replace(path: Path, new: pd.DataFrame, columns: Sequence[str]) -> pd.DataFrame:
    table = new
    if path.exists():
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
    return f"{x:.6g}" if math.isfinite(x) else ""


def _value_rows(claim: Claim) -> list[dict[str, object]]:
    """The claim's rows of ``claim_values.csv``: its rule's numbers with their intervals, then its facts."""
    head = {"id": claim.id, "robot": claim.robot, "figure": claim.figure, "reading": reading_of(claim.id)}
    return [
        head
        | {"quantity": name}
        | {k: _number_text(getattr(x, k)) for k in ("value", "low", "high")}
        | {"level": _number_text(x.level) if x.interval else "", "n": x.n}
        for name, x in numbers_of(claim).items()
    ]


@dataclasses.dataclass(frozen=True)
class PaperClaim:
    """One row of the verdict table: a claim of the paper, and where it is measured."""

    id: str  # the headline row's id in claims.csv
    claim: str  # the claim, in the paper's words
    paper: str  # the paper's number
    short: str  # the claim in a few words, for the README's summary
    mechanism: str = ""  # what makes our verdict, in a line; never a result (lasa.evidence.findings)
    why: str = ""  # why it does not reproduce where it does not, in a few words (the summary's)
    ours: bool = False  # our addition, not a claim of the paper: listed apart, never counted


# the notebook (file stem) that measures a figure's claims, and its section that explains the mechanisms
_NOTEBOOKS = {
    "sim1": "04_fixed_expertise",
    "sim2": "05_changing_goals",
    "sim3": "06_learning_users",
    "sim4": "07_new_goals",
    "study": "11_eating_study",
}
_MECHANISMS = "#what-it-shows-against-the-paper"
PAPER_CLAIMS: tuple[PaperClaim, ...] = (
    PaperClaim(
        "sim1.final_error",
        "shared autonomy reduces the final state error (Fig. sim1)",
        "LA+SA below LA at every beta",
        "SA lowers the final error (sim1)",
        "Eq. M2 pulls towards the mid-preference grasp; a myopic Eq. S1 user never fully resists it (Eq. T4)",
        "Eq. M2 pulls towards the mid-preference grasp",
    ),
    PaperClaim(
        "sim1.time_ratio",
        "LA takes 45% more time than LA+SA at beta = 75 and 30% more at beta = 1000",
        "time ratio 1.45 and 1.30",
        "LA is slower than LA+SA (sim1)",
        "the pull is largest far from the goal",
    ),
    PaperClaim(
        "sim1.gap_narrows",
        "the gap between LA and LA+SA narrows as the user becomes more rational",
        "45% at beta = 75 -> 30% at beta = 1000",
        "the LA/LA+SA gap narrows with rationality (sim1)",
    ),
    PaperClaim(
        "sim1.entropy_sa",
        "shared autonomy helps with or without the entropy term",
        "LA+SA and LA+SA+Entropy below LA",
        "SA helps with and without entropy (sim1)",
        "the entropy decoder keeps inputs towards the other cup, and Eq. M2 pulls to the mid grasp",
        "Eq. M2 pulls to the mid grasp",
    ),
    PaperClaim(
        "sim2.sa_trapped",
        "with LA+SA, a user who changes their mind late is stuck at the first goal",
        "final error grows, confidence falls with N",
        "a late change of mind is stuck with LA+SA (sim2)",
        "the belief holds the first cup (Panda), or Eq. M2 pulls there until it turns (planar5)",
    ),
    PaperClaim(
        "sim2.entropy_escapes",
        "the entropy term lets users change their mind",
        "LA+SA+Entropy reaches the new goal",
        "entropy lets users change their mind (sim2)",
        "Eq. T6 keeps some input leading to each goal at every belief",
    ),
    PaperClaim(
        "sim3.entropy_learners",
        "entropy improves in-task performance for fast and slow learners",
        "LA+SA+Entropy below LA+SA over time",
        "entropy helps learning users (sim3)",
        "a learner's early random inputs commit the belief; entropy lets them undo it",
    ),
    PaperClaim(
        "sim4.straight_line_linear",
        "with the context map, the error at a new goal grows linearly with its distance",
        "y = 0.11x, R^2 = 0.98",
        "with the map, the error grows linearly with distance (sim4)",
        "the straight-line map moves the grasp curve rigidly in joint space, missing the new cup's grasps",
        "the straight-line map misses the new cup's grasps by a margin",
    ),
    PaperClaim(
        "sim4.grasp_linear",
        "the same, with our grasp-to-grasp context map (not the paper's)",
        "y = 0.11x, R^2 = 0.98",
        "our grasp-to-grasp map (sim4)",
        "the grasp-to-grasp map is exact at every grasp",
        ours=True,
    ),
    PaperClaim(
        "sim4.no_map_training_goal",
        "without the map, the robot only reaches for the training goal",
        "y = x",
        "without the map, the robot reaches the training goal (sim4)",
        "without the map the robot reaches for the training cup; some users' belief ends on the other one",
    ),
    PaperClaim(
        "study.h1",
        "H1: with shared autonomy users maintain their goals more accurately (Goal Error)",
        "F(1,18) = 29.9, p < .001",
        "H1, SA keeps the goal (study)",
    ),
    PaperClaim(
        "study.h2",
        "H2: latent actions let users execute their preferences (Dessert, scoop)",
        "LA+SA adjusts to scoop; R+SA stays stabbing",
        "H2, LA lets users scoop (study)",
    ),
    PaperClaim(
        "study.h3",
        "H3: LA+SA completes the tasks most efficiently (Total and Idle Time)",
        "LA+SA fastest, p < .05 vs each",
        "H3, LA+SA is fastest (study)",
    ),
    PaperClaim(
        "study.likert",
        "H3, subjective: users rate LA+SA above the other conditions (Fig. dessert, Likert)",
        "LA+SA higher, t-tests p < .05",
        "H3's Likert ratings (study)",
        "simulated participants answer no questionnaire; people's sessions are judged in notebook 11",
    ),
)


def effect_text(row: pd.Series, numbers: Numbers) -> str:
    """A row's effect word, ``(censored: lower bound)`` where it rests on one, and a study row's
    saying that its participants are simulated (``not reproduced by simulated participants``)."""
    censored = numbers.get("censored", Number(0.0)).value == 1.0
    said = f"{row.effect} ({CENSORED})" if censored else str(row.effect)
    if str(row.figure) != "study":
        return said
    return f"{said} {'with' if row.effect in (UNDECIDED, NOT_TESTABLE) else 'by'} simulated participants"


def _interval_text(number: Number) -> str:
    iv = number.interval
    return f"{number.value:.3g}" + (f" [{iv[0]:.3g}, {iv[1]:.3g}]" if iv is not None else "")


def _cell(row: pd.Series | None, numbers: Numbers) -> str:
    """A robot's cell: the effect word, each paper number's word and our interval, N, settled."""
    if row is None:
        return "—"
    head = f"effect {effect_text(row, numbers)}"
    if row.figure == "study":
        effect = study_effect(str(row.id), numbers)
        if row.effect == NOT_TESTABLE:
            seen = f"; measured, not judged: {effect}" if effect else ""
            return f"{head} ({_untestable_why(row, numbers)}), N = {row.n_users}{seen}"
        said = [effect] if effect else []
    else:
        r = RULES.get(str(row.id).split("@", 1)[0])
        paper = paper_numbers_of(str(row.id), str(row.robot))
        said = [
            f"{p.value:g} {w}: {_interval_text(numbers[p.quantity])}"
            for p, w in zip(paper, str(row.number).split("; "), strict=False)
            if p.quantity in numbers
        ]
        if not said and r is not None and r.quantities[0].name in numbers:
            said = [f"{r.quantities[0].name} {_interval_text(numbers[r.quantities[0].name])}"]
        if r is not None and r.paper and not paper:
            said.append(f"no paper number for {row.robot}")
    bold = row.effect not in (UNDECIDED, NOT_TESTABLE)
    settled = ", settled" if str(row.settled) == "yes" else ""
    return "; ".join([f"**{head}**" if bold else head, *said]) + f", N = {row.n_users}{settled}"


def _heads(table: pd.DataFrame) -> tuple[list[str], int, str]:
    """The headline rows' effect words, how many numbers they state and ``1 in, 4 out, ...``."""
    rows = _by_key(table)
    heads = [rows[(pc.id, r)] for pc in PAPER_CLAIMS if not pc.ours for r in ROBOTS if (pc.id, r) in rows]
    numbers = [w for r in heads for w in str(r.number).split("; ") if w != NOT_APPLICABLE]
    stated = ", ".join(f"{numbers.count(w)} {w}" for w in NUMBER_WORDS if w != NOT_APPLICABLE)
    return [str(r.effect) for r in heads], len(numbers), stated


def count_line(table: pd.DataFrame) -> str:
    """``Of 21 paper claims × robot, the effect: 8 reproduced, ...; of the 5 numbers ...: 1 in, ...``."""
    effects, n, stated = _heads(table)
    counts = ", ".join(f"{effects.count(w)} {w}" for w in WORDS)
    return (
        f"Of {len(effects)} paper claims × robot, the effect: {counts}. Of the {n} numbers "
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


def _by_key(table: pd.DataFrame) -> dict[tuple[str, str], pd.Series]:
    return {(r.id, r.robot): r for _, r in table.iterrows()}


def flips(rows: Mapping[tuple[str, str], pd.Series], claim_id: str) -> tuple[dict[str, list[str]], int]:
    """The readings of ``claim_id`` (rows by (id, robot)) whose words differ from its headline's,
    as ``{reading: ["<robot>: effect <word>; <numbers' words>", ...]}``, and how many readings it has."""
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


def render_flips(table: pd.DataFrame) -> str:
    """Claims.md's first section: per paper claim, every reading whose words differ from the headline's."""
    out = [
        "# Readings that flip a headline",
        "",
        "Other readings of what the paper leaves open, whose words differ from the headline's "
        "(reading names: the README's *Reading names*).",
    ]
    rows = _by_key(table)
    for pc in PAPER_CLAIMS:
        flipped, n = flips(rows, pc.id)
        if not n:
            continue
        out += ["", f"### {pc.id}", "", f"{pc.claim}: {len(flipped)} of {n} readings flip it.", ""]
        out += [f"- `{k}`: {'; '.join(v)}" for k, v in flipped.items()] or ["- none"]
    return "\n".join(out) + "\n"


def render_verdicts(
    table: pd.DataFrame,
    values: Values,
    link: Callable[[str], str] | None = None,
    claims_md: str = "figures/claims.md",
) -> str:
    """The verdict table of ``table`` (``claims.csv`` as strings) and its ``values``, a row per paper claim;
    ``link`` maps a notebook stem to its page, ``claims_md`` is where the readings that flip a claim are."""
    head = [
        "| claim (paper) | paper | planar5 | Panda | readings that flip it | mechanism |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    rows = _by_key(table)
    paper, ours = list(head), list(head)
    for pc in PAPER_CLAIMS:
        cells = [_cell(rows.get((pc.id, r)), values.get((pc.id, r), {})) for r in ROBOTS]
        if cells == ["—", "—"]:
            continue
        notebook = _NOTEBOOKS[pc.id.split(".", 1)[0]]
        target = link(notebook) if link is not None else f"notebooks/{notebook}.ipynb"
        said = "; ".join(s for s in (finding(pc.id, values, ROBOTS), pc.mechanism) if s)
        mech = " ".join(s for s in (said, f"([{notebook[:2]}]({target}{_MECHANISMS}))") if s)
        flipped, n = flips(rows, pc.id)
        listed = f" ([list]({claims_md}#{pc.id.replace('.', '').lower()}))" if flipped else ""
        count = f"{len(flipped)} of {n}{listed}" if n else "none"
        line = f"| {pc.claim} | {pc.paper} | {cells[0]} | {cells[1]} | {count} | {mech} |"
        (ours if pc.ours else paper).append(line)
    out = [f"{count_line(table)} {fragile_line(table)}", "", *paper]
    if len(ours) > len(head):
        out += ["", "Our additions, not claims of the paper (not counted above):", "", *ours]
    return "\n".join(out) + "\n"


def render_summary(table: pd.DataFrame, values: Values) -> str:
    """The README's summary: per effect word its paper claims (why, where not reproduced or not testable)."""
    rows = _by_key(table)
    by_word: dict[str, list[str]] = {}
    for pc in [pc for pc in PAPER_CLAIMS if not pc.ours]:
        words: dict[str, list[str]] = {}
        for robot in [r for r in ROBOTS if (pc.id, r) in rows]:
            words.setdefault(str(rows[(pc.id, robot)].effect), []).append(robot)
        for w, robots in words.items():
            where = on_robots(robots)
            said = f"{pc.short[:-1]}; {where})" if pc.short.endswith(")") else f"{pc.short} ({where})"
            why = finding(pc.id, values, robots) or pc.why
            if w == "not reproduced" and why:
                said += f": {why.replace('; ', ', ')}"
            if w == NOT_TESTABLE:
                row = rows[(pc.id, robots[0])]
                numbers = values.get((pc.id, robots[0]), {})
                said += f": {_untestable_why(row, numbers, 'completion {} within the horizon')}"
            by_word.setdefault(w, []).append(said)
    lines = [
        "**In short.** What reproduced, claim by claim (sims 1–4: simulated users; the study: "
        "simulated participants, not a replication with people; words and N: [the verdicts](#the-verdicts)):"
    ]
    lines += [f"- **{w.capitalize()}** ({len(s)}): {'; '.join(s)}." for w in WORDS if (s := by_word.get(w))]
    _, n, stated = _heads(table)
    lines.append(f"- **The paper's numbers** ({n}, stated for the Panda): {stated}.")
    return "\n".join(lines) + "\n"


def _untestable_why(row: pd.Series, numbers: Numbers, completion: str = "completion: {}") -> str:
    """Why a headline row is not testable: its short conditions' ``completion``, else its ``measured``'s."""
    if short := short_conditions(numbers):
        return completion.format(completion_text(short))
    if str(row.measured).startswith(f"{NOT_TESTABLE} (") and "completion" not in str(row.measured):
        return str(row.measured)[len(NOT_TESTABLE) + 2 :].split(")", 1)[0]
    return "too few episodes finish within the horizon"


def write_verdicts(claims_csv: str | os.PathLike[str], out: str | os.PathLike[str]) -> Path:
    """Render ``claims_csv`` as the verdict table into ``out``, ``summary.md`` beside it, and claims.md."""
    claims_csv = Path(claims_csv)
    table = pd.read_csv(claims_csv, dtype=str, keep_default_na=False)
    values = read_values(pd.read_csv(claims_csv.with_name(VALUES_NAME), dtype=str, keep_default_na=False))
    write_text(claims_csv.with_suffix(".md"), render_markdown(table))
    write_text(Path(out).with_name("summary.md"), render_summary(table, values))
    return write_text(out, render_verdicts(table, values))


def sync_readme(readme: str | os.PathLike[str], table_md: str | os.PathLike[str]) -> bool:
    """Whether the README changed on putting ``table_md`` and its ``summary.md`` between its markers."""
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
    else:
        said = "updated" if sync_readme(sys.argv[1], verdicts) else "already current"
        print(f"{verdicts} written; {Path(sys.argv[1])}: verdict table {said}")
