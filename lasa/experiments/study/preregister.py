"""The eating study's pre-registration in AsPredicted's order, from the package: the rules, measures and
exclusions are the analysis' own, the sample size the simulated cohort's power (:func:`power_table`).
``python -m lasa.experiments.study.preregister --out prereg.md``; ``[to fill in]`` is the experimenter's."""

from __future__ import annotations

import argparse
import inspect
import re
import sys
from pathlib import Path

import pandas as pd

from lasa.base.conditions import CONDITIONS
from lasa.base.errors import ArtifactError, ConfigError
from lasa.base.io import require_file, write_text
from lasa.evidence.rules import COMPLETION_BAR, rule
from lasa.evidence.sessions import DROPPED, LEFT_OUT, PRACTICE_TASK, QUESTIONS, SCALES
from lasa.experiments.study import analysis as study_analysis
from lasa.experiments.study import power as study_power
from lasa.experiments.study import run as study
from lasa.world import measures
from lasa.world.eating import STUDY_BELIEF_CAP

__all__ = [
    "HYPOTHESES",
    "MEASURES",
    "Reading",
    "cohort",
    "headline_reading",
    "power_table",
    "document",
    "main",
]

# The paper's three hypotheses (Sec. VI), each with the claim whose rule tests it.
HYPOTHESES = {
    "study.h1": "H1: shared autonomy (SA) reduces Goal Error, with retargeting or latent actions.",
    "study.h2": "H2: with SA, latent actions (LA+SA) align the fork with the preference better than "
    "retargeting (R+SA) in the Dessert's scoop phase.",
    "study.h3": "H3: LA+SA completes the tasks faster, and with less idle time, than every other condition.",
}
# The dependent variables: each one's definition is the first line of the function that computes it.
MEASURES = {
    "Total Time": measures.total_time,
    "Idle Time": measures.idle_time,
    "Goal Error": measures.goal_error,
    "Preference Alignment": measures.alignment,
}

Reading = tuple[str, str, str]  # (SA member, decoder reading, participant model)


def definition(function: object) -> str:
    """The first line of a measure's docstring, its definition (without the array shape it ends with)."""
    return re.sub(r",? \(E,\)\.$", ".", inspect.getdoc(function).splitlines()[0])  # type: ignore[union-attr]


def cohort(figures: Path) -> dict[str, pd.DataFrame]:
    """The simulated cohort's committed tables (``study_{goal_error,time,alignment}.csv``)."""
    return {
        name: pd.read_csv(require_file(figures / f"study_{name}.csv", "make figures (notebook 11)"))
        for name in ("goal_error", "time", "alignment")
    }


def headline_reading(figures: Path, frames: dict[str, pd.DataFrame]) -> Reading:
    """Notebook 11's headline: its first SA member, the property rule's decoder, its model rule's model."""
    config = study.Config()
    decoder = study.variants_to_run(study.eating_property(figures), "property")[0]
    model = study_analysis.headline_model(frames["time"], config.participant_models)
    return config.session.assistance[0], decoder, model


def power_table(
    frames: dict[str, pd.DataFrame],
    reading: Reading,
    draws: int,
    sizes: tuple[int, ...],
    n_jobs: int = 1,
    progress: bool = False,
) -> pd.DataFrame:
    """:func:`lasa.experiments.study.power.power` on the simulated cohort's ``frames``, for ``reading``."""
    from lasa.world.eating import load_eating_robot

    assistance, decoder, model = reading
    config = study.Config()
    horizon = config.session.horizon * load_eating_robot().control.dt  # notebook 11's [s]
    return study_power.power(
        frames,
        assistance,
        decoder=decoder,
        model=model,
        sizes=sizes,
        draws=draws,
        seed=config.seed,
        horizon=horizon,
        n_jobs=n_jobs,
        progress=progress,
    )


def _power_lines(table: pd.DataFrame) -> list[str]:
    need = study_power.needed(table)
    lines = ["| hypothesis | " + " | ".join(f"n = {n}" for n in sorted(set(table.n))) + " |"]
    lines.append("| --- |" + " ---: |" * len(set(table.n)))
    for claim, rows in table.groupby("claim", sort=False):
        cells = [f"{p:.2f}" for p in rows.sort_values("n").power]
        lines.append(f"| {claim.upper()} | " + " | ".join(cells) + " |")
    lines += ["", *[f"- {study_power.sentence(need, claim)}" for claim in study_power.POWER_CLAIMS]]
    return lines


def document(
    table: pd.DataFrame,
    reading: Reading,
    practice_s: float,
    trial_s: float,
    conditions: tuple[str, ...] = CONDITIONS,
    belief_cap: float = STUDY_BELIEF_CAP,
) -> str:
    """The pre-registration, Markdown, from the power ``table`` of ``reading`` and the server's settings."""
    assistance, decoder, model = reading
    bar = f"{100 * COMPLETION_BAR:.0f}%"
    variables = [f"- {definition(fn)}" for fn in MEASURES.values()]
    variables += ["- Questionnaire, after each condition, 7-point Likert (1 = strongly disagree):"]
    variables += [f"  - {scale}: {QUESTIONS[scale]}" for scale in SCALES]
    blocks = [  # each a paragraph or list, a blank line between
        "# Pre-registration: shared autonomy with learned latent actions, the eating study",
        "Generated by `python -m lasa.experiments.study.preregister` from the `lasa` package: every rule "
        "below is the one its analysis (notebook 11 with `sessions_dir`) applies.",
        "## 1. Data collection",
        "Have any data been collected for this study already? [to fill in]",
        "## 2. Hypotheses",
        "\n".join(
            f"- **{t}** Test and decision rule (`{c}`): {rule(c).text}." for c, t in HYPOTHESES.items()
        ),
        "## 3. Dependent variables",
        "\n".join(variables),
        "## 4. Conditions",
        f"Within subjects, 2 x 2: interface (retargeting R, latent actions LA) x shared autonomy (without, "
        f"with SA): {', '.join(conditions)}. Participants see each condition as a letter in their own "
        "order (A-D), never its name. The robot's belief is not shown.",
        "The robot's belief over the goals is Javdani et al.'s (2018), whose shared autonomy the paper's "
        "study ran, as their implementation keeps it: after each Bayesian update no goal keeps more than "
        f"{belief_cap:g}, the excess spread evenly over the other goals. The latent-action decoder was "
        "trained with the same belief.",
        "## 5. Analyses",
        f"Significance level .05, two-sided. H1 and H3 are judged only if every condition finishes at least "
        f"{bar} of its episodes (H2: LA+SA and R+SA), as stated in each rule above; H3's restricted times "
        f"end at the trials' limit ({trial_s:g} s). Notebook 11 applies these tests and rules to the "
        "sessions (`lasa.evidence.hypotheses.people_claims`: the simulated cohort's own `analyse` and "
        f"`judge`). The planned reading: SA as `{assistance}`, the latent-action decoder `{decoder}`.",
        "## 6. Outliers and exclusions",
        "Sessions left out of every analysis, each named with its reason:",
        "\n".join(f"- {reason}" for reason in LEFT_OUT.values()),
        f"Participants left out of a within-subject test: {DROPPED}",
        "## 7. Sample size",
        f"From the simulated cohort (participant model `{model}`): the power of each hypothesis's own test "
        f"for cohorts of n drawn from the simulated participants ({int(table.draws.iloc[0])} draws per n). "
        "These numbers say what a replication needs if people differed as the simulated ones do.",
        "\n".join(_power_lines(table)),
        "N = [to fill in: at least the largest n above for the hypotheses you test, a multiple of 4]",
        "## 8. Design",
        f"Each participant: consent; then, for each condition in a balanced Latin square order (Williams: "
        f"each condition first once and after each other once per 4 participants), a practice on the "
        f"{PRACTICE_TASK} of up to {practice_s:g} s, the Entree and the Dessert tasks (each at most "
        f"{trial_s:g} s), and the questionnaire.",
        "## 9. Other",
        "[to fill in]",
    ]
    return "\n\n".join(blocks) + "\n"


def main(argv: list[str] | None = None) -> int:
    """Command line: write the pre-registration (after ``make figures``)."""
    parser = argparse.ArgumentParser(
        prog="python -m lasa.experiments.study.preregister",
        description="write the study's pre-registration (Markdown), generated from the package",
    )
    parser.add_argument("--out", default="build/preregistration.md", help="the document [%(default)s]")
    parser.add_argument("--figures", default="figures", help="make figures' folder [%(default)s]")
    parser.add_argument(
        "--practice-s", type=float, default=300.0, help="the server's --practice-s [%(default)s]"
    )
    parser.add_argument("--trial-s", type=float, default=300.0, help="the server's --trial-s [%(default)s]")
    parser.add_argument("--draws", type=int, default=100, help="drawn cohorts per n [%(default)s]")
    parser.add_argument(
        "--sizes", type=int, nargs="+", default=list(study_power.SIZES), help="cohort sizes [%(default)s]"
    )
    parser.add_argument("--jobs", type=int, default=1, help="worker processes of the power [%(default)s]")
    args = parser.parse_args(argv)
    figures = Path(args.figures)
    try:
        frames = cohort(figures)
        reading = headline_reading(figures, frames)
        table = power_table(frames, reading, args.draws, tuple(args.sizes), args.jobs, progress=True)
    except (ConfigError, ArtifactError) as exc:  # a bad setting; the figures' tables missing
        print(f"error: {exc}", file=sys.stderr)
        return 2
    text = document(table, reading, args.practice_s, args.trial_s)
    print(f"pre-registration: {write_text(args.out, text)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
