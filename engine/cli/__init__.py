"""The ``xabsl`` command line: one subcommand per module.

Engine subcommands live in the engine (``compile``, ``trace``, ``run``, ``test``, ...). Subcommands
that belong to layers above it (``serve`` in ``server``, ``lsp``, the soccer ``tournament``) are found
through the ``xabsl.commands`` entry-point group, so the engine never imports the layers that
depend on it.

Each subcommand module exposes ``register(subparsers)``, which adds its parser and sets
``func`` to a callable taking the parsed namespace and returning the exit status:
0 success, 1 errors in the input behavior, 2 usage or I/O problems.

Start-up is part of every command's time (``xabsl --help`` should cost little more than starting
Python), so this module imports only ``argparse``:

* the engine subcommands are listed in :data:`ENGINE_COMMANDS` with their one-line help; only
  the module of the subcommand a command line names is imported (and registers itself), the
  others appear in ``--help`` from the table; the modules import their heavy parts (compiler,
  engine) only when they run;
* the entry points are read straight from the installed distributions' ``entry_points.txt``
  (what ``importlib.metadata`` reads, without its import cost of ``email`` and friends), and a
  command line that names an engine subcommand loads none;
* help is formatted without ``shutil`` (and the compression modules it imports) for the width.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import sys
from collections.abc import Callable, Iterator, Sequence

from xabsl_studio import __version__
from xabsl_studio.engine.errors import CommandLineError

#: Engine-level subcommands in the order ``--help`` lists them: name -> (module, one-line help).
#: The help must be the one the module's ``register`` gives (a test compares them).
ENGINE_COMMANDS: dict[str, tuple[str, str]] = {
    "compile": (
        "xabsl_studio.engine.cli.compile",
        "check a behavior; write intermediate code (--ic) and a JSON description (--json)",
    ),
    "docs": (
        "xabsl_studio.engine.cli.docs",
        "write HTML documentation of a behavior set (option graph, options, symbols, search)",
    ),
    "diff": (
        "xabsl_studio.engine.cli.diff",
        "compare two versions of a behavior set: options, states, transitions, symbols added, removed, changed",
    ),
    "picture": (
        "xabsl_studio.engine.cli.picture",
        "draw the option graph, a state machine or a recorded tick's activation path as SVG, PNG or PDF",
    ),
    "trace": (
        "xabsl_studio.engine.cli.trace",
        "run a behavior under the conformance host: input trace in, activation trace out",
    ),
    "profile": (
        "xabsl_studio.engine.cli.profile",
        "profile a recording: time per option and state, transitions, oscillations, coverage",
    ),
    "diverge": (
        "xabsl_studio.engine.cli.diverge",
        "the first tick where two recordings act differently, per robot: both paths and the why of each",
    ),
    "query": (
        "xabsl_studio.engine.cli.query",
        "find the ticks of a recording where an XABSL condition holds (docs/queries.md)",
    ),
    "import": (
        "xabsl_studio.engine.cli.imports",
        "convert another system's logs into a recording (naoth: a NaoTH game log): docs/naoth.md",
    ),
    "recover": (
        "xabsl_studio.engine.cli.recover",
        "make cut recordings (FILE.mcap.part left by a killed run) readable to their last complete tick",
    ),
    "plan": ("xabsl_studio.engine.cli.plan", "run GRAPHPLAN on a PDDL domain and problem and print the layered plan"),
    "run": (
        "xabsl_studio.engine.cli.run",
        "run an example world headless (xabsl run examples/soccer --help for its flags)",
    ),
    "test": (
        "xabsl_studio.engine.testing.cli",
        "run behavior test suites (*.xabsl-test.toml): setups, forced options, timed assertions",
    ),
}
#: The entry-point group of the subcommands of other layers.
COMMAND_GROUP = "xabsl.commands"


class UsageError(CommandLineError):
    """A problem with the command line or the files it names (exit status 2)."""


def _metadata_folders(path: Sequence[str]) -> Iterator[tuple[str, str]]:
    """``(normalized distribution name, folder)`` of every ``*.dist-info``/``*.egg-info`` on ``path``."""
    for entry in path:
        try:
            names = os.listdir(entry or ".")
        except OSError:
            continue
        for name in sorted(names):
            stem, dot, suffix = name.rpartition(".")
            if dot and suffix in ("dist-info", "egg-info"):
                # "xabsl_studio-0.1.0.dist-info": the name is what precedes the version
                distribution = stem.split("-", 1)[0].lower().replace("-", "_").replace(".", "_")
                yield distribution, os.path.join(entry or ".", name)


def entry_points(group: str, path: Sequence[str] | None = None) -> list[tuple[str, str]]:
    """``(name, "module:attribute")`` of the entry points in ``group``.

    As ``importlib.metadata`` finds them: per distribution, the first one on ``path`` (default
    ``sys.path``) counts.
    """
    found: list[tuple[str, str]] = []
    seen: set[str] = set()
    for distribution, folder in _metadata_folders(sys.path if path is None else path):
        if distribution in seen:
            continue
        seen.add(distribution)
        try:
            with open(os.path.join(folder, "entry_points.txt"), encoding="utf-8") as handle:
                lines = handle.read().splitlines()
        except OSError:
            continue
        section = None
        for raw in lines:
            line = raw.strip()
            if not line or line.startswith(("#", ";")):
                continue
            if line.startswith("[") and line.endswith("]"):
                section = line[1:-1].strip()
            elif section == group and "=" in line:
                name, _, value = line.partition("=")
                found.append((name.strip(), value.strip()))
    return found


def load_entry_point(value: str) -> Callable[..., object]:
    """The object an entry point's ``module:attribute [extras]`` value names."""
    module_name, _, attribute = value.split("[", 1)[0].strip().partition(":")
    target: object = importlib.import_module(module_name.strip())
    for part in attribute.strip().split(".") if attribute.strip() else ():
        target = getattr(target, part)
    if not callable(target):
        raise TypeError(f"entry point {value!r} is not callable")
    return target


def _terminal_columns() -> int:
    """The terminal width as ``shutil.get_terminal_size`` finds it (``COLUMNS``, the tty, 80)."""
    try:
        columns = int(os.environ.get("COLUMNS", "0"))
    except ValueError:
        columns = 0
    if columns <= 0:
        try:
            columns = os.get_terminal_size(sys.__stdout__.fileno()).columns if sys.__stdout__ else 0
        except (AttributeError, ValueError, OSError):
            columns = 0
    return columns if columns > 0 else 80


class _HelpFormatter(argparse.HelpFormatter):
    """argparse's formatter, taking the width without importing ``shutil``."""

    def __init__(self, prog: str, indent_increment: int = 2, max_help_position: int = 24, width: int | None = None):
        super().__init__(prog, indent_increment, max_help_position, _terminal_columns() - 2 if width is None else width)


class _ArgumentParser(argparse.ArgumentParser):
    """The parser class of ``xabsl`` and its subcommands (for :class:`_HelpFormatter`)."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        kwargs.setdefault("formatter_class", _HelpFormatter)
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]


def _command_named(argv: Sequence[str] | None) -> str | None:
    """The subcommand a command line names (its first word that is no option), if any."""
    return next((a for a in argv if not a.startswith("-")), None) if argv is not None else None


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The ``xabsl`` parser for the command line ``argv`` (default: every subcommand in full).

    Given ``argv``, only the subcommand it names is registered in full; the other engine
    subcommands are listed by name and help, and the entry points are loaded only when
    ``argv`` names no engine subcommand.
    """
    parser = _ArgumentParser(
        prog="xabsl",
        description="XABSL 2 toolchain, engine and studio for hierarchical state-machine behaviors.",
    )
    parser.add_argument("--version", action="version", version=f"xabsl {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_ArgumentParser)
    subparsers.required = True
    named = _command_named(argv)
    for name, (module_name, help_text) in ENGINE_COMMANDS.items():
        if argv is not None and name != named:
            subparsers.add_parser(name, help=help_text)
            continue
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as error:
            if error.name != module_name:
                raise
            continue
        module.register(subparsers)
    if named in ENGINE_COMMANDS:
        return parser
    for _, value in entry_points(COMMAND_GROUP):
        load_entry_point(value)(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``xabsl`` command line; returns the exit status.

    Called without ``argv`` (as the console script and ``python -m xabsl_studio.engine.cli`` do), a
    subcommand that sets ``exit_at_once`` ends the process right after it: its results are
    written and flushed, and tearing down the compiled program's objects one by one would only
    cost time (a tenth of a second on a 200-file set).
    """
    arguments = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(arguments)
    args = parser.parse_args(arguments)
    try:
        status = int(args.func(args))
        if argv is None and getattr(args, "exit_at_once", False):
            for stream in (sys.stdout, sys.stderr):
                # a reader that went away (`| head`) is not the command's failure
                with contextlib.suppress(OSError):
                    stream.flush()
            os._exit(status)
        return status
    except UsageError as error:
        print(f"xabsl {args.command}: {error}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        # The reader went away (`xabsl diverge A B | head`): not the command's failure, and no
        # traceback; what is still buffered goes nowhere instead of failing again at exit.
        with contextlib.suppress(OSError, ValueError):
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, sys.stdout.fileno())
        return 0
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
