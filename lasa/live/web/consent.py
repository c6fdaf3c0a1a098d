"""The consent page: a Markdown text (``--consent FILE``, else the package's example,
``consent_example.md``) whose duration placeholders (:data:`PLACEHOLDERS`) the server fills in from its
settings, rendered to HTML on the server by markdown-it-py with raw HTML off: the file cannot put a script
or a tag into the page."""

from __future__ import annotations

import os
import re
from pathlib import Path

from markdown_it import MarkdownIt

from lasa.base.errors import ConfigError
from lasa.base.io import write_text

EXAMPLE = Path(__file__).with_name("consent_example.md")
# {practice}, {trial}: the longest practice and trial; {total}: the longest the study takes; {conditions}:
# how many ways of controlling the robot, in words
PLACEHOLDERS = ("practice", "trial", "total", "conditions")
FIELD = re.compile(r"\{([a-z_]+)\}")
NUMBERS = ("no", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten")


def duration(seconds: float) -> str:
    """A duration as a person reads it: "45 seconds", "1 minute", "5 minutes", "about 1.5 hours"."""
    if seconds < 90:
        return f"{round(seconds)} seconds"
    minutes = round(seconds / 60)
    if minutes < 90:
        return "1 minute" if minutes == 1 else f"{minutes} minutes"
    hours = round(minutes / 30) / 2
    return "about an hour" if hours == 1 else f"about {hours:g} hours"


def read_consent(path: str | os.PathLike[str] | None) -> str:
    """The consent text at ``path`` (None or "": the package's example), checked: a ConfigError names an
    unreadable file or a ``{placeholder}`` the server does not fill in."""
    source = Path(path) if path else EXAMPLE
    try:
        text = source.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"the consent file {source} cannot be read ({exc})") from None
    unknown = sorted({name for name in FIELD.findall(text) if name not in PLACEHOLDERS})
    if unknown:
        raise ConfigError(
            f"the consent file {source} has placeholders {unknown} the server does not fill in; "
            f"it fills in {['{' + p + '}' for p in PLACEHOLDERS]}"
        )
    return text


def render_consent(text: str, practice_s: float, trial_s: float, conditions: int, longest_min: float) -> str:
    """``text`` with its placeholders filled in, as HTML (raw HTML in the text is shown as text)."""
    values = {
        "practice": duration(practice_s),
        "trial": duration(trial_s),
        "total": duration(60.0 * longest_min),
        "conditions": NUMBERS[conditions] if 0 <= conditions < len(NUMBERS) else str(conditions),
    }
    filled = FIELD.sub(lambda m: values.get(m.group(1), m.group(0)), text)
    return str(MarkdownIt("commonmark", {"html": False}).render(filled))


def write_template(out: str | os.PathLike[str]) -> Path:
    """Write the package's consent template (the example text) to ``out``; an existing file is kept."""
    if Path(out).exists():
        raise ConfigError(f"{out} exists already: give another --out")
    return write_text(out, EXAMPLE.read_text(encoding="utf-8"))
