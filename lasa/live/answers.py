"""The questionnaires' tidy tables beside the sessions: ``tlx.csv`` (participant, condition, subscale,
value), ``comments.csv`` (participant, condition, comment) and ``demographics.csv`` (participant, item,
answer), each written atomically under the folder's lock. A participant's rows for one condition (or their
demographics) are written once: the same rows again pass (a server that crashed between the answers'
write and the progress step asks again); other rows for them are refused."""

from __future__ import annotations

import os
import unicodedata
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import NoReturn

import pandas as pd

from lasa.base.errors import ConfigError
from lasa.base.io import locked, write_csv
from lasa.evidence.questionnaire import COMMENT_CHARS, DEMOGRAPHICS, TLX_STEP, TLX_SUBSCALES


def answered(path: Path, key: Mapping[str, str]) -> tuple[pd.DataFrame | None, pd.Series | None]:
    """The CSV at ``path`` as text (None if there is none) and which of its rows hold ``key``'s values."""
    if not path.is_file():
        return None, None
    old = pd.read_csv(path, dtype=str, keep_default_na=False)
    mine = pd.Series(True, index=old.index)
    for column, value in key.items():
        mine &= old[column] == value
    return old, mine


def refuse_answered(path: Path, key: Mapping[str, str]) -> NoReturn:
    """A ConfigError saying that ``key``'s participant answered already (in ``path``)."""
    after = f" for {key['condition']}" if "condition" in key else ""
    raise ConfigError(
        f"{key['participant']} answered{after} already in {path}: pass --overwrite to replace those answers"
    )


def record(path: Path, new: pd.DataFrame, key: Mapping[str, str], overwrite: bool = False) -> Path:
    """Add ``new`` (rows whose ``key`` columns hold ``key``'s values) to the CSV at ``path``: the same rows
    recorded before pass, other rows recorded before for ``key`` are a ConfigError unless ``overwrite``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with locked(path.parent):
        old, mine = answered(path, key)
        if old is not None and mine is not None:
            if mine.any() and not overwrite:
                if old[mine].reset_index(drop=True).equals(new.astype(str).reset_index(drop=True)):
                    return path  # the same answers again: recorded already
                refuse_answered(path, key)
            new = pd.concat([old[~mine], new.astype(str)], ignore_index=True)
        write_csv(path, new)
    return path


def parse_tlx(values: Sequence[object]) -> list[int]:
    """The six TLX ratings, each a whole number 0..100 in steps of :data:`TLX_STEP`, else a ConfigError."""
    if len(values) != len(TLX_SUBSCALES) or not all(type(v) is int for v in values):
        raise ConfigError(
            f"give {len(TLX_SUBSCALES)} TLX ratings ({', '.join(TLX_SUBSCALES)}), got {values!r}"
        )
    ints = [int(v) for v in values]  # type: ignore[call-overload]
    if not all(0 <= v <= 100 and v % TLX_STEP == 0 for v in ints):
        raise ConfigError(f"a TLX rating is 0..100 in steps of {TLX_STEP}, got {values!r}")
    return ints


def record_tlx(
    folder: str | os.PathLike[str],
    participant: str,
    condition: str,
    values: Sequence[object],
    overwrite: bool = False,
) -> Path:
    """Record ``participant``'s TLX ratings (:func:`parse_tlx`) after ``condition`` (``tlx.csv``)."""
    new = pd.DataFrame(
        {
            "participant": participant,
            "condition": condition,
            "subscale": TLX_SUBSCALES,
            "value": parse_tlx(values),
        }
    )
    key = {"participant": participant, "condition": condition}
    return record(Path(folder) / "tlx.csv", new, key, overwrite)


def clean_comment(text: object) -> str:
    """A free-text comment as stored: at most :data:`COMMENT_CHARS` characters, control characters (but line
    breaks) dropped, surrounding blanks trimmed; a ConfigError for a non-string or a longer one."""
    if not isinstance(text, str) or len(text) > COMMENT_CHARS:
        raise ConfigError(f"a comment is text of at most {COMMENT_CHARS} characters")
    kept = "".join(c for c in text if c in "\n\t" or unicodedata.category(c)[0] != "C")
    return kept.strip()


def record_comment(
    folder: str | os.PathLike[str], participant: str, condition: str, text: object, overwrite: bool = False
) -> Path | None:
    """Record ``participant``'s comment after ``condition`` (``comments.csv``); None if empty."""
    comment = clean_comment(text)
    if not comment:
        return None
    new = pd.DataFrame({"participant": [participant], "condition": [condition], "comment": [comment]})
    key = {"participant": participant, "condition": condition}
    return record(Path(folder) / "comments.csv", new, key, overwrite)


def parse_demographics(answers: Mapping[str, object]) -> dict[str, str]:
    """The demographics form's answers: a known item each, with one of its answers, else a ConfigError."""
    if not isinstance(answers, Mapping) or not set(answers) <= set(DEMOGRAPHICS):
        raise ConfigError(f"demographics answer the items {tuple(DEMOGRAPHICS)} only")
    for item, answer in answers.items():
        if answer not in DEMOGRAPHICS[item]:
            raise ConfigError(f"{item} is answered by one of {DEMOGRAPHICS[item]}")
    return {item: str(answers[item]) for item in DEMOGRAPHICS if item in answers}


def record_demographics(
    folder: str | os.PathLike[str], participant: str, answers: Mapping[str, object]
) -> Path | None:
    """Record ``participant``'s demographics in ``<folder>/demographics.csv`` (None: nothing answered)."""
    chosen = parse_demographics(answers)
    if not chosen:
        return None
    new = pd.DataFrame({"participant": participant, "item": list(chosen), "answer": list(chosen.values())})
    return record(Path(folder) / "demographics.csv", new, {"participant": participant})
