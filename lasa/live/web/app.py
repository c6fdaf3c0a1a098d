"""The study's web application (Starlette): the page, its files and the participants' WebSocket.

No URL carries a secret, so none reaches a server's or a proxy's log: a participant's link is
``/study#token=...``, whose fragment the browser never sends; the page sends the token once, as
the WebSocket's first message.

- ``GET /study``: the study page (the same for everyone; it holds nothing secret).
- ``GET /static/...``: the page's script and style (served from this package: no CDN).
- ``GET /npm/mujoco/...``, ``GET /npm/three/...``: MuJoCo's WebAssembly bindings and three.js, with
  ``--frames browser`` only (:mod:`lasa.live.web.scene`; read-only, installed by ``make setup``).
- ``GET /scene``: the scene of the participant's current trial as the page loads it (its MJCF, the
  names of its mesh files); ``GET /scene/<name>``: one of those files. Each needs the header
  ``X-Scene-Key``: a random key the server sends with the trial's ``scene`` message, valid while
  that trial runs; else 403 or 404.
- ``WS /ws``: the participant's connection (:class:`lasa.live.web.conversation.Conversation`).
  Refused before it opens (HTTP 403) from another site's page (the ``Origin`` must be this
  server's own, or one given with ``--origin``). Its first message is ``{"type": "hello",
  "token": ...}`` within :data:`HELLO_S`; a token that is not valid, whose schedule is done or
  that is connected elsewhere is answered ``{"type": "refused", "reason": ...}`` (one of
  :data:`REFUSALS`) and the connection closed (1008), with nothing written.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import secrets
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, PlainTextResponse, Response
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket

from lasa.base.config import Positive, validate
from lasa.base.errors import ConfigError
from lasa.live.station import Station
from lasa.live.web.conversation import Conversation
from lasa.live.web.frames import FrameRenderer
from lasa.live.web.labels import goal_labels
from lasa.live.web.plan import Progress, plan_of
from lasa.live.web.protocol import ProtocolError, parse
from lasa.live.web.scene import ASSET_TYPES, NPM_PACKAGES, NpmFiles, browser_scene, npm_folder
from lasa.live.web.tokens import TokenStore

__all__ = ["FRAMES", "HELLO_S", "PING_S", "PING_TIMEOUT_S", "REFUSALS", "WebConfig", "Study", "create_app"]

# How the page shows the robot: drawn by the server (JPEG), by the browser (MuJoCo in WebAssembly
# and three.js, from the joint positions), or not at all.
FRAMES = ("server", "browser", "none")

# How long a connection may take to send its token [s].
HELLO_S = 10.0
# The heartbeat (uvicorn's WebSocket pings): one every PING_S, answered within PING_TIMEOUT_S, else
# the connection is closed and its link is free again: a laptop gone to sleep holds a link for at
# most PING_S + PING_TIMEOUT_S [s]. The page reconnects by itself (static/study.js).
PING_S = 3.0
PING_TIMEOUT_S = 5.0
# Why a connection was refused, as the page is told (it shows each its own message).
REFUSALS = ("invalid", "finished", "elsewhere", "no_hello")

STATIC = Path(__file__).parent / "static"
HEADERS = {
    "Cache-Control": "no-store",
    "Referrer-Policy": "no-referrer",  # the token is in the page's address (its fragment)
    "X-Content-Type-Options": "nosniff",
    "X-Frame-Options": "DENY",
    "Content-Security-Policy": (
        "default-src 'self'; img-src 'self' blob:; connect-src 'self'; frame-ancestors 'none'"
    ),
}
# MuJoCo's bindings (Emscripten's embind) build their wrappers with `new Function`, and compile the
# .wasm: the page that draws the robot itself may evaluate code, its own origin's only.
BROWSER_CSP = (
    "default-src 'self'; script-src 'self' 'unsafe-eval' 'wasm-unsafe-eval'; img-src 'self' blob:; "
    "connect-src 'self'; frame-ancestors 'none'"
)


@dataclasses.dataclass(frozen=True)
class WebConfig:
    """The server's settings.

    Attributes:
        sessions: The sessions folder (its ``study/`` subfolder holds the schedule and tokens).
        build_dir: Where ``make figures`` left the decoders.
        practice_s: The longest practice per condition [s] (the paper: 5 minutes).
        trial_s: The longest trial [s].
        frames: How the page shows the robot (one of :data:`FRAMES`): ``server`` sends JPEG frames
            rendered here, ``browser`` sends the state only and the page draws it.
        origins: Page origins allowed besides the server's own (e.g. ``https://study.example.org``
            behind a reverse proxy).
        show_belief: Show the participant the robot's belief over the goals while driving. Off by
            default: the paper describes no such display, and seeing what the robot infers
            changes how people steer (under R and LA too, which have no shared autonomy); turn
            it on for pilots or demonstrations, and report it.
    """

    sessions: str
    build_dir: str = "build"
    practice_s: Positive = 300.0
    trial_s: Positive = 300.0
    frames: str = "browser"
    origins: tuple[str, ...] = ()
    show_belief: bool = False

    def __post_init__(self) -> None:
        validate(self)
        if self.frames not in FRAMES:
            raise ConfigError(f"frames is one of {FRAMES}, got {self.frames!r}")

    def durations(self, conditions: int) -> dict[str, float]:
        """What the consent page states, from these settings: the longest practice and trial [s],
        the conditions, and the longest the study can take [min] (a practice, two trials and
        the questions, about 2 minutes, per condition)."""
        per_condition = self.practice_s + 2 * self.trial_s + 120.0
        return {
            "practice_s": self.practice_s,
            "trial_s": self.trial_s,
            "conditions": conditions,
            "longest_min": round(conditions * per_condition / 60.0),
        }


class Study:
    """The server's state: settings, tokens, progress, the connected participants, the renderer."""

    def __init__(self, config: WebConfig) -> None:
        self.config = config
        self.tokens = TokenStore(config.sessions)
        self.progress = Progress(config.sessions)
        self.active: set[str] = set()
        self.renderer = FrameRenderer() if config.frames == "server" else None
        self.scenes: dict[str, Path] = {}  # scene key -> the scene XML of a trial in progress
        self._labels: list[dict[str, Any]] | None = None  # the goals' places: one scene, one camera
        if config.frames == "browser":
            for name in NPM_PACKAGES:
                npm_folder(name)  # fail at start, not in a participant's page

    def admit(self, token: str | None) -> tuple[str | None, str]:
        """(participant, "") for a valid token whose schedule is not done and that is not connected
        elsewhere, else (None, the reason: one of :data:`REFUSALS`)."""
        participant = self.tokens.participant(token)
        if participant is None:
            return None, "invalid"
        plan = plan_of(self.config.sessions, participant)
        if not plan or self.progress.finished(participant, plan):
            return None, "finished"
        if participant in self.active:
            return None, "elsewhere"
        return participant, ""

    def labels(self, station: Station) -> list[dict[str, Any]]:
        """The goals' names and places on the picture (:func:`lasa.live.web.labels.goal_labels`),
        computed for the first trial: every trial has the eating scene and its camera."""
        if self._labels is None:
            robot = station.robot
            self._labels = goal_labels(station.task, robot.model.camera(robot.spec.camera).id)
        return self._labels

    def scene_key(self, xml: Path) -> str:
        """A new random key for a trial's scene (the ``X-Scene-Key`` of its requests)."""
        key = secrets.token_urlsafe(24)
        self.scenes[key] = xml
        return key


def _same_origin(ws: WebSocket, extra: tuple[str, ...]) -> bool:
    origin, host = ws.headers.get("origin"), ws.headers.get("host")
    return bool(origin and host) and origin in {f"http://{host}", f"https://{host}", *extra}


async def page(request: Request) -> Response:
    """The study page: the same for everyone (the token stays in the address's fragment)."""
    study: Study = request.app.state.study
    headers = (
        HEADERS | {"Content-Security-Policy": BROWSER_CSP} if study.config.frames == "browser" else HEADERS
    )
    return FileResponse(STATIC / "index.html", headers=headers)


def _scene_of(request: Request) -> tuple[str, dict[str, Path]] | Response:
    study: Study = request.app.state.study
    key = request.headers.get("x-scene-key", "")
    xml = study.scenes.get(key) if 0 < len(key) <= 64 else None
    if xml is None or study.config.frames != "browser":
        return PlainTextResponse("No trial of this page is running.", 404, headers=HEADERS)
    return browser_scene(xml)


async def scene(request: Request) -> Response:
    """The current trial's scene as the page loads it: ``{"xml": ..., "assets": [names]}``."""
    found = _scene_of(request)
    if isinstance(found, Response):
        return found
    xml, assets = found
    return JSONResponse({"xml": xml, "assets": sorted(assets)}, headers=HEADERS)


async def scene_asset(request: Request) -> Response:
    """One file of the current trial's scene, by a name the server gave (else 404)."""
    found = _scene_of(request)
    if isinstance(found, Response):
        return found
    path = found[1].get(request.path_params["name"])
    if path is None:
        return PlainTextResponse("No such file.", 404, headers=HEADERS)
    return FileResponse(path, media_type=ASSET_TYPES[path.suffix.lower()], headers=HEADERS)


async def _hello(ws: WebSocket) -> str | None:
    """The token of the connection's first message, or None (not a hello, or not in time)."""
    try:
        message = await asyncio.wait_for(ws.receive(), HELLO_S)
        msg = parse(message.get("text"))
    except (TimeoutError, ProtocolError, KeyError):
        return None
    return msg.get("token") if msg["type"] == "hello" else None


async def _refuse(ws: WebSocket, reason: str) -> None:
    with contextlib.suppress(Exception):
        await ws.send_json({"type": "refused", "reason": reason})
        await ws.close(code=1008)


async def socket(ws: WebSocket) -> None:
    """A participant's connection: the origin checked before it opens, the token in its first message."""
    study: Study = ws.app.state.study
    if not _same_origin(ws, study.config.origins):
        await ws.close(code=1008)
        return
    await ws.accept()
    token = await _hello(ws)
    participant, reason = study.admit(token) if token is not None else (None, "no_hello")
    if participant is None:
        await _refuse(ws, reason)
        return
    study.active.add(participant)
    try:
        await Conversation(ws, study, participant).run()
    finally:
        study.active.discard(participant)


def create_app(config: WebConfig) -> Starlette:
    """The application serving ``config``'s study."""
    study = Study(config)

    @contextlib.asynccontextmanager
    async def lifespan(app: Starlette) -> AsyncIterator[None]:
        if study.renderer is not None:
            await study.renderer.warm_up()
        yield
        if study.renderer is not None:
            study.renderer.close()

    routes = [
        Route("/study", page),
        Mount("/static", StaticFiles(directory=STATIC), name="static"),
        WebSocketRoute("/ws", socket),
    ]
    if config.frames == "browser":
        routes += [Route("/scene", scene), Route("/scene/{name}", scene_asset)]
        routes += [Mount(f"/npm/{name}", NpmFiles(directory=npm_folder(name))) for name in NPM_PACKAGES]
    app = Starlette(lifespan=lifespan, routes=routes)
    app.state.study = study
    return app
