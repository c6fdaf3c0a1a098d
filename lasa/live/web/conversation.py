"""One participant's connection: the protocol's steps (:mod:`lasa.live.web.plan`), driven by the server over
one WebSocket, and each trial's loop (:func:`run_trial`). Page input updates the next tick's sample; a page
gone mid-trial leaves its session ``interrupted`` and its progress where it was, for its link to resume."""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import dataclasses
import logging
import math
import secrets
import time
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from starlette.websockets import WebSocket

from lasa.base.errors import ArtifactError, ConfigError
from lasa.evidence.questionnaire import page_demographics, page_questions
from lasa.evidence.sessions import disconnected_flag
from lasa.live.answers import (
    answered,
    clean_comment,
    parse_tlx,
    record_comment,
    record_demographics,
    record_tlx,
)
from lasa.live.devices import StickSample
from lasa.live.session import Session, open_log
from lasa.live.station import SessionConfig, Station
from lasa.live.studykit import parse_answer, survey
from lasa.live.web.consent import render_consent
from lasa.live.web.plan import Step, plan_of
from lasa.live.web.protocol import Inputs, ProtocolError, RateLimit, parse
from lasa.world.instructions import DISPLAY_NAMES

if TYPE_CHECKING:
    from lasa.live.web.app import Study


LOG = logging.getLogger("lasa.live.web")
# Page messages (consent, start, survey, ready, hello) waiting for the step that reads them: a connection
# holds at most this many; more, and any a step did not ask for, are dropped and counted.
QUEUE_MAX = 8
# How long a trial waits for the page to draw its picture (--frames browser) before its clock starts [s]
READY_S = 15.0
# How long a trial waits for the page's first input after its Start (it sends 20 a second) [s]
FIRST_INPUT_S = 1.0
# A page silent this long (no heartbeat, no message) is noted in the experimenter's log [s]
SILENT_S = 3.0
# Close code of a connection a newer page of the same link took over (a private code: 4000-4999)
REPLACED = 4000
# What a participant reads when something goes wrong: a few fixed, plain messages, never a condition's
# code, a path or an option (the detail goes to the experimenter's log).
MESSAGES = {
    "unavailable": "The study cannot go on right now, through no fault of yours. Please tell the person "
    "who sent you the link; you can come back with the same link later.",
    "answers": "Please answer every question with one of the choices shown, then submit again.",
    "not_saved": "Your answers could not be saved, through no fault of yours. Please try again in a "
    "moment; if this happens again, tell the person who sent you the link.",
}
UNAVAILABLE = MESSAGES["unavailable"]


def _first_line(exc: Exception) -> str:
    return " ".join(str(exc).split())[:300]


class Gone(Exception):
    """The page went away (or was sent away for a refused message)."""


@dataclasses.dataclass
class Conversation:
    """The connection of participant ``participant`` (an id from the schedule) to ``study``."""

    ws: WebSocket
    study: Study
    participant: str
    inputs: Inputs = dataclasses.field(default_factory=Inputs)
    gone: bool = False
    finish: bool = False
    dropped: int = 0  # out-of-step page messages dropped (logged when the connection ends)
    why: str = ""  # why the connection ended, for the experimenter's log

    def __post_init__(self) -> None:
        self._queue: asyncio.Queue[dict[str, Any]] = asyncio.Queue(QUEUE_MAX)
        self._send_lock = asyncio.Lock()
        self._frames: set[asyncio.Task[None]] = set()
        self.ended = asyncio.Event()  # set once run() has returned: the trial (if any) is closed
        self.heard = time.monotonic()  # the page's last message (a heartbeat at least every second)
        self._silent = False  # whether the log says the page went silent

    async def run(self) -> None:
        """Serve the participant until their plan is done or the page goes."""
        receiver = asyncio.create_task(self._receive())
        step = int(self.study.progress.of(self.participant)["step"])
        LOG.info("participant %s: joined at step %d", self.participant, step + 1)
        try:
            with contextlib.suppress(Gone):
                await self._protocol()
        finally:
            receiver.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await receiver
            if self.dropped:
                LOG.info("participant %s: %d out-of-step messages dropped", self.participant, self.dropped)
            LOG.info("participant %s: connection closed: %s", self.participant, self.why or "the page went")
            self.ended.set()

    async def replace(self) -> None:
        """End this connection for a newer page of the same link: its trial (if any) ends ``interrupted``,
        the page is closed with :data:`REPLACED` (it says the study goes on in another window)."""
        self.why = f"a newer page of the same link took over (close {REPLACED})"
        self._end()
        with contextlib.suppress(Exception):
            await asyncio.wait_for(self.ws.close(code=REPLACED, reason="replaced"), 1.0)

    def _end(self) -> None:
        """The page is gone: the trial loop stops at its next tick, a waiting step wakes."""
        self.gone = True
        if self._queue.full():  # the end always reaches the step waiting for a message
            self._queue.get_nowait()
            self.dropped += 1
        self._queue.put_nowait({"type": "_gone"})

    async def _receive(self) -> None:
        limit = RateLimit()
        try:
            while (message := await self.ws.receive())["type"] != "websocket.disconnect":
                if not limit.allow():
                    raise ProtocolError("too many messages")
                msg = parse(message.get("text"))
                self._heard()
                if msg["type"] == "input":
                    self.inputs.update(msg)
                elif msg["type"] == "finish":
                    self.finish = True
                elif msg["type"] != "beat":
                    self._put(msg)
            self.why = self.why or f"the page closed it (code {message.get('code', 1005)})"
        except ProtocolError as exc:
            self.why = self.why or f"a refused message: {exc} (close {exc.code})"
            with contextlib.suppress(Exception):  # the page shows its own plain words for the code
                await self.ws.close(code=exc.code, reason="refused message")
        except Exception as exc:  # a broken connection: the page is gone either way
            self.why = self.why or f"the connection broke ({type(exc).__name__})"
        finally:
            if not self.gone:
                self._end()

    def _heard(self) -> None:
        now = time.monotonic()
        if self._silent:
            LOG.info("participant %s: page heard again after %.1f s", self.participant, now - self.heard)
            self._silent = False
        self.heard = now

    def silent(self) -> bool:
        """Whether the page has sent nothing for :data:`SILENT_S` (noted once in the log)."""
        quiet = time.monotonic() - self.heard > SILENT_S
        if quiet and not self._silent:
            LOG.info("participant %s: page silent for %.0f s (a frozen tab?)", self.participant, SILENT_S)
            self._silent = True
        return quiet

    def _put(self, msg: dict[str, Any]) -> None:
        try:
            self._queue.put_nowait(msg)
        except asyncio.QueueFull:
            self.dropped += 1

    def _clear(self) -> None:
        """Drop and count what the page sent before this step (a second Start, an early survey)."""
        while not self._queue.empty():
            msg = self._queue.get_nowait()
            if msg["type"] == "_gone":
                raise Gone
            self.dropped += 1

    async def send(self, message: dict[str, Any] | bytes) -> None:
        """Send one JSON message (bytes: a JPEG frame); a failed send means the page is gone."""
        try:
            async with self._send_lock:
                if isinstance(message, bytes):
                    await self.ws.send_bytes(message)
                else:
                    await self.ws.send_json(message)
        except Exception:
            self.gone = True

    async def _expect(self, kind: str, timeout: float | None = None) -> dict[str, Any] | None:
        """The page's next ``kind`` message (others dropped and counted); None after ``timeout`` [s]."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            try:
                left = None if deadline is None else max(0.0, deadline - time.monotonic())
                msg = await asyncio.wait_for(self._queue.get(), left)
            except TimeoutError:
                return None
            if msg["type"] == "_gone":
                raise Gone
            if msg["type"] == kind:
                return msg
            self.dropped += 1

    async def _protocol(self) -> None:
        study, participant = self.study, self.participant
        plan = plan_of(study.config.sessions, participant)
        if not study.progress.of(participant)["consented"]:
            await self._consent(plan)
        done = study.progress.of(participant)
        if not done.get("demographics") and int(done["step"]) == 0:  # before the first practice only
            await self._demographics()
        while not study.progress.finished(participant, plan):
            self._clear()
            index = int(study.progress.of(participant)["step"])
            step = plan[index]
            # the condition's letter, never its code (the page is blind to it, as the paper's people were)
            header: dict[str, Any] = {"type": "phase", "kind": step.kind, "label": step.label}
            header |= {"task": step.task, "index": index + 1, "total": len(plan)}
            if study.resume.pop(participant, None) == index:  # the page left this trial: it starts again
                header["resume"] = True
            if step.kind == "survey":
                await self._survey(step, header)
            else:
                limit = study.config.practice_s if step.kind == "practice" else study.config.trial_s
                await self.send(header | {"limit_s": limit})
                device = (await self._expect("start") or {}).get("device")
                if await self._drive(step, limit, device) != "complete":
                    study.resume[participant] = index
                    raise Gone
            study.progress.count(participant, "step")
        await self.send(self._thanks())
        self.why = "the study is finished (close 1000)"
        with contextlib.suppress(Exception):
            await self.ws.close(code=1000)

    async def _consent(self, plan: list[Step]) -> None:
        """The consent text (the server's HTML, its durations filled in) until the participant agrees; with
        ``--frames browser`` the page first checks that it can draw the robot (``webgl``)."""
        config = self.study.config
        durations = config.durations(len({step.condition for step in plan}))
        html = render_consent(
            self.study.consent,
            durations["practice_s"],
            durations["trial_s"],
            int(durations["conditions"]),
            durations["longest_min"],
        )
        webgl = config.frames == "browser"
        await self.send({"type": "phase", "kind": "consent", "html": html, "webgl": webgl} | durations)
        await self._expect("consent")
        self.study.progress.consent(self.participant)

    async def _demographics(self) -> None:
        """The optional demographics form, once, before the first practice: answered (in part) or skipped."""
        await self.send({"type": "phase", "kind": "demographics", "items": page_demographics()})
        while True:
            msg = await self._expect("demographics")
            assert msg is not None  # no timeout
            try:
                if not msg.get("skip"):
                    record_demographics(self.study.config.sessions, self.participant, msg.get("answers", {}))
                break
            except ConfigError as exc:
                LOG.warning("participant %s: demographics refused: %s", self.participant, _first_line(exc))
                await self.send({"type": "error", "message": MESSAGES["answers"]})
        self.study.progress.mark(self.participant, "demographics")

    async def _survey(self, step: Step, header: dict[str, Any]) -> None:
        """The questionnaire after a way: the Likert items, the TLX and the optional comment, checked whole,
        then stored (the Likert answers last: stored, they mark the whole form stored); a refused form gets
        a fixed message, the detail going to the experimenter's log (never the comment)."""
        await self.send(header | page_questions())
        folder, who, condition = self.study.config.sessions, self.participant, step.condition
        while True:
            msg = await self._expect("survey")
            assert msg is not None  # no timeout
            if self._answered(step):  # stored before a crash kept the step from being counted: go on
                LOG.info("participant %s: %s answers stored already; going on", who, condition)
                return
            try:
                parse_tlx(msg.get("tlx", []))  # every part checked before any is written
                clean_comment(msg.get("comment", ""))
                for answer in msg["answers"]:
                    parse_answer(answer)
                record_tlx(folder, who, condition, msg.get("tlx", []), overwrite=True)  # a form never stored
                record_comment(folder, who, condition, msg.get("comment", ""), overwrite=True)
                survey(folder, who, condition, msg["answers"])
                return
            except ConfigError as exc:
                LOG.warning("participant %s: questionnaire refused: %s", who, _first_line(exc))
                await self.send({"type": "error", "message": MESSAGES["answers"]})
            except OSError as exc:
                LOG.error("participant %s: questionnaire not stored: %s", who, exc)
                await self.send({"type": "error", "message": MESSAGES["not_saved"]})

    def _answered(self, step: Step) -> bool:
        """Whether the participant's answers for ``step``'s condition are stored already."""
        key = {"participant": self.participant, "condition": step.condition}
        _, mine = answered(Path(self.study.config.sessions) / "likert.csv", key)
        return mine is not None and bool(mine.any())

    def _thanks(self) -> dict[str, Any]:
        """The thank-you page: the participant's id (to quote in a withdrawal request) and the completion
        code and link of the recruiting site, if the server has them."""
        config = self.study.config
        return {
            "type": "phase",
            "kind": "thanks",
            "participant": self.participant,
            "code": config.completion_code,
            "url": config.completion_url,
        }

    async def _drive(self, step: Step, limit_s: float, device: dict[str, str] | None = None) -> str:
        study, practice = self.study, step.kind == "practice"
        config = SessionConfig("panda", step.task, step.condition, self.participant, study.config.build_dir)
        self.finish = False
        self.inputs.reset()  # a zero stick: nothing the page sent before this Start moves the robot
        attempt = study.progress.count(self.participant, "attempts")
        folder = Path(study.config.sessions, "practice" if practice else "")  # the analysis reads trials only
        try:
            trial = await asyncio.to_thread(open_trial, config, folder, attempt, limit_s, step.order, device)
        except (ConfigError, ArtifactError, OSError) as exc:
            # the detail (paths, commands) is the experimenter's, in the server's log; never the page's
            LOG.error("participant %s cannot run %s %s: %s", self.participant, step.task, step.condition, exc)
            await self.send({"type": "error", "message": UNAVAILABLE})
            self.why = "the server could not run the step"
            raise Gone from exc
        if study.config.frames != "none":  # the goals' names over the picture
            await self.send({"type": "labels", "labels": study.labels(trial.station)})
        key = None
        if study.config.frames == "browser":
            # the page fetches this trial's scene (GET /scene) and draws the robot from the ticks' q
            # with a key of its own (X-Scene-Key), valid while the trial runs: no token in a URL
            assert trial.writer is not None  # open_trial always logs
            key = secrets.token_urlsafe(24)
            study.scenes[key] = trial.writer.csv.with_suffix(".xml")
            robot = trial.station.robot
            qpos_adr = robot.qpos_adr.tolist()
            camera = robot.model.camera(robot.spec.camera).id
            q = [float(v) for v in trial.station.state]
            await self.send({"type": "scene", "key": key, "qpos_adr": qpos_adr, "camera": camera, "q": q})
        try:
            try:
                await self._picture(trial)
            except BaseException:  # the server stopping while the page loads: no step ran
                trial.close("interrupted")
                raise
            status = await run_trial(
                trial, self.inputs, self._tick, self._connected, lambda: practice and self.finish
            )
        finally:
            study.scenes.pop(key or "", None)
        if status != "complete":
            assert trial.writer is not None
            LOG.info(
                "participant %s: %s %s, way %s (%s), attempt %d interrupted after %d steps: %s",
                self.participant, step.kind, step.task, step.label, step.condition, attempt,
                trial.steps, self.why or "the page went",
            )  # fmt: skip
        return status

    async def _picture(self, trial: Session) -> None:
        """Wait until the page shows the robot, so that the clock starts with a picture: the page's
        ``ready`` (``--frames browser``; at most :data:`READY_S`), or the first frame sent (``server``); then
        the page's first input since its Start (at most :data:`FIRST_INPUT_S`): the first tick reads it."""
        if self.study.config.frames == "browser":
            ready = None
            with contextlib.suppress(Gone):  # a page gone meanwhile: the trial loop ends it at once
                ready = await self._expect("ready", READY_S)
            if not self.gone and ready is None:
                LOG.info(
                    "participant %s: no picture after %.0f s; the trial starts", self.participant, READY_S
                )
        elif self.study.renderer is not None:
            jpeg = await self.study.renderer.frame([float(v) for v in trial.station.state])
            if jpeg is not None:
                await self.send(jpeg)
        deadline = time.monotonic() + FIRST_INPUT_S
        while self.inputs.received == -math.inf and time.monotonic() < deadline and not self.gone:
            await asyncio.sleep(0.01)

    def _connected(self) -> bool:
        self.silent()
        return not self.gone

    async def _tick(self, message: dict[str, Any]) -> None:
        if not self.study.config.show_belief:  # the paper's people saw the robot only
            message = {k: v for k, v in message.items() if k not in ("belief", "goals")}
        await self.send(message)
        if self.study.renderer is not None and not self._frames:
            task = asyncio.create_task(self._frame(message["q"]))
            self._frames.add(task)
            task.add_done_callback(self._frames.discard)

    async def _frame(self, q: list[float]) -> None:
        assert self.study.renderer is not None
        jpeg = await self.study.renderer.frame(q)
        if jpeg is not None and not self.gone:
            await self.send(jpeg)


STEPPER = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="lasa-step")
"""The one thread that runs every participant's :func:`tick`, in turn: steps of small NumPy and torch calls in
several threads fight over the GIL and each takes several times as long (``benchmarks/web_load.py``)."""


def open_trial(
    config: SessionConfig,
    folder: Path,
    attempt: int,
    duration_s: float,
    order: int = 0,
    device: dict[str, str] | None = None,
) -> Session:
    """A warmed-up station and its new log ``<participant>_<task>_<condition>_<time>_a<attempt>`` (a new name
    for each attempt, its sidecar the limit ``limit_s``); ``order``: the condition's position in the
    participant's schedule; ``device``: the input device the page uses
    (:func:`lasa.live.web.protocol.device`), in the sidecar."""
    station = Station(config)
    station.warm_up()
    meta: dict[str, Any] = dict(interface="web", attempt=attempt, order=int(order), limit_s=float(duration_s))
    writer = open_log(station, folder, suffix=f"_a{attempt}", **meta, device=device or {"kind": "unknown"})
    return Session(station, writer, max(1, int(round(duration_s / station.control.dt))))


def tick(trial: Session, sample: StickSample) -> dict[str, Any]:
    """The loop's one step on ``sample``, logged, and the page's state message."""
    rec = trial.step(sample)
    assert rec is not None
    station = trial.station
    return {
        "type": "tick",
        "step": trial.steps,
        "q": [float(v) for v in rec["s"]],
        "belief": [float(v) for v in rec["b"]],
        "goals": [DISPLAY_NAMES[g] for g in station.task.goal_names],  # as the labels name them
        "instruction": station.phase_text(),
        "late": trial.misses,
        "stop": bool(rec["stop"]),
        "connected": bool(rec["connected"]),
        "done": station.done,
        "remaining_s": (trial.max_steps - trial.steps) * station.control.dt,
    }


async def run_trial(
    trial: Session,
    inputs: Inputs,
    send: Callable[[dict[str, Any]], Awaitable[None]],
    connected: Callable[[], bool],
    finish: Callable[[], bool],
) -> str:
    """Tick until done, out of time, ``finish()`` or the page goes; the status the log closed with:
    ``interrupted`` if the page went or anything raised (a cancelled loop logs its step's row first).
    The sidecar counts the ticks without input (``disconnected_ticks``) and says why it is ``flagged``
    when they break :data:`lasa.evidence.sessions.DISCONNECTED_SHARE` (None: it is not)."""
    status, missing = "complete", 0
    step: concurrent.futures.Future[dict[str, Any]] | None = None
    with trial.guard():
        try:
            while trial.steps < trial.max_steps:
                if not connected():
                    status = "interrupted"
                    break
                step = STEPPER.submit(tick, trial, inputs.take())
                message = await asyncio.wrap_future(step)
                missing += not message["connected"]
                await send(message)
                if trial.station.done or finish():
                    break
                pause = trial.pause()
                if pause > 0:
                    await asyncio.sleep(pause)
        except BaseException:
            if step is not None:
                concurrent.futures.wait([step])  # a few ms: the step's row goes in before the log closes
            raise
    trial.close(status, disconnected_ticks=missing, flagged=disconnected_flag(missing, trial.steps))
    return status
