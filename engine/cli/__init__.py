"""The ``xabsl`` command line: one subcommand per module.

Engine subcommands live in this package (``compile``, ``trace``, ...). Subcommands that belong
to layers above the engine (``serve`` in ``server``, ``run`` in ``examples``) are found through the
``xabsl.commands`` entry-point group, so the engine never imports the layers that depend on it.

Each subcommand module exposes ``register(subparsers)``, which adds its parser and sets
``func`` to a callable taking the parsed namespace and returning the exit status:
0 success, 1 errors in the input behavior, 2 usage or I/O problems.

Start-up is part of every command's time (``xabsl --help`` should cost little more than starting
Python), so this module imports only ``argparse``: subcommand modules import their heavy parts
(compiler, engine, server) when they run; the entry points are read straight from the installed
distributions' ``entry_points.txt`` (what ``importlib.metadata`` reads, without its import cost of
``email`` and friends); and a command line that names an engine subcommand loads no entry point.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Callable, Iterator, Sequence
from typing import Any

#: Engine-level subcommand modules, in the order ``--help`` lists them.
ENGINE_COMMANDS = ("engine.cli.compile", "engine.cli.trace", "engine.cli.plan")
#: The entry-point group of the subcommands of other layers.
COMMAND_GROUP = "xabsl.commands"


class UsageError(Exception):
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


def load_entry_point(value: str) -> Callable[..., Any]:
    """The object an entry point's ``module:attribute [extras]`` value names."""
    module_name, _, attribute = value.split("[", 1)[0].strip().partition(":")
    target: Any = importlib.import_module(module_name.strip())
    for part in attribute.strip().split(".") if attribute.strip() else ():
        target = getattr(target, part)
    return target  # type: ignore[no-any-return]


def _engine_command_named(argv: Sequence[str]) -> bool:
    """Whether the command line's first word is an engine subcommand (then no entry point is needed)."""
    first = next((a for a in argv if not a.startswith("-")), None)
    return first is not None and f"engine.cli.{first}" in ENGINE_COMMANDS


def build_parser(argv: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """The ``xabsl`` parser; given ``argv`` naming an engine subcommand, without the entry points."""
    parser = argparse.ArgumentParser(
        prog="xabsl",
        description="XABSL 2 toolchain, engine and studio for hierarchical state-machine behaviors.",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    subparsers.required = True
    for module_name in ENGINE_COMMANDS:
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as error:
            if error.name != module_name:
                raise
            continue
        module.register(subparsers)
    if argv is not None and _engine_command_named(argv):
        return parser
    for _, value in entry_points(COMMAND_GROUP):
        load_entry_point(value)(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``xabsl`` command line; returns the exit status."""
    arguments = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(arguments)
    args = parser.parse_args(arguments)
    try:
        return int(args.func(args))
    except UsageError as error:
        print(f"xabsl {args.command}: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
