"""The messages between the page and the server: the page's (:data:`KINDS`, JSON of at most
:data:`MAX_MESSAGE_BYTES`, at most :data:`MAX_RATE` a second; anything else ends the connection) and the
server's (``phase``, ``tick``, ``scene``, ``labels``, ``refused``, ``error``; JPEG frames with ``--frames
server``)."""

from __future__ import annotations

import dataclasses
import json
import math
import time
from typing import Any

import numpy as np

from lasa.base.errors import LasaError
from lasa.live.devices import StickSample
from lasa.live.web.tokens import MAX_TOKEN_CHARS

MAX_MESSAGE_BYTES = 4096
MAX_RATE = 50.0  # messages per second, averaged over a burst of as many
STALE_S = 0.5  # input older than this reads as disconnected: zero input, never a held command
# hello (the token, first), consent, demographics (answers or skip), start (device), finish, input (axes,
# mode, stop), survey (answers, tlx, comment), beat (the page's heartbeat, every second in every step) and
# ready (the trial's picture is drawn: its clock starts)
KINDS = ("hello", "consent", "demographics", "start", "finish", "input", "survey", "beat", "ready")
DEVICE_ID_CHARS = 100  # a gamepad's name as the browser reports it: free text, kept this short


class ProtocolError(LasaError, ValueError):
    """A message the server refuses; the connection is closed with :attr:`code`."""

    def __init__(self, message: str, code: int = 1008) -> None:
        super().__init__(message)
        self.code = code


def _no_constants(name: str) -> float:
    raise ProtocolError(f"{name} is not a number the protocol accepts")


def parse(text: str | bytes | None) -> dict[str, Any]:
    """One page message, checked: its size, JSON, type and fields (else :class:`ProtocolError`)."""
    if not isinstance(text, str):
        raise ProtocolError("messages are JSON text")
    if len(text.encode()) > MAX_MESSAGE_BYTES:
        raise ProtocolError(f"a message is at most {MAX_MESSAGE_BYTES} bytes", code=1009)
    try:
        msg = json.loads(text, parse_constant=_no_constants)
    except (json.JSONDecodeError, RecursionError, ValueError) as exc:  # deep nesting; 5,000-digit ints
        raise ProtocolError("a message is one JSON object") from exc
    if not isinstance(msg, dict) or msg.get("type") not in KINDS:
        raise ProtocolError(f"a message's type is one of {KINDS}")
    token = msg.get("token")
    if msg["type"] == "hello" and not (isinstance(token, str) and len(token) <= MAX_TOKEN_CHARS):
        raise ProtocolError("hello carries the token, a short string")
    if msg["type"] == "input":
        axes = msg.get("axes")
        if not (isinstance(axes, list) and len(axes) == 2 and all(_number(a) for a in axes)):
            raise ProtocolError("input carries two numeric axes")
        if not isinstance(msg.get("mode", False), bool) or not isinstance(msg.get("stop", False), bool):
            raise ProtocolError("input's mode and stop are true or false")
    if msg["type"] == "survey" and not _short_ints(msg.get("answers")):
        raise ProtocolError("survey answers are a short list of integers")
    _check_study(msg)
    return msg


def _short_ints(value: Any) -> bool:
    """Whether ``value`` is a list of at most 16 integers (a form's ratings)."""
    return isinstance(value, list) and len(value) <= 16 and all(type(v) is int for v in value)


def _check_study(msg: dict[str, Any]) -> None:
    """The questionnaires' and the device's fields: their shapes (their values are the study's to check)."""
    if msg["type"] == "survey":
        if not _short_ints(msg.get("tlx", [])):
            raise ProtocolError("survey's tlx is a short list of integers")
        if not isinstance(msg.get("comment", ""), str):
            raise ProtocolError("survey's comment is text")
    if msg["type"] == "demographics":
        answers = msg.get("answers", {})
        if not (
            isinstance(answers, dict)
            and len(answers) <= 16
            and all(isinstance(a, str) for a in answers.values())
        ):
            raise ProtocolError("demographics answers are a short object of text")
    if msg["type"] == "start":
        msg["device"] = device(msg.get("device"))


def device(raw: Any) -> dict[str, str]:
    """The input device a ``start`` names, as its session records it: ``{"kind": "keyboard"}`` or
    ``{"kind": "gamepad", "id": ..., "mapping": ...}`` (the id and mapping cut to
    :data:`DEVICE_ID_CHARS` printable characters); a start naming none: ``{"kind": "unknown"}``."""
    if raw is None:
        return {"kind": "unknown"}
    if not isinstance(raw, dict) or raw.get("kind") not in ("keyboard", "gamepad"):
        raise ProtocolError("start's device is a keyboard or a gamepad")
    if raw["kind"] == "keyboard":
        return {"kind": "keyboard"}
    text = {k: raw.get(k, "") for k in ("id", "mapping")}
    if not all(isinstance(v, str) for v in text.values()):
        raise ProtocolError("a gamepad's id and mapping are text")
    clean = {k: "".join(c for c in v if c.isprintable())[:DEVICE_ID_CHARS] for k, v in text.items()}
    return {"kind": "gamepad"} | clean


def _number(value: Any) -> bool:
    """A finite int or float (a 400-digit int is not: as a float it overflows)."""
    if type(value) not in (int, float):
        return False
    try:
        return math.isfinite(float(value))
    except OverflowError:
        return False


class RateLimit:
    """A token bucket: :data:`MAX_RATE` messages a second, bursts of up to as many."""

    def __init__(self) -> None:
        self._level = MAX_RATE
        self._last = time.monotonic()

    def allow(self) -> bool:
        """Whether one more message is within the limit now."""
        now = time.monotonic()
        self._level = min(MAX_RATE, self._level + (now - self._last) * MAX_RATE)
        self._last = now
        if self._level < 1.0:
            return False
        self._level -= 1.0
        return True


@dataclasses.dataclass
class Inputs:
    """The latest input of one page: what the next control step reads (:meth:`take`)."""

    axes: tuple[float, float] = (0.0, 0.0)
    mode: bool = False
    stop: bool = False
    received: float = -math.inf

    def reset(self) -> None:
        """A zero stick, nothing pressed, nothing received: how every step starts."""
        self.axes, self.mode, self.stop, self.received = (0.0, 0.0), False, False, -math.inf

    def update(self, msg: dict[str, Any]) -> None:
        """Take an ``input`` message; a mode press is kept until a step reads it."""
        # a stick reads [-1, 1] (the Gamepad API's range): 1e308 is the stick held, logged as 1
        self.axes = tuple(min(1.0, max(-1.0, float(a))) for a in msg["axes"][:2])  # type: ignore[assignment]
        self.mode = self.mode or bool(msg.get("mode", False))
        self.stop = bool(msg.get("stop", False))
        self.received = time.monotonic()

    def take(self) -> StickSample:
        """This step's sample; stale input (a stalled page or network) reads as disconnected."""
        fresh = time.monotonic() - self.received <= STALE_S
        sample = StickSample(
            raw=np.array(self.axes, dtype=float), mode=self.mode and fresh, stop=self.stop, connected=fresh
        )
        self.mode = False
        return sample
