"""``xabsl run EXAMPLE``: run an example world headless; each example brings its own flags.

An engine subcommand (``ENGINE_COMMANDS``): it serves every example world and imports none until a
command line names one.

Dispatch: ``EXAMPLE`` is an example folder (``examples/soccer``) or its name (``soccer``). The
folder's ``run.py`` (module ``xabsl_studio.examples.<name>.run``) is the example's command line and
must define two hooks:

* ``add_arguments(parser)``: add the example's own flags to an ``argparse`` parser;
* ``main(args) -> int``: run with the parsed flags and return the exit status (0 ok, 1 the
  behavior has errors, 2 usage; raise ``xabsl_studio.engine.cli.UsageError`` for a usage problem).

``xabsl run`` itself only knows the example name: everything after it is parsed by a parser
built from the example's ``add_arguments``, so ``xabsl run examples/soccer --help`` shows the
soccer flags and a new example (``examples/errands/run.py``) plugs in without touching this file.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
from pathlib import Path
from types import ModuleType

from xabsl_studio.engine.cli import UsageError

#: where the examples that came with the package are (found by name when a command line names one;
#: the engine imports none of them otherwise)
EXAMPLES_DIR = Path(__file__).resolve().parents[2] / "examples"


def available_examples() -> list[str]:
    """Names of the example folders that have a ``run.py``."""
    return sorted(p.parent.name for p in EXAMPLES_DIR.glob("*/run.py"))


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``xabsl run`` (headless matches of an example world) to the command line."""
    parser = subparsers.add_parser(
        "run",
        help="run an example world headless (xabsl run examples/soccer --help for its flags)",
        description=(
            "Run an example world headless. EXAMPLE is an example folder or its name; the flags after "
            f"it belong to the example (available: {', '.join(available_examples()) or 'none'})."
        ),
    )
    parser.add_argument("example", metavar="EXAMPLE", help="example folder, e.g. examples/soccer")
    parser.add_argument("example_args", nargs=argparse.REMAINDER, metavar="...", help="the example's own flags")
    parser.set_defaults(func=run)


def load_example(example: str) -> tuple[str, ModuleType]:
    """The example's name and its ``run`` module.

    Raises:
        UsageError: no such example folder, or the folder has no usable ``run.py``.
    """
    path = Path(example)
    name = path.name if path.name else path.resolve().name
    if not name.isidentifier():
        raise UsageError(f"not an example: {example}")
    if len(path.parts) > 1 and not path.is_dir():
        raise UsageError(f"no such example folder: {example}")
    if not (EXAMPLES_DIR / name).is_dir():
        known = ", ".join(available_examples())
        raise UsageError(f"unknown example {name!r} (available: {known})")
    if importlib.util.find_spec(f"xabsl_studio.examples.{name}.run") is None:
        raise UsageError(f"example {name!r} has no run.py")
    module = importlib.import_module(f"xabsl_studio.examples.{name}.run")
    if not (hasattr(module, "add_arguments") and hasattr(module, "main")):
        raise UsageError(f"examples/{name}/run.py defines no add_arguments(parser) and main(args)")
    return name, module


def run(args: argparse.Namespace) -> int:
    """Run the example named on the command line headless; the exit status."""
    _name, module = load_example(args.example)
    # The example's docstring opens with what it does and what to watch for: show both in --help.
    paragraphs = (module.__doc__ or "").strip().split("\n\n")
    parser = argparse.ArgumentParser(
        prog=f"xabsl run {args.example}",
        description="\n\n".join(paragraphs[:2]),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    module.add_arguments(parser)
    example_args = parser.parse_args(args.example_args)
    return int(module.main(example_args))
