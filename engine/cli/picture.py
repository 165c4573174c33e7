"""``xabsl picture``: the option graph, a state machine or an activation path as SVG, PNG or PDF.

``xabsl picture BEHAVIOR [--agent A] [--option X | --machine OPTION] -o FILE [--format F]``
draws the compiled behavior (an agents file, or a folder with one): the option graph below the
agent's root (default the first agent), or below option ``X`` (a subtree), or the state machine
of ``OPTION``. With ``--recording R --tick N [--robot NAME]`` it draws what that robot ran at
that tick instead, from the behavior the recording carries (BEHAVIOR is then optional): the
option graph with the options and calls that ran emphasized and each one's state, or with
``--machine`` that option's state machine with its active state and the transition that fired.

The format is ``--format`` or the output's suffix. The file is written atomically. Exit status:
0 written, 1 errors in the behavior, 2 usage or I/O problems (also a missing Graphviz ``dot``).
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path
from typing import TYPE_CHECKING

from xabsl_studio.engine.cli import UsageError

if TYPE_CHECKING:  # the command line imports what a command needs only when it runs
    from xabsl_studio.engine.ir.model import Option, Program


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``xabsl picture`` to the command line."""
    parser = subparsers.add_parser(
        "picture",
        help="draw the option graph, a state machine or a recorded tick's activation path as SVG, PNG or PDF",
        description=(
            "Draw a behavior's option graph (whole, or below --option), one option's state machine (--machine), "
            "or what a robot ran at a tick of a recording (--recording R --tick N), with Graphviz, as "
            "SVG, PNG or PDF."
        ),
    )
    parser.add_argument(
        "behavior",
        metavar="BEHAVIOR",
        nargs="?",
        help="an agents file or a behavior folder (not needed with --recording)",
    )
    parser.add_argument("-o", "--out", metavar="FILE", required=True, help="the picture to write")
    parser.add_argument("--format", choices=("svg", "png", "pdf"), help="default: the suffix of --out")
    parser.add_argument("--agent", help="the XABSL agent whose option graph to draw (default: the first)")
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--option", help="draw the option graph below this option (a subtree)")
    group.add_argument("--machine", metavar="OPTION", help="draw this option's state machine")
    parser.add_argument("--recording", metavar="FILE.mcap", help="draw what a robot ran at --tick of this recording")
    parser.add_argument("--tick", type=int, help="the tick of --recording (its seq, as the studio's timeline shows)")
    parser.add_argument("--robot", help="the robot of --recording (default: the first with a behavior)")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Compile or read the behavior, build the DOT, render it, write the file."""
    from xabsl_studio.engine.docs.pictures import PictureError, render
    from xabsl_studio.engine.emit.dot import GraphvizMissing
    from xabsl_studio.engine.files import write_atomically

    fmt = args.format or Path(args.out).suffix.lstrip(".").lower()
    if fmt not in ("svg", "png", "pdf"):
        raise UsageError(f"say --format svg, png or pdf (the suffix of {args.out!r} is not one)")
    if (args.recording is None) != (args.tick is None):
        raise UsageError("--recording and --tick go together")
    if args.robot is not None and args.recording is None:
        raise UsageError("--robot names a robot of --recording")
    if os.path.isdir(args.out):
        raise UsageError(f"a folder: {args.out}")
    if args.recording is not None:
        dot, what = _recorded(args)
    else:
        if args.behavior is None:
            raise UsageError("name the behavior (an agents file or a folder), or give --recording")
        compiled = _compiled(args.behavior)
        if compiled is None:
            return 1
        dot, what = _drawn(compiled, args)
    try:
        data = render(dot, fmt)
    except (GraphvizMissing, PictureError) as error:
        raise UsageError(str(error)) from None
    try:
        write_atomically(args.out, data)
    except OSError as error:
        raise UsageError(f"cannot write {args.out}: {error.strerror or error}") from None
    print(f"ok: {what} as {fmt.upper()} in {args.out} ({len(data)} bytes)")
    return 0


def _compiled(behavior: str) -> Program | None:
    """The program of ``behavior`` (printing its errors; None when it has any)."""
    from xabsl_studio.engine.host import ExampleError
    from xabsl_studio.engine.lang import compile_file
    from xabsl_studio.engine.worlds.bench import find_agents_file

    path = Path(behavior)
    if path.is_dir():
        try:
            path = find_agents_file(path)
        except ExampleError as error:
            raise UsageError(str(error)) from None
    elif not path.is_file():
        raise UsageError(f"no such file or folder: {behavior}")
    compilation = compile_file(str(path))
    for diagnostic in compilation.errors:
        print(diagnostic.format())
    if compilation.program is None or compilation.errors:
        print(f"failed: {len(compilation.errors)} errors; no picture written")
        return None
    return compilation.program


def _drawn(program: Program, args: argparse.Namespace) -> tuple[str, str]:
    """The DOT of the compiled behavior's option graph or state machine, and what it shows."""
    from xabsl_studio.engine.docs.pictures import activation_machine, for_paper
    from xabsl_studio.engine.emit.dot import option_graph

    if args.machine is not None:
        option = _option(program, args.machine)
        return activation_machine(option, None, f"option {option.name}"), f"the state machine of {option.name}"
    if args.option is not None:
        _option(program, args.option)
        what = f"the option graph below {args.option}"
        return for_paper(option_graph(program, args.option), f"below {args.option}"), what
    root, name = _root(program, args.agent)
    title = f"agent {name}" if name else None
    return for_paper(option_graph(program, root), title), f"the option graph of {name or 'every option'}"


def _option(program: Program, name: str) -> Option:
    option = program.options.get(name)
    if option is None:
        raise UsageError(f"no option {name!r} in this behavior")
    return option


def _root(program: Program, agent: str | None) -> tuple[str | None, str | None]:
    """The root option of ``agent`` (default: the first agent) and the agent's name."""
    if agent is None:
        return (program.agents[0].root, program.agents[0].name) if program.agents else (None, None)
    chosen = next((a for a in program.agents if a.name == agent), None)
    if chosen is None:
        known = ", ".join(a.name for a in program.agents) or "none"
        raise UsageError(f"no agent {agent!r} in this behavior (agents: {known})")
    return chosen.root, chosen.name


def program_option(program: Program, index: int) -> str | None:
    """The name of the option with IR index ``index``."""
    return next((o.name for o in program.options.values() if o.index == index), None)


def _recorded(args: argparse.Namespace) -> tuple[str, str]:
    """The DOT of what ``--robot`` ran at ``--tick`` of ``--recording``, and what it shows."""
    from xabsl_studio.engine.docs.pictures import Ran, activation_graph, activation_machine
    from xabsl_studio.engine.record.reader import Recording, RecordingError

    if not os.path.isfile(args.recording):
        raise UsageError(f"no such file: {args.recording}")
    try:
        with Recording(args.recording) as recording:
            if not recording.agents:
                raise UsageError(f"{args.recording}: no robot in it runs a behavior")
            robot = args.robot if args.robot is not None else recording.agents[0]
            if robot not in recording.agents:
                raise UsageError(f"no robot {robot!r} in {args.recording} (robots: {', '.join(recording.agents)})")
            view = recording.tick(args.tick)
            tick = view.agents.get(robot)
            if tick is None:
                raise UsageError(f"{robot} ran no behavior at tick {args.tick}")
            program = tick.program.program()
            if program is None:
                raise UsageError(f"{args.recording} was recorded without the behavior's code (an older recording)")
            path = tick.path
            seconds = view.t / 1000
    except RecordingError as error:
        raise UsageError(str(error)) from None
    try:
        ran = Ran.from_path(program, path)
    except ValueError as error:
        raise UsageError(f"{args.recording} at tick {args.tick}: {error}") from None
    title = f"{robot} at tick {args.tick} ({seconds:.2f} s)"
    if args.machine is not None:
        option = _option(program, args.machine)
        state = ran.states.get(args.machine)
        shown = f"{option.name}: {state}" if state else f"{option.name} (not running)"
        what = f"the state machine of {args.machine} at tick {args.tick}"
        return activation_machine(option, ran, f"{title}, {shown}"), what
    if args.option is not None:
        _option(program, args.option)
        root = args.option
    else:
        roots = [program_option(program, node[2]) for node in path if node[0] == 0 and node[1] == 0]
        root = roots[0] if roots else _root(program, args.agent)[0]
    return activation_graph(program, ran, root, title), f"{robot}'s activation path at tick {args.tick}"
