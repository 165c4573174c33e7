"""``xabsl mcp``: serve recordings and behavior sets to a coding assistant over the Model Context Protocol.

Registered through the ``xabsl.commands`` entry point (``mcp = "xabsl_studio.server.mcp.cli:register"``),
so the engine's command line never imports the ``mcp`` package; ``python -m
xabsl_studio.server.mcp`` runs the same command.
"""

from __future__ import annotations

import argparse
import sys

# This module registers `xabsl mcp` whenever `xabsl` starts, so it imports only argparse at the top.
TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing
if TYPE_CHECKING:
    from typing import Any


def register(subparsers: Any) -> None:
    """Add the ``mcp`` subcommand to the ``xabsl`` parser."""
    parser = subparsers.add_parser(
        "mcp",
        help="serve recordings and behaviors to a coding assistant (Model Context Protocol on stdio)",
        description="Run a Model Context Protocol server on stdin/stdout: compile diagnostics, the activation "
        "path, why and why not at a tick of a recording, divergence of two runs, profile summaries and "
        "queries, as tools for a coding assistant (docs/mcp.md).",
    )
    add_arguments(parser)
    parser.set_defaults(func=run)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The flags of ``xabsl mcp``."""
    parser.add_argument(
        "--root",
        action="append",
        default=[],
        metavar="DIR",
        help="a folder whose files the tools may read; repeatable (default: the working directory); "
        "relative paths in tool calls are relative to the first",
    )


def run(args: argparse.Namespace) -> int:
    """Serve until the client closes stdin; the exit status."""
    try:
        from xabsl_studio.server.mcp.server import serve_stdio
    except ModuleNotFoundError as error:
        if error.name is None or not error.name.startswith("mcp"):
            raise
        print("xabsl mcp: the mcp package is missing (pip install 'mcp>=2.3,<3')", file=sys.stderr)
        return 2
    from xabsl_studio.server.mcp.tools import Roots

    serve_stdio(Roots.of(args.root))
    return 0


def main(argv: list[str] | None = None) -> int:
    """``python -m xabsl_studio.server.mcp``."""
    parser = argparse.ArgumentParser(prog="xabsl mcp")
    add_arguments(parser)
    return run(parser.parse_args(argv))
