"""The study server's logging: every line (its own, uvicorn's) to the terminal and to the experimenter's log
file, each with any IP address replaced by ``<ip>`` (:class:`NoAddresses`): what the consent page promises."""

from __future__ import annotations

import logging
import os
import re
from pathlib import Path

# IPv4 (a dotted quad); IPv6 in full (eight groups) or compressed (with "::"), with a dotted quad at its
# end or not: ::1, 2001:db8::1, ::ffff:10.0.0.1
IPV4 = r"(?:\d{1,3}\.){3}\d{1,3}"
GROUPS = r"(?:[0-9A-Fa-f]{1,4}(?::[0-9A-Fa-f]{1,4})*)?"  # hex groups joined by ":", or none
IPV6_FULL = r"(?:[0-9A-Fa-f]{1,4}:){7}[0-9A-Fa-f]{1,4}"
IPV6_SHORT = rf"{GROUPS}::(?:{GROUPS}:{IPV4}|{GROUPS})"
ADDRESS = re.compile(rf"(?<![\w:.])(?:{IPV6_FULL}|{IPV6_SHORT})(?![\w:]|\.\d)|(?<![\w.]){IPV4}(?![\w]|\.\d)")
FORMAT = "%(asctime)s %(levelname)s %(name)s: %(message)s"


def redact(text: str) -> str:
    """``text`` with every IP address replaced by ``<ip>``."""
    return ADDRESS.sub("<ip>", text)


class NoAddresses(logging.Filter):
    """A handler's filter: the record's message (arguments and exception text merged in) without any IP
    address; it never drops a record."""

    def filter(self, record: logging.LogRecord) -> bool:
        message = record.getMessage()
        if record.exc_info and not record.exc_text:
            record.exc_text = logging.Formatter().formatException(record.exc_info)
        record.msg, record.args = redact(message), ()
        if record.exc_text:
            record.exc_text = redact(record.exc_text)
        return True


def setup(path: str | os.PathLike[str], level: str = "INFO") -> Path:
    """Send every record at ``level`` or above to stderr and to the file ``path`` (appended; its folder
    made), both through :class:`NoAddresses`; the log file's path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    root = logging.getLogger()
    root.setLevel(level.upper())
    for handler in (logging.StreamHandler(), logging.FileHandler(path, encoding="utf-8")):
        handler.setFormatter(logging.Formatter(FORMAT))
        handler.addFilter(NoAddresses())
        root.addHandler(handler)
    return path
