"""The study's web application (Starlette): the page, its files and the participants' WebSocket.

- ``GET /study?token=...``: the study page, for a valid token of a participant whose schedule is not
  done; anything else is 403 and writes nothing.
- ``GET /static/...``: the page's script and style (served from this package: no CDN).
- ``GET /npm/mujoco/...``, ``GET /npm/three/...``: MuJoCo's WebAssembly bindings and three.js, with
  ``--frames browser`` only (:mod:`lasa.live.web.scene`; read-only, installed by ``make setup``).
- ``GET /scene?token=...``: the scene of the participant's current trial as the page loads it (its
  MJCF, the names of its mesh files); ``GET /scene/<name>?token=...``: one of those files. A valid
  token, a trial in progress and a name the server gave, else 403 or 404.
- ``WS /ws?token=...``: the participant's connection (:class:`lasa.live.web.conversation.Conversation`).
  Refused before it opens (HTTP 403) without a valid token, from another site's page (the
  ``Origin`` must be this server's own, or one given with ``--origin``), while the same token is
  connected elsewhere, or once the participant's schedule is done.
"""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import AsyncIterator
from pathlib import Path

from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import FileResponse, JSONResponse, PlainTextResponse, Response
from starlette.routing import Mount, Route, WebSocketRoute
from starlette.staticfiles import StaticFiles
from starlette.websockets import WebSocket

from lasa.base.config import Positive, validate
from lasa.base.errors import ConfigError
from lasa.live.web.conversation import Conversation
from lasa.live.web.frames import FrameRenderer
from lasa.live.web.plan import Progress, plan_of
from lasa.live.web.scene import ASSET_TYPES, NPM_PACKAGES, NpmFiles, browser_scene, npm_folder
from lasa.live.web.tokens import TokenStore

__all__ = ["FRAMES", "WebConfig", "Study", "create_app"]

# How the page shows the robot: drawn by the server (JPEG), by the browser (MuJoCo in WebAssembly
# and three.js, from the joint positions), or not at all.
FRAMES = ("server", "browser", "none")

STATIC = Path(__file__).parent / "static"
HEADERS = {
    "Cache-Control": "no-store",
    "Referrer-Policy": "no-referrer",  # the token is in the page's address
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
    """

    sessions: str
    build_dir: str = "build"
    practice_s: Positive = 300.0
    trial_s: Positive = 300.0
    frames: str = "browser"
    origins: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        validate(self)
        if self.frames not in FRAMES:
            raise ConfigError(f"frames is one of {FRAMES}, got {self.frames!r}")


class Study:
    """The server's state: settings, tokens, progress, the connected participants, the renderer."""

    def __init__(self, config: WebConfig) -> None:
        self.config = config
        self.tokens = TokenStore(config.sessions)
        self.progress = Progress(config.sessions)
        self.active: set[str] = set()
        self.renderer = FrameRenderer() if config.frames == "server" else None
        self.scenes: dict[str, Path] = {}  # participant -> the scene XML of their current trial
        if config.frames == "browser":
            for name in NPM_PACKAGES:
                npm_folder(name)  # fail at start, not in a participant's page

    def admit(self, token: str | None) -> str | None:
        """The participant of a valid token whose schedule is not done, else None."""
        participant = self.tokens.participant(token)
        if participant is None:
            return None
        plan = plan_of(self.config.sessions, participant)
        if not plan or self.progress.finished(participant, plan):
            return None
        return participant


def _same_origin(ws: WebSocket, extra: tuple[str, ...]) -> bool:
    origin, host = ws.headers.get("origin"), ws.headers.get("host")
    return bool(origin and host) and origin in {f"http://{host}", f"https://{host}", *extra}


async def page(request: Request) -> Response:
    """The study page for a valid token, else 403."""
    study: Study = request.app.state.study
    if study.admit(request.query_params.get("token")) is None:
        return PlainTextResponse("This link is not valid (or its study is done).", 403, headers=HEADERS)
    headers = (
        HEADERS | {"Content-Security-Policy": BROWSER_CSP} if study.config.frames == "browser" else HEADERS
    )
    return FileResponse(STATIC / "index.html", headers=headers)


def _scene_of(request: Request) -> tuple[str, dict[str, Path]] | Response:
    study: Study = request.app.state.study
    participant = study.admit(request.query_params.get("token"))
    if participant is None:
        return PlainTextResponse("This link is not valid (or its study is done).", 403, headers=HEADERS)
    xml = study.scenes.get(participant)
    if xml is None or study.config.frames != "browser":
        return PlainTextResponse("No trial is running.", 404, headers=HEADERS)
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


async def socket(ws: WebSocket) -> None:
    """A participant's connection; refused (403, before it opens) unless every check passes."""
    study: Study = ws.app.state.study
    participant = study.admit(ws.query_params.get("token"))
    if participant is None or participant in study.active or not _same_origin(ws, study.config.origins):
        await ws.close(code=1008)
        return
    study.active.add(participant)
    try:
        await ws.accept()
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
