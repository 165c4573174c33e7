"""The ``xabsl`` command line: one subcommand per module.

Engine subcommands live in this package (``compile``, ``trace``, ...). Subcommands that belong
to layers above the engine (``serve`` in ``server``, ``run`` in ``examples``) are found through the
``xabsl.commands`` entry-point group, so the engine never imports the layers that depend on it.

Each subcommand module exposes ``register(subparsers)``, which adds its parser and sets
``func`` to a callable taking the parsed namespace and returning the exit status:
0 success, 1 errors in the input behavior, 2 usage or I/O problems.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence
from importlib.metadata import entry_points

from engine.errors import CommandLineError

#: Engine-level subcommand modules, in the order ``--help`` lists them.
ENGINE_COMMANDS = ("engine.cli.compile", "engine.cli.trace", "engine.cli.plan")


class UsageError(CommandLineError):
    """A problem with the command line or the files it names (exit status 2)."""


def build_parser() -> argparse.ArgumentParser:
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
    for entry in entry_points(group="xabsl.commands"):
        entry.load()(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except UsageError as error:
        print(f"xabsl {args.command}: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
