"""``xabsl serve PATH``: run a world and its XABSL behaviors in a live studio session (FastAPI on uvicorn).

PATH is an example folder (its ``studio.py`` says how to run it), a behavior folder or an agents
file anywhere on disk (both run in the bench world); ``--world NAME`` picks an installed world
plug-in instead (``xabsl_studio.engine.worlds.loader`` is the loader).

Registered through the ``xabsl.commands`` entry point (``serve = "xabsl_studio.server.cli:register"``) so the
engine's command line never imports the server. Binds to 127.0.0.1 unless told otherwise; off
loopback a token is always required, generated and printed with the URL (as Jupyter does) when
none is given.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def _option(text: str) -> tuple[str, object]:
    """``KEY=VALUE`` of ``--world-option``: the value as JSON when it parses, else the text."""
    import json

    key, sep, value = text.partition("=")
    if not sep or not key.isidentifier():
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r}")
    try:
        return key, json.loads(value)
    except ValueError:
        return key, value


def example_folder(name: str) -> Path:
    """The folder of the example ``name`` that came with the package (``--example``).

    Raises:
        UsageError: no example of that name.
    """
    import xabsl_studio
    from xabsl_studio.engine.cli import UsageError

    root = Path(xabsl_studio.__file__).parent / "examples"
    known = sorted(p.name for p in root.iterdir() if (p / "studio.py").is_file() or (p / "agents.xabsl").is_file())
    if name not in known:
        raise UsageError(f"--example: no example {name!r} (installed: {', '.join(known)})")
    return root / name


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``serve`` subcommand to the ``xabsl`` parser."""
    parser = subparsers.add_parser(
        "serve",
        help="run a world and its behaviors in the live studio (web UI + websocket API)",
        description="Run a world with its XABSL behaviors and serve the studio: the web UI at /, "
        "the REST API under /api (schema at /api/openapi.json), the live session on the websocket /ws "
        "(docs/protocol.md). PATH is an example folder with a studio.py, a behavior folder with "
        "agents.xabsl, or an agents file anywhere on disk (both run in the bench world).",
    )
    parser.add_argument(
        "path",
        metavar="PATH",
        nargs="?",
        default=".",
        help="example folder, behavior folder or agents file (default: the current folder)",
    )
    parser.add_argument(
        "--example",
        default=None,
        metavar="NAME",
        help="serve an example that came with the package instead of PATH (an unknown NAME lists them)",
    )
    parser.add_argument(
        "--world", default=None, metavar="NAME", help="run PATH in this world plug-in (xabsl.worlds entry point)"
    )
    parser.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    parser.add_argument("--port", type=int, default=8000, help="port (default 8000; 0 picks a free one)")
    parser.add_argument("--token", default=None, help="token clients must present (generated off loopback)")
    parser.add_argument("--speed", type=float, default=1.0, help="simulation speed, x real time (0.1..20)")
    parser.add_argument("--seed", type=int, default=1, help="the world's seed")
    parser.add_argument("--paused", action="store_true", help="start paused")
    parser.add_argument(
        "--allow-origin",
        action="append",
        default=[],
        metavar="ORIGIN",
        help="also accept this Origin (e.g. http://localhost:5173 for the Vite dev server)",
    )
    parser.add_argument("--robots", type=int, default=None, help="robots (per team, in a world with teams)")
    parser.add_argument(
        "--world-option",
        action="append",
        type=_option,
        default=[],
        metavar="KEY=VALUE",
        help="an option of the world plug-in (VALUE as JSON, else text), e.g. half_duration_s=300",
    )
    parser.add_argument(
        "--bindings",
        default=None,
        metavar="FILE.py",
        help="bench world: a Python module whose bind(bindings, robot) supplies input symbols, input "
        "functions and basic behaviors (docs/own-behaviors.md)",
    )
    parser.add_argument(
        "--inputs",
        default=None,
        metavar="FILE.jsonl",
        help="bench world: an input trace (the xabsl trace format) played on every robot, on the session's clock",
    )
    parser.add_argument("--web-dist", default=None, help="built web UI folder (default web/dist)")
    parser.add_argument("--compress", action="store_true", help="websocket per-message deflate")
    parser.add_argument(
        "--record-dir",
        default=None,
        metavar="DIR",
        help=(
            "record the live session into rolling .mcap files here (default: the behavior set's own "
            "sub-folder of $XDG_CACHE_HOME/xabsl-studio/recordings)"
        ),
    )
    parser.add_argument("--no-record", action="store_true", help="do not record the live session")
    parser.add_argument(
        "--record-cap-mb", type=float, default=2000.0, help="the recordings folder's size cap (default 2000 MB)"
    )
    parser.add_argument(
        "--replay",
        default=None,
        metavar="FILE.mcap",
        help="serve a recording (xabsl run ... --record) instead of a live world: seek any tick, explain it",
    )
    parser.set_defaults(func=run)


def register_attach(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add the ``attach`` subcommand to the ``xabsl`` parser (docs/attach.md)."""
    parser = subparsers.add_parser(
        "attach",
        help="open the studio on engines running elsewhere (a robot program, a ROS 2 node): docs/attach.md",
        description="Attach a studio session to running hosts: programs that run their own XABSL engines "
        "and serve them with xabsl_studio.attach.serve_engines (docs/attach.md). Several hosts make one "
        "session (a team of robot processes). The studio is served like xabsl serve's.",
    )
    parser.add_argument(
        "addresses",
        metavar="HOST:PORT",
        nargs="+",
        help="a host's address (e.g. 127.0.0.1:7410), or naoth://HOST[:5401] for a NaoTH robot or simulator "
        "(docs/naoth.md; needs --behavior)",
    )
    parser.add_argument(
        "--behavior",
        default=None,
        metavar="PATH",
        help="the behavior set the hosts run (agents file or folder): the editor, hot reload into the hosts",
    )
    parser.add_argument("--token", default=None, help="the token the hosts require (serve_engines(..., token=...))")
    parser.add_argument(
        "--studio-token",
        default=None,
        help="the token of this studio's web UI (generated off loopback)",
    )
    parser.add_argument("--watch", action="store_true", help="attach without taking control (a command takes it)")
    parser.add_argument(
        "--no-connect", action="store_true", help="the studio's users may not attach more hosts (Connect…)"
    )
    parser.add_argument(
        "--share",
        type=int,
        default=None,
        metavar="PORT",
        help="NaoTH: serve the robot's one debug slot on 127.0.0.1:PORT to other studios and RobotControl",
    )
    parser.add_argument("--name", default=None, help="how the hosts show this studio")
    parser.add_argument("--hz", type=int, default=100, help="the hosts' tick rate, for sizing the history (100)")
    parser.add_argument("--host", default="127.0.0.1", help="address the studio binds (default 127.0.0.1)")
    parser.add_argument("--port", type=int, default=8000, help="the studio's port (default 8000; 0 picks one)")
    parser.add_argument("--web-dist", default=None, help="built web UI folder (default web/dist)")
    parser.add_argument(
        "--record-dir", default=None, metavar="DIR", help="record the attached session into rolling .mcap files here"
    )
    parser.add_argument("--no-record", action="store_true", help="do not record the attached session")
    parser.add_argument("--allow-origin", action="append", default=[], metavar="ORIGIN", help="also accept this Origin")
    parser.set_defaults(func=run_attach)


def run_attach(args: argparse.Namespace) -> int:
    """Attach to the hosts and serve the studio until interrupted."""
    import logging  # here, not at the top: `xabsl --help` imports this module
    import tempfile

    import uvicorn

    from xabsl_studio.engine.cli import UsageError
    from xabsl_studio.engine.host import BehaviorSource, ExampleError, behavior_source, common_root
    from xabsl_studio.engine.record.folder import cache_folder, default_folder
    from xabsl_studio.server.api.app import WEB_DIST, create_app
    from xabsl_studio.server.api.library import RecordingLibrary
    from xabsl_studio.server.api.listen import uvicorn_config
    from xabsl_studio.server.api.security import SecurityPolicy, TokenError
    from xabsl_studio.server.protocol.naoth import parse_naoth_address
    from xabsl_studio.server.session.attached import AttachedExample, AttachedSession, parse_address
    from xabsl_studio.server.session.recording import LiveRecorder

    naoth = [a.startswith("naoth://") for a in args.addresses]
    if any(naoth) and not all(naoth):
        raise UsageError("attach either NaoTH robots (naoth://HOST) or hosts of xabsl_studio.attach, not both")
    if any(naoth) and args.behavior is None:
        raise UsageError("a NaoTH robot needs --behavior AGENTS_FILE: the sources it runs (docs/naoth.md)")
    try:
        addresses = [
            parse_naoth_address(a) if n else parse_address(a) for a, n in zip(args.addresses, naoth, strict=True)
        ]
    except ValueError as error:
        raise UsageError(str(error)) from None
    try:
        policy = SecurityPolicy.for_host(args.host, args.studio_token, args.allow_origin)
    except TokenError as error:
        raise UsageError(f"--token: {error}") from None
    sources: tuple[BehaviorSource, ...] = ()
    if args.behavior is not None:
        path = Path(args.behavior).expanduser().resolve()
        agents = path / "agents.xabsl" if path.is_dir() else path
        try:
            sources = (behavior_source(agents),)
        except ExampleError as error:
            raise UsageError(f"--behavior: {error}") from None
    # Without --behavior the studio serves no files: its root is an empty folder of its own (the
    # working directory would have the language server look through whatever lies there).
    root = common_root(sources) if sources else Path(tempfile.mkdtemp(prefix="xabsl-attach-"))
    hosts = ", ".join(args.addresses)
    example = AttachedExample(f"attached: {hosts}", root, sources, behavior_hz=max(1, args.hz) * len(addresses))
    session: AttachedSession
    if args.share is not None and not any(naoth):
        raise UsageError("--share is for a NaoTH robot (naoth://HOST)")
    if any(naoth):
        from xabsl_studio.server.session.naoth import NaothSession

        example.behavior_hz = 30 * len(addresses)  # NaoTH's cognition runs at 30 frames per second
        if args.share is not None and (len(addresses) != 1 or not 0 <= args.share < 65536):
            raise UsageError("--share PORT shares one robot's slot: attach one naoth:// robot, PORT in 0..65535")
        session = NaothSession(addresses, example, share=args.share, studio=args.name)
    else:
        session = AttachedSession(
            addresses, example, args.token, args.name, control=not args.watch, allow_connect=not args.no_connect
        )
    # The hosts send what a recording needs (their programs' IC and description, their sources).
    if args.record_dir:
        folder = Path(args.record_dir)
    elif sources:
        folder = default_folder([s.agents_file for s in sources])
    else:
        folder = cache_folder() / "attached"
    recording = None
    if args.no_record:
        recording = "off (--no-record)"
    else:
        session.live_recorder = LiveRecorder(folder, example.name, example.behavior_hz, example.physics_hz)
    web_dist = Path(args.web_dist) if args.web_dist else WEB_DIST
    app = create_app(session, policy, web_dist, RecordingLibrary(folder, []))
    config = uvicorn_config(app, args.host, args.port)
    shown = "localhost" if args.host in ("127.0.0.1", "::1") else args.host
    query = f"/?token={policy.token}" if policy.token else "/"
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    for name in ("pygls", "lsprotocol", "xabsl_studio.lsp"):  # as xabsl serve: /lsp logs every message at INFO
        logging.getLogger(name).setLevel(logging.WARNING)
    print(f"xabsl studio: attached to {hosts}")
    if args.share:
        print(
            f"  the robot's debug port is shared on 127.0.0.1:{args.share} (xabsl attach naoth://127.0.0.1:{args.share})"
        )
    print(f"  open  http://{shown}:{args.port}{query}")
    if session.live_recorder is not None:
        print(f"  recording the session into {session.live_recorder.folder} (--no-record: off)")
    else:
        print(f"  recording {recording}")
    sys.stdout.flush()
    uvicorn.Server(config).run()
    return 0


def run(args: argparse.Namespace) -> int:
    """Load the world plug-in, compile its behaviors, serve the studio until interrupted."""
    import logging  # here, not at the top: `xabsl --help` imports this module
    from typing import Any

    import uvicorn

    from xabsl_studio.engine.cli import UsageError
    from xabsl_studio.engine.worlds.loader import ExampleError, load_example
    from xabsl_studio.server.api.app import WEB_DIST, create_app
    from xabsl_studio.server.api.listen import uvicorn_config
    from xabsl_studio.server.api.security import SecurityPolicy, TokenError
    from xabsl_studio.server.protocol.limits import MAX_SPEED, MIN_SPEED
    from xabsl_studio.server.session.live import Session

    if args.example is not None:
        args.path = str(example_folder(args.example))
    if not 0 < args.record_cap_mb < float("inf"):
        raise UsageError("--record-cap-mb must be a positive number")
    try:
        policy = SecurityPolicy.for_host(args.host, args.token, args.allow_origin)
    except TokenError as error:
        raise UsageError(f"--token: {error}") from None
    if not MIN_SPEED <= args.speed <= MAX_SPEED:
        raise UsageError(f"--speed must be in {MIN_SPEED:g}..{MAX_SPEED:g}")
    options: dict[str, Any] = dict(args.world_option)
    if args.robots is not None:
        options["robots"] = args.robots
    for flag in ("bindings", "inputs"):  # options of the bench world, absolute for the simulation process
        value = getattr(args, flag)
        if value is not None:
            options[flag] = str(Path(value).expanduser().resolve())
    session: Session
    try:
        if args.replay is not None:
            from xabsl_studio.server.session.replay import ReplaySession

            session = ReplaySession(args.replay, speed=args.speed)
        else:
            example = load_example(args.path, args.world, **options)
            session = Session(
                example,
                seed=args.seed,
                speed=args.speed,
                behavior_hz=example.behavior_hz,
                physics_hz=example.physics_hz,
            )
            session.paused = args.paused
            if not args.no_record:
                from xabsl_studio.engine.record.folder import default_folder
                from xabsl_studio.server.session.recording import LiveRecorder

                agents = [source.agents_file for source in example.sources]
                folder = Path(args.record_dir) if args.record_dir else default_folder(agents)
                cap = int(args.record_cap_mb * 1e6)
                session.live_recorder = LiveRecorder(
                    folder, example.name, example.behavior_hz, example.physics_hz, cap_bytes=cap
                )
    except ExampleError as error:
        if (args.bindings or args.inputs) and "unexpected keyword argument" in str(error):
            raise UsageError(
                f"{args.path}: --bindings and --inputs are options of the bench world, and this folder runs in "
                "a world of its own"
            ) from None
        raise UsageError(str(error)) from None
    name = session.example.name
    for key, state in session.programs.items():
        comp = state.compilation
        if comp is not None and not comp.ok:
            print(
                f"warning: behavior {key!r} has {len(comp.errors)} errors; the studio shows them, "
                "its robots stand until it compiles:",
                file=sys.stderr,
            )
            for diagnostic in comp.errors[:10]:
                print("  " + diagnostic.format(), file=sys.stderr)
    web_dist = Path(args.web_dist) if args.web_dist else WEB_DIST
    from xabsl_studio.engine.record.folder import cache_folder, default_folder
    from xabsl_studio.server.api.library import RecordingLibrary

    # The recordings the studio lists and opens: its record folder (a behavior set's own, see
    # default_folder; a replay's the folder its file is in when that is one of the cache's),
    # and a file named here.
    listed: Path | None
    if args.record_dir:
        listed = Path(args.record_dir)
    elif args.replay is not None:
        parent = Path(args.replay).expanduser().resolve().parent
        listed = parent if parent.is_relative_to(cache_folder().expanduser().resolve()) else None
    else:
        listed = default_folder([source.agents_file for source in session.example.sources])
    library = RecordingLibrary(listed, [Path(args.replay)] if args.replay is not None else [])
    app = create_app(session, policy, web_dist, library)

    config = uvicorn_config(app, args.host, args.port, compress=args.compress)
    server = uvicorn.Server(config)
    shown = "localhost" if args.host in ("127.0.0.1", "::1") else args.host
    query = f"/?token={policy.token}" if policy.token else "/"
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    # The language server behind /lsp (pygls) logs every message it sends or receives at INFO:
    # a few keystrokes made 112 KB of console. Its warnings and errors still show.
    for logger in ("pygls", "lsprotocol", "xabsl_studio.lsp"):
        logging.getLogger(logger).setLevel(logging.WARNING)
    where = "a recording, paused" if args.replay is not None else "simulation in its own process"
    print(f"xabsl studio: {name}, speed {session.speed:g}x ({where})")
    print(f"  open  http://{shown}:{args.port}{query}")
    if session.live_recorder is not None:
        print(f"  recording the session into {session.live_recorder.folder} (--no-record: off)")
    print(f"  API   http://{shown}:{args.port}/api/openapi.json   websocket ws://{shown}:{args.port}/ws")
    token = f"?token={policy.token}" if policy.token else ""
    print(f"  Foxglove / Lichtblick: ws://{shown}:{args.port}/foxglove{token}   (docs/foxglove.md)")
    if not (web_dist / "index.html").is_file():
        print(f"  (the web UI is not built: {web_dist} is missing; run make)")
    sys.stdout.flush()
    server.run()
    return 0
