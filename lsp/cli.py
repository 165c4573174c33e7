"""``xabsl lsp``: run the XABSL language server on stdio (editors) or a websocket (browsers).

Registered through the ``xabsl.commands`` entry point (``lsp = "xabsl_studio.lsp.cli:register"``), so the
engine's command line never imports pygls. ``python -m lsp`` runs the same command.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

# This module registers `xabsl lsp` whenever `xabsl` starts, so it imports only argparse at the top.
TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing
if TYPE_CHECKING:
    from typing import Any


def register(subparsers: Any) -> None:
    """Add the ``lsp`` subcommand to the ``xabsl`` parser."""
    parser = subparsers.add_parser(
        "lsp",
        help="run the XABSL language server (Language Server Protocol on stdio or a websocket)",
        description="Run the XABSL language server: diagnostics, completion, hover, definition, references, "
        "rename, symbols, semantic tokens and folding for behavior sets (docs/editors.md).",
    )
    add_arguments(parser)
    parser.set_defaults(func=run)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The flags of ``xabsl lsp``: the transport (stdio or websocket, its origins) and the agents file."""
    parser.add_argument("--stdio", action="store_true", help="speak on stdin/stdout (the default)")
    parser.add_argument("--ws", action="store_true", help="serve websocket clients instead of stdio")
    parser.add_argument("--host", default="127.0.0.1", help="websocket address (default 127.0.0.1)")
    parser.add_argument("--port", type=int, default=2087, help="websocket port (default 2087)")
    parser.add_argument(
        "--allow-origin",
        action="append",
        default=[],
        metavar="ORIGIN",
        help="with --ws: a web page origin whose pages may connect (default: none, only non-browser clients)",
    )
    parser.add_argument(
        "--agents",
        default=None,
        metavar="FILE",
        help="the agents file of every document (default: the nearest one above it)",
    )


def run(args: argparse.Namespace) -> int:
    """Serve the language server until the client exits; the exit status."""
    from xabsl_studio.lsp.bridge import serve_websocket
    from xabsl_studio.lsp.server import serve_stdio

    if args.ws:
        serve_websocket(args.host, args.port, args.agents, args.allow_origin)
    else:
        serve_stdio(args.agents)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m lsp``: the ``xabsl lsp`` command without the ``xabsl`` front."""
    parser = argparse.ArgumentParser(prog="xabsl lsp", description="The XABSL language server.")
    add_arguments(parser)
    return run(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
