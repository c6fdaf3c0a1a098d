"""The study's web application (Starlette): ``/study``, ``/static``, ``/npm`` and ``/scene`` (``--frames
browser``: MuJoCo's WebAssembly build, three.js and the trial's scene, files renamed by :func:`browser_scene`,
behind the trial's ``X-Scene-Key``) and ``WS /ws``. No URL or client string reaches a path: the page sends the
token (its link's fragment) as the WebSocket's first message; another site's page is refused (``Origin``)."""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import logging
import os
import xml.etree.ElementTree as ET
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, PlainTextResponse, Response
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.types import Scope
from starlette.websockets import WebSocket

from lasa.base.config import TRIAL_LIMIT_S, Positive, validate
from lasa.base.errors import ArtifactError, ConfigError
from lasa.base.paths import repo_root
from lasa.evidence.sessionlog import repair_running
from lasa.live.station import Station
from lasa.live.web.consent import read_consent
from lasa.live.web.conversation import Conversation
from lasa.live.web.frames import FrameRenderer
from lasa.live.web.plan import Progress, plan_of
from lasa.live.web.protocol import ProtocolError, parse
from lasa.live.web.tokens import TokenStore
from lasa.live.web.withdraw import withdrawn
from lasa.world.camera import project
from lasa.world.fork import tip_frames
from lasa.world.instructions import DISPLAY_NAMES, PICTURE_CAMERA

# How the page shows the robot: server-drawn JPEG, drawn by the browser (MuJoCo WebAssembly), or not.
FRAMES = ("server", "browser", "none")

LOG = logging.getLogger("lasa.live.web")
HELLO_S = 10.0  # how long a connection may take to send its token [s]
# how long a newer page of a link waits for the older one's trial to close before it is refused [s]
TAKEOVER_S = 10.0
# uvicorn's WebSocket pings: a sleeping laptop holds its link at most PING_S + PING_TIMEOUT_S [s]
PING_S = 3.0
PING_TIMEOUT_S = 5.0

STATIC = Path(__file__).parent / "static"
CSP = "default-src 'self'; {}img-src 'self' blob:; connect-src 'self'; frame-ancestors 'none'"
HEADERS = {
    "Cache-Control": "no-store",
    "Referrer-Policy": "no-referrer",  # the token is in the page's address (its fragment)
    "X-Content-Type-Options": "nosniff",
    "X-Frame-Options": "DENY",
    "Content-Security-Policy": CSP.format(""),
}
# MuJoCo's bindings build wrappers with `new Function` and compile the .wasm: its own origin's only
BROWSER_HEADERS = HEADERS | {
    "Content-Security-Policy": CSP.format("script-src 'self' 'unsafe-eval' 'wasm-unsafe-eval'; ")
}


@dataclasses.dataclass(frozen=True)
class WebConfig:
    """The server's settings; ``show_belief`` is off as in the paper (seeing the belief changes how
    people steer): turn it on for pilots, and report it."""

    sessions: str  # the sessions folder (its study/ holds the schedule and the tokens)
    build_dir: str = "build"  # where `make figures` left the decoders
    practice_s: Positive = 300.0  # the longest practice per condition [s] (the paper: 5 minutes)
    trial_s: Positive = TRIAL_LIMIT_S  # the longest trial [s]: the analysis' horizon (one limit)
    frames: str = "browser"  # how the page shows the robot (FRAMES)
    origins: tuple[str, ...] = ()  # page origins allowed besides the server's own (behind a proxy)
    show_belief: bool = False
    # the lab's own study: its consent text (Markdown; "": the package's example), what the thank-you
    # page gives (a completion code, a link back to the recruiting site)
    consent: str = ""
    completion_code: str = ""
    completion_url: str = ""

    def __post_init__(self) -> None:
        validate(self)
        if self.frames not in FRAMES:
            raise ConfigError(f"frames is one of {FRAMES}, got {self.frames!r}")
        self._check_completion()

    def _check_completion(self) -> None:
        if len(self.completion_code) > 64 or not self.completion_code.isprintable():
            raise ConfigError("a completion code is at most 64 printable characters")
        if self.completion_url and not self.completion_url.startswith(("https://", "http://")):
            raise ConfigError(f"a completion URL starts with https://, got {self.completion_url!r}")

    def durations(self, conditions: int) -> dict[str, float]:
        """What the consent page states: the longest practice and trial [s], the conditions, and the
        longest the study takes [min] (a practice, two trials and ~2 minutes of questions each)."""
        longest = round(conditions * (self.practice_s + 2 * self.trial_s + 120.0) / 60.0)
        return dict(
            practice_s=self.practice_s, trial_s=self.trial_s, conditions=conditions, longest_min=longest
        )


ASPECT = 4.0 / 3.0  # width / height of the page's picture (320 x 240 frames, a 480 x 360 canvas)


class Study:
    """The server's state: settings, tokens, progress, the connected participants, the renderer."""

    def __init__(self, config: WebConfig) -> None:
        self.config = config
        self.tokens = TokenStore(config.sessions)
        self.progress = Progress(config.sessions)
        self.active: dict[str, Conversation] = {}  # participant -> their page's connection
        self.renderer = FrameRenderer() if config.frames == "server" else None
        self.scenes: dict[str, Path] = {}  # scene key -> the scene XML of a trial in progress
        self.resume: dict[str, int] = {}  # participant -> the step whose trial the page left: it restarts
        self._labels: list[dict[str, Any]] | None = None  # the goals' places: one scene, one camera
        self.consent = read_consent(config.consent)  # a bad file fails at start, not in a page

    async def admit(self, token: str | None) -> tuple[str | None, str]:
        """(participant, "") for a valid token whose schedule is not done, else (None, the reason:
        ``invalid``, ``finished``, or ``elsewhere`` if an older page of the link would not let go within
        :data:`TAKEOVER_S`). The newest page wins: an older one's connection is closed, its trial
        ``interrupted`` (the step runs again as a new attempt)."""
        participant = self.tokens.participant(token)
        if participant is None or participant in withdrawn(self.config.sessions):
            return None, "invalid"
        older = self.active.get(participant)
        if older is not None:
            LOG.info("participant %s: a newer page takes over from the open one", participant)
            await older.replace()
            try:
                await asyncio.wait_for(older.ended.wait(), TAKEOVER_S)
            except TimeoutError:
                LOG.warning(
                    "participant %s: the open page did not let go; the newer one is refused", participant
                )
                return None, "elsewhere"
        plan = plan_of(self.config.sessions, participant)
        if not plan or self.progress.finished(participant, plan):
            return None, "finished"
        if self.active.get(participant, older) is not older:  # a third page took over meanwhile
            return None, "elsewhere"
        return participant, ""

    def labels(self, station: Station) -> list[dict[str, Any]]:
        """``{"name", "x", "y"}`` per goal: where its name (at its goal pose's fork tip) goes on the picture
        (x right, y down, in [0, 1]), computed once (every trial: one scene, one camera)."""
        if self._labels is None:
            robot, task = station.robot, station.task
            tips = tip_frames(robot, mujoco.MjData(robot.model), np.asarray(task.goals))[0]
            where = project(robot, tips, PICTURE_CAMERA, ASPECT)
            self._labels = [
                {"name": DISPLAY_NAMES[name], "x": round(float(u), 4), "y": round(float(v), 4)}
                for name, (u, v) in zip(task.goal_names, where, strict=True)
            ]
        return self._labels


# The npm packages the page loads: URL name -> (folder under .venv, the file that must be there).
NPM_PACKAGES = {"mujoco": ("mujoco-js", "mujoco.wasm"), "three": ("three", "three.module.js")}
# The scene's asset files the page may fetch, by suffix, with their content types.
ASSET_TYPES = {
    ".stl": "model/stl",
    ".obj": "model/obj",
    ".msh": "application/octet-stream",
    ".png": "image/png",
}


def npm_folder(name: str) -> Path:
    """Where ``make setup`` put npm package ``name`` (a key of :data:`NPM_PACKAGES`); else ArtifactError."""
    folder, marker = NPM_PACKAGES[name]
    path = repo_root() / ".venv" / folder
    if not (path / marker).is_file():
        raise ArtifactError(f"{path / marker} is missing (the page draws the robot with it): run make setup")
    return path


class NpmFiles(StaticFiles):
    """A read-only folder of an npm package: ``.wasm`` as ``application/wasm``, ``.js`` as JavaScript,
    cacheable (the folder holds one pinned version)."""

    TYPES = {".wasm": "application/wasm", ".js": "text/javascript", ".mjs": "text/javascript"}

    def file_response(
        self,
        full_path: str | os.PathLike[str],
        stat_result: os.stat_result,
        scope: Scope,
        status_code: int = 200,
    ) -> Response:
        response = super().file_response(full_path, stat_result, scope, status_code)
        media_type = self.TYPES.get(Path(full_path).suffix)
        if media_type is not None:
            response.headers["content-type"] = media_type
        response.headers["cache-control"] = "public, max-age=86400"
        response.headers["x-content-type-options"] = "nosniff"
        return response


def browser_scene(xml_path: Path) -> tuple[str, dict[str, Path]]:
    """The scene ``xml_path`` as the page loads it: its MJCF with every ``file`` renamed, and the map from
    those names to the files on the server; ArtifactError for a missing file or one the page cannot load."""
    root = ET.fromstring(xml_path.read_text())
    for compiler in root.iter("compiler"):
        for attr in ("meshdir", "texturedir", "assetdir"):
            compiler.attrib.pop(attr, None)
    assets: dict[str, Path] = {}
    for element in root.iter():
        source = element.get("file")
        if source is None:
            continue
        path = Path(source)
        suffix = path.suffix.lower()
        if suffix not in ASSET_TYPES or not path.is_absolute() or not path.is_file():
            raise ArtifactError(f"the scene {xml_path.name} names {source!r}, which the page cannot load")
        name = f"asset{len(assets)}{suffix}"
        assets[name] = path
        element.set("file", name)
    return ET.tostring(root, encoding="unicode"), assets


async def page(request: Request) -> Response:
    """The study page: the same for everyone (the token stays in the address's fragment)."""
    browser = request.app.state.study.config.frames == "browser"
    return FileResponse(STATIC / "index.html", headers=BROWSER_HEADERS if browser else HEADERS)


async def scene(request: Request) -> Response:
    """The current trial's scene as the page loads it: ``{"xml": ..., "assets": [names]}`` at ``/scene``, or
    one of its files at ``/scene/{name}``, by a name the server gave (else 404)."""
    study: Study = request.app.state.study
    key = request.headers.get("x-scene-key", "")
    xml = study.scenes.get(key) if 0 < len(key) <= 64 else None
    if xml is None or study.config.frames != "browser":
        return PlainTextResponse("No trial of this page is running.", 404, headers=HEADERS)
    text, assets = browser_scene(xml)
    if "name" not in request.path_params:
        return JSONResponse({"xml": text, "assets": sorted(assets)}, headers=HEADERS)
    path = assets.get(request.path_params["name"])
    if path is None:
        return PlainTextResponse("No such file.", 404, headers=HEADERS)
    return FileResponse(path, media_type=ASSET_TYPES[path.suffix.lower()], headers=HEADERS)


async def socket(ws: WebSocket) -> None:
    """A participant's connection: the origin checked before it opens, the token in its first message."""
    study: Study = ws.app.state.study
    origin, host = ws.headers.get("origin"), ws.headers.get("host")
    if not (origin and host and origin in {f"http://{host}", f"https://{host}", *study.config.origins}):
        await ws.close(code=1008)
        return
    await ws.accept()
    try:  # the token of the connection's first message (a hello, in time)
        msg = parse((await asyncio.wait_for(ws.receive(), HELLO_S)).get("text"))
        token = msg.get("token") if msg["type"] == "hello" else None
    except (TimeoutError, ProtocolError, KeyError):
        token = None
    participant, reason = await study.admit(token) if token is not None else (None, "no_hello")
    if participant is None:
        with contextlib.suppress(Exception):
            await ws.send_json({"type": "refused", "reason": reason})
            await ws.close(code=1008)
        return
    conversation = study.active[participant] = Conversation(ws, study, participant)
    try:
        await conversation.run()
    finally:
        if study.active.get(participant) is conversation:
            del study.active[participant]


def repair_sessions(sessions: str | os.PathLike[str]) -> list[str]:
    """Close the sessions a killed server left ``running`` (trials and practice): ``interrupted``, with the
    reason "the server stopped", their rows kept (:func:`lasa.evidence.sessionlog.repair_running`); each
    named in the log. Their stems."""
    repaired = [*repair_running(sessions), *repair_running(Path(sessions, "practice"))]
    for stem in repaired:
        LOG.info("session %s was left running: closed as interrupted (the server stopped)", stem)
    return repaired


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
    if config.frames == "browser":  # npm_folder fails at start, not in a participant's page
        routes += [Route("/scene", scene), Route("/scene/{name}", scene)]
        routes += [Mount(f"/npm/{name}", NpmFiles(directory=npm_folder(name))) for name in NPM_PACKAGES]
    app = Starlette(lifespan=lifespan, routes=routes)
    app.state.study = study
    return app
