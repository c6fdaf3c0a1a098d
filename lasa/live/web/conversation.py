"""One participant's connection: the protocol's steps (:mod:`lasa.live.web.plan`), driven by the server over
one WebSocket, and each trial's loop (:func:`run_trial`). Page input updates the next tick's sample; a page
gone mid-trial leaves its session ``interrupted`` and its progress where it was, for its link to resume."""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import dataclasses
import logging
import secrets
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from starlette.websockets import WebSocket

from lasa.base.errors import ArtifactError, ConfigError
from lasa.evidence.sessions import QUESTIONS, SCALES
from lasa.live.devices import StickSample
from lasa.live.session import Session, open_log
from lasa.live.station import SessionConfig, Station
from lasa.live.studykit import survey
from lasa.live.web.plan import Step, plan_of
from lasa.live.web.protocol import Inputs, ProtocolError, RateLimit, parse

if TYPE_CHECKING:
    from lasa.live.web.app import Study


LOG = logging.getLogger("lasa.live.web")
# Page messages (consent, start, survey, hello) waiting for the step that reads them: a connection
# holds at most this many; more, and any a step did not ask for, are dropped and counted.
QUEUE_MAX = 8
# What a participant reads when the server cannot run their step (preflight makes it rare).
UNAVAILABLE = (
    "The study cannot go on right now, through no fault of yours. Please tell the person who sent "
    "you the link; you can come back with the same link later."
)


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

    def __post_init__(self) -> None:
        self._queue: asyncio.Queue[dict[str, Any]] = asyncio.Queue(QUEUE_MAX)
        self._send_lock = asyncio.Lock()
        self._frames: set[asyncio.Task[None]] = set()

    async def run(self) -> None:
        """Serve the participant until their plan is done or the page goes."""
        receiver = asyncio.create_task(self._receive())
        try:
            with contextlib.suppress(Gone):
                await self._protocol()
        finally:
            receiver.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await receiver
            if self.dropped:
                LOG.info("participant %s: %d out-of-step messages dropped", self.participant, self.dropped)

    async def _receive(self) -> None:
        limit = RateLimit()
        try:
            while (message := await self.ws.receive())["type"] != "websocket.disconnect":
                if not limit.allow():
                    raise ProtocolError("too many messages")
                msg = parse(message.get("text"))
                if msg["type"] == "input":
                    self.inputs.update(msg)
                elif msg["type"] == "finish":
                    self.finish = True
                else:
                    self._put(msg)
        except ProtocolError as exc:
            with contextlib.suppress(Exception):
                await self.ws.close(code=exc.code, reason=str(exc)[:100])
        except Exception:  # a broken connection: the page is gone either way
            pass
        finally:
            self.gone = True
            if self._queue.full():  # the end always reaches the step waiting for a message
                self._queue.get_nowait()
                self.dropped += 1
            self._queue.put_nowait({"type": "_gone"})

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

    async def _expect(self, kind: str) -> dict[str, Any]:
        while True:
            msg = await self._queue.get()
            if msg["type"] == "_gone":
                raise Gone
            if msg["type"] == kind:
                return msg
            self.dropped += 1

    async def _protocol(self) -> None:
        study, participant = self.study, self.participant
        plan = plan_of(study.config.sessions, participant)
        if not study.progress.of(participant)["consented"]:
            conditions = len({step.condition for step in plan})
            await self.send({"type": "phase", "kind": "consent"} | study.config.durations(conditions))
            await self._expect("consent")
            study.progress.consent(participant)
        while not study.progress.finished(participant, plan):
            self._clear()
            index = int(study.progress.of(participant)["step"])
            step = plan[index]
            # the condition's letter, never its code (the page is blind to it, as the paper's people were)
            header: dict[str, Any] = {"type": "phase", "kind": step.kind, "label": step.label}
            header |= {"task": step.task, "index": index + 1, "total": len(plan)}
            if step.kind == "survey":
                await self._survey(step, header)
            else:
                limit = study.config.practice_s if step.kind == "practice" else study.config.trial_s
                await self.send(header | {"limit_s": limit})
                await self._expect("start")
                if await self._drive(step, limit) != "complete":
                    raise Gone
            study.progress.count(participant, "step")
        await self.send({"type": "phase", "kind": "thanks"})
        with contextlib.suppress(Exception):
            await self.ws.close(code=1000)

    async def _survey(self, step: Step, header: dict[str, Any]) -> None:
        await self.send(header | {"questions": [{"scale": s, "text": QUESTIONS[s]} for s in SCALES]})
        while True:
            answers = (await self._expect("survey"))["answers"]
            try:
                survey(self.study.config.sessions, self.participant, step.condition, answers)
                return
            except ConfigError as exc:
                await self.send({"type": "error", "message": str(exc)})

    async def _drive(self, step: Step, limit_s: float) -> str:
        study, practice = self.study, step.kind == "practice"
        config = SessionConfig("panda", step.task, step.condition, self.participant, study.config.build_dir)
        attempt = study.progress.count(self.participant, "attempts")
        folder = Path(study.config.sessions, "practice" if practice else "")  # the analysis reads trials only
        try:
            trial = await asyncio.to_thread(open_trial, config, folder, attempt, limit_s, step.order)
        except (ConfigError, ArtifactError) as exc:
            # the detail (paths, commands) is the experimenter's, in the server's log; never the page's
            LOG.error("participant %s cannot run %s %s: %s", self.participant, step.task, step.condition, exc)
            await self.send({"type": "error", "message": UNAVAILABLE})
            raise Gone from exc
        self.finish = False
        self.inputs.reset()  # a zero stick: nothing the page sent before this Start moves the robot
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
            await self.send({"type": "scene", "key": key, "qpos_adr": qpos_adr, "camera": camera})
        try:
            return await run_trial(
                trial, self.inputs, self._tick, lambda: not self.gone, lambda: practice and self.finish
            )
        finally:
            study.scenes.pop(key or "", None)

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
    config: SessionConfig, folder: Path, attempt: int, duration_s: float, order: int = 0
) -> Session:
    """A warmed-up station and its new log ``<participant>_<task>_<condition>_<time>_a<attempt>`` (a new name
    for each attempt); ``order``: the condition's position in the participant's schedule."""
    station = Station(config)
    station.warm_up()
    writer = open_log(
        station, folder, suffix=f"_a{attempt}", interface="web", attempt=attempt, order=int(order)
    )
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
        "goals": list(station.task.goal_names),
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
    ``interrupted`` if the page went or anything raised (a cancelled loop logs its step's row first)."""
    status = "complete"
    step: concurrent.futures.Future[dict[str, Any]] | None = None
    with trial.guard():
        try:
            while trial.steps < trial.max_steps:
                if not connected():
                    status = "interrupted"
                    break
                step = STEPPER.submit(tick, trial, inputs.take())
                await send(await asyncio.wrap_future(step))
                if trial.station.done or finish():
                    break
                pause = trial.pause()
                if pause > 0:
                    await asyncio.sleep(pause)
        except BaseException:
            if step is not None:
                concurrent.futures.wait([step])  # a few ms: the step's row goes in before the log closes
            raise
    trial.close(status)
    return status
