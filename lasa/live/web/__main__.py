"""Command line of the web study: ``serve`` (the default), ``schedule``, ``consent-template``, ``withdraw``
and ``export``.

``--port 8000 --sessions build/sessions [--host H] [--log FILE]`` serves the study; ``schedule --participants
12 --url http://...`` writes the schedule and one link per participant (pre-registration:
lasa.experiments.study); ``consent-template --out FILE`` the consent text to start from; ``withdraw
--participant p03`` deletes one participant's data; ``export --out FILE.zip`` archives the data to share."""

from __future__ import annotations

import argparse
import dataclasses
import logging
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from lasa.base.errors import ArtifactError, ConfigError
from lasa.runtime import pin

if TYPE_CHECKING:
    from lasa.live.web.app import WebConfig

DEFAULT_HOST = "127.0.0.1"
LOG = logging.getLogger("lasa.live.web")
EXAMPLE_CONSENT = (
    "no --consent given: participants read the package's EXAMPLE consent text, with its [bracketed] parts "
    "unfilled; write your own with `python -m lasa.live.web consent-template --out consent.md`"
)
TLS_HINT = (
    "serving on {host} without TLS: put a reverse proxy that terminates HTTPS in front "
    "(e.g. Caddy: `caddy reverse-proxy --from study.example.org --to {host}:{port}`), and pass "
    "--origin https://study.example.org so its pages may connect"
)


def preflight(config: WebConfig) -> list[str]:
    """The conditions of ``config``'s schedule, each built as a trial would on every task before the server
    listens; else a ConfigError naming the first thing missing and the command that makes it, in one line."""
    import pandas as pd

    from lasa.evidence.sessions import PRACTICE_TASK
    from lasa.live.station import SessionConfig, Station
    from lasa.live.web.tokens import study_dir

    schedule = study_dir(config.sessions) / "schedule.csv"
    if not schedule.is_file():
        raise ConfigError(f"no study in {config.sessions}: run `python -m lasa.live.web schedule` first")
    conditions = list(dict.fromkeys(pd.read_csv(schedule).condition))
    for condition in conditions:
        for task in dict.fromkeys((PRACTICE_TASK, "Entree", "Dessert")):
            try:
                Station(SessionConfig("panda", task, condition, "p00", config.build_dir))
            except (ArtifactError, ConfigError) as exc:
                first = " ".join(str(exc).split())
                raise ConfigError(f"the study's {condition} condition cannot run: {first}") from exc
    return conditions


def _schedule(argv: list[str]) -> int:
    from lasa.live.web.tokens import issue_links

    parser = argparse.ArgumentParser(
        prog="python -m lasa.live.web schedule", description=__doc__.splitlines()[0]
    )
    parser.add_argument("--participants", type=int, default=10, help="participants to schedule [%(default)s]")
    parser.add_argument("--sessions", default="build/sessions", help="the sessions folder [%(default)s]")
    parser.add_argument("--url", default="http://127.0.0.1:8000", help="the server as participants reach it")
    args = parser.parse_args(argv)
    links = issue_links(args.participants, args.sessions, args.url)
    print(f"links (the only copy of the tokens; send each to its participant): {links}")
    return 0


def _serve(argv: list[str]) -> int:
    import torch
    import uvicorn

    from lasa.base.config import TRIAL_LIMIT_S
    from lasa.live.web import logs
    from lasa.live.web.app import FRAMES, PING_S, PING_TIMEOUT_S, WebConfig, create_app, repair_sessions
    from lasa.live.web.protocol import MAX_MESSAGE_BYTES
    from lasa.live.web.tokens import study_dir

    parser = argparse.ArgumentParser(prog="python -m lasa.live.web", description=__doc__.splitlines()[0])
    parser.add_argument("--port", type=int, default=8000, help="the port [%(default)s]")
    parser.add_argument("--host", help=f"the interface to listen on [{DEFAULT_HOST}: this machine only]")
    parser.add_argument("--sessions", default="build/sessions", help="the sessions folder [%(default)s]")
    parser.add_argument(
        "--build-dir", default="build", help="where make figures left the decoders [%(default)s]"
    )
    parser.add_argument("--practice-s", type=float, default=300.0, help="longest practice [s] [%(default)s]")
    parser.add_argument(
        "--trial-s",
        type=float,
        default=TRIAL_LIMIT_S,
        help="longest trial [s], the analysis' horizon too [%(default)s]",
    )
    parser.add_argument(
        "--frames",
        choices=FRAMES,
        default=WebConfig.frames,
        help="who draws the robot: the server (JPEG frames), the browser (MuJoCo in WebAssembly, "
        "from the state), or nobody [%(default)s]",
    )
    parser.add_argument(
        "--origin", action="append", default=[], help="a page origin allowed besides the server's"
    )
    parser.add_argument(
        "--show-belief",
        action="store_true",
        help="show participants the robot's belief over the goals (off: the paper's people saw "
        "the robot only)",
    )
    parser.add_argument(
        "--log", help="the experimenter's log (appended; no IP address in it) [<sessions>/study/server.log]"
    )
    parser.add_argument(
        "--log-level", default="info", choices=("debug", "info", "warning", "error"), help="[%(default)s]"
    )
    _study_options(parser)
    args = parser.parse_args(argv)
    host = args.host or DEFAULT_HOST
    settings = {f.name: getattr(args, f.name, None) for f in dataclasses.fields(WebConfig)}
    config = WebConfig(**settings | {"origins": tuple(args.origin)})
    conditions = preflight(config)  # every decoder, scene and npm file the schedule needs, or exit
    log = logs.setup(args.log or Path(study_dir(config.sessions), "server.log"), args.log_level)
    repaired = repair_sessions(config.sessions)  # a killed server's trials: interrupted, rows kept
    LOG.info(
        "checked: every step of %s can run; %d session(s) left running closed as interrupted; log: %s",
        ", ".join(conditions), len(repaired), log,
    )  # fmt: skip
    if not config.consent:
        LOG.warning(EXAMPLE_CONSENT)
    app = create_app(config)
    # one participant's step at a time decodes one row: torch's own threads only contend with the
    # event loop's thread for the machine's cores (the load test measured it)
    torch.set_num_threads(1)
    if args.host:
        LOG.warning(TLS_HINT.format(host=host, port=args.port))
    where = "this machine only" if host == DEFAULT_HOST else "the interface given by --host"
    LOG.info("study of %s on port %d (%s): links /study#token=...", args.sessions, args.port, where)
    uvicorn.run(
        app,
        host=host,
        port=args.port,
        log_config=None,  # lasa.live.web.logs: uvicorn's lines too, without IP addresses
        log_level=args.log_level,
        proxy_headers=False,  # X-Forwarded-For is not trusted, nor logged: no participant's address
        ws_max_size=MAX_MESSAGE_BYTES,
        ws_per_message_deflate=False,  # the messages are small: compressing them costs more than it saves
        ws_ping_interval=PING_S,  # the heartbeat: a dead connection frees its link within ~8 s
        ws_ping_timeout=PING_TIMEOUT_S,
        access_log=False,
    )
    return 0


def _study_options(parser: argparse.ArgumentParser) -> None:
    """The lab's own study: its consent text and what the thank-you page gives."""
    parser.add_argument(
        "--consent",
        default="",
        help="the consent text (Markdown; `consent-template` writes one to start from)",
    )
    parser.add_argument(
        "--completion-code", default="", help="a code the thank-you page shows (e.g. Prolific's)"
    )
    parser.add_argument(
        "--completion-url", default="", help="a link the thank-you page gives back to the recruiter"
    )


def _consent_template(argv: list[str]) -> int:
    from lasa.live.web.consent import write_template

    parser = argparse.ArgumentParser(prog="python -m lasa.live.web consent-template")
    parser.add_argument("--out", required=True, help="the Markdown file to write (never replaced)")
    args = parser.parse_args(argv)
    print(f"wrote {write_template(args.out)}: fill in the parts in [square brackets], then pass --consent")
    return 0


def _withdraw(argv: list[str]) -> int:
    from lasa.live.web.withdraw import withdraw

    parser = argparse.ArgumentParser(prog="python -m lasa.live.web withdraw")
    parser.add_argument("--participant", required=True, help="the id the participant quotes (e.g. p03)")
    parser.add_argument("--sessions", default="build/sessions", help="the sessions folder [%(default)s]")
    parser.add_argument("--yes", action="store_true", help="do not ask for confirmation")
    args = parser.parse_args(argv)
    if not args.yes:
        question = f"delete every session and answer of {args.participant} in {args.sessions}? type yes: "
        if input(question).strip() != "yes":
            print("nothing deleted")
            return 1
    deleted = withdraw(args.sessions, args.participant)
    print(f"withdrew {args.participant}: deleted {len(deleted)} items; recorded in study/withdrawn.csv")
    return 0


def _export(argv: list[str]) -> int:
    from lasa.live.web.withdraw import export

    parser = argparse.ArgumentParser(prog="python -m lasa.live.web export")
    parser.add_argument("--sessions", default="build/sessions", help="the sessions folder [%(default)s]")
    parser.add_argument("--out", required=True, help="the zip file to write")
    args = parser.parse_args(argv)
    names = export(args.sessions, args.out)
    print(f"wrote {args.out}: {len(names)} files (tables, session logs, README.md); no tokens or links")
    return 0


COMMANDS = {
    "schedule": _schedule,
    "consent-template": _consent_template,
    "withdraw": _withdraw,
    "export": _export,
}


def main(argv: list[str] | None = None) -> int:
    """``schedule``, ``consent-template``, ``withdraw`` or ``export ...``; anything else serves."""
    argv = sys.argv[1:] if argv is None else argv
    pin()  # the renderer and kernels, before the server imports mujoco, numpy and torch
    try:
        command = COMMANDS.get(argv[0]) if argv else None
        return command(argv[1:]) if command is not None else _serve(argv)
    except (ConfigError, ArtifactError) as exc:  # a bad setting; npm files missing (make setup)
        print(f"error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
