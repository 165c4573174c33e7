"""``xabsl test PATH... [-k EXPR] [--junit OUT] [--jobs N]``: run behavior test suites.

Registered under the ``xabsl.commands`` entry-point group (``test = "xabsl_studio.engine.testing.cli:register"``);
``python -m xabsl_studio.engine.testing`` runs the same command. ``PATH`` is a test file or a folder
(searched recursively for ``*.xabsl-test.toml``). Exit status: 0 every selected test passed,
1 a test failed or could not run (or nothing was selected), 2 usage (a bad file, a bad ``-k``).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterable, Sequence
from pathlib import Path

# This module registers `xabsl test` whenever `xabsl` starts, so it imports only argparse at the
# top; the test format, the runner and the worlds load when the command runs.
TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing
if TYPE_CHECKING:
    from typing import Any

    from xabsl_studio.engine.testing.runner import CaseResult
    from xabsl_studio.engine.testing.spec import Case

#: How test files are named (``xabsl_studio.engine.testing.spec.SUFFIX``; a test checks that they agree).
SUFFIX = ".xabsl-test.toml"

__all__ = ["collect", "main", "register", "run_cases"]

#: Where failing tests leave their recordings unless ``--recordings`` says otherwise.
DEFAULT_RECORDINGS = Path("xabsl-test-recordings")


def register(subparsers: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """Add ``xabsl test`` to the command line (the ``xabsl.commands`` entry point)."""
    parser = subparsers.add_parser(
        "test",
        help="run behavior test suites (*.xabsl-test.toml): setups, forced options, timed assertions",
        description=__doc__.split("\n\n")[0] if __doc__ else None,
    )
    add_arguments(parser)
    parser.set_defaults(func=_run)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The command's flags (shared by ``xabsl test`` and ``python -m xabsl_studio.engine.testing``)."""
    parser.add_argument("paths", nargs="+", metavar="PATH", help=f"test files or folders (with *{SUFFIX})")
    parser.add_argument("-k", dest="keyword", metavar="EXPR", help="only tests whose suite::name matches EXPR")
    parser.add_argument("--junit", metavar="OUT", help="write a JUnit XML report")
    parser.add_argument("--jobs", "-j", type=int, default=1, metavar="N", help="run N tests at once (processes)")
    parser.add_argument(
        "--recordings",
        metavar="DIR",
        default=str(DEFAULT_RECORDINGS),
        help=f"failing tests leave a recording here (default: {DEFAULT_RECORDINGS}/)",
    )
    parser.add_argument("--no-recordings", action="store_true", help="leave no recordings")
    parser.add_argument(
        "--record-all",
        action="store_true",
        help="record every test's run into --recordings, passed or failed (a run then costs its recording)",
    )
    parser.add_argument("-q", "--quiet", action="store_true", help="print failures and the summary only")


def collect(paths: Iterable[str | Path]) -> list[Case]:
    """The cases of the test files at ``paths`` (folders searched for ``*.xabsl-test.toml``).

    Raises:
        SpecError: a bad test file, or a path that is neither.
    """
    from xabsl_studio.engine.testing.spec import SpecError, load_suite

    cases: list[Case] = []
    for raw in paths:
        path = Path(raw)
        if path.is_dir():
            files = sorted(path.rglob(f"*{SUFFIX}"))
        elif path.exists():
            files = [path]  # load_suite reads regular files only: a FIFO or device is an error
        else:
            raise SpecError(f"{path}: no such test file or folder")
        for file in files:
            cases.extend(load_suite(file).cases)
    return cases


def run_cases(
    cases: Sequence[Case], jobs: int = 1, recordings: Path | None = None, record_all: bool = False
) -> list[CaseResult]:
    """Run ``cases`` (in ``jobs`` processes); the results are in the order of ``cases``.

    Failing tests leave a recording in ``recordings``; with ``record_all`` every test does.
    """
    import concurrent.futures
    import multiprocessing

    from xabsl_studio.engine.testing.runner import run_case

    if jobs <= 1 or len(cases) <= 1:
        return [run_case(case, recordings, record_all) for case in cases]
    # forkserver: the workers start from a clean interpreter (no threads of the parent), and each
    # compiles a behavior once for all the tests it runs.
    context = multiprocessing.get_context("forkserver")
    with concurrent.futures.ProcessPoolExecutor(min(jobs, len(cases)), mp_context=context) as pool:
        return list(pool.map(run_case, cases, [recordings] * len(cases), [record_all] * len(cases)))


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m xabsl_studio.engine.testing``: the same as ``xabsl test``."""
    parser = argparse.ArgumentParser(prog="xabsl test", description=__doc__.split("\n\n")[0] if __doc__ else None)
    add_arguments(parser)
    return _run(parser.parse_args(argv))


def _run(args: argparse.Namespace) -> int:
    from xabsl_studio.engine.testing.coverage import Coverage
    from xabsl_studio.engine.testing.report import KeywordError, keyword_matcher, printable, write_junit
    from xabsl_studio.engine.testing.spec import SpecError

    try:
        cases = collect(args.paths)
        if args.keyword:
            matcher: Any = keyword_matcher(args.keyword)
            cases = [c for c in cases if matcher(c.id)]
    except (SpecError, KeywordError) as error:
        print(f"xabsl test: {printable(str(error), lines=True)}", file=sys.stderr)
        return 2
    if args.jobs < 1:
        print("xabsl test: --jobs must be at least 1", file=sys.stderr)
        return 2
    if not cases:
        print("xabsl test: no tests selected", file=sys.stderr)
        return 1
    if args.record_all and args.no_recordings:
        print("xabsl test: --record-all and --no-recordings contradict each other", file=sys.stderr)
        return 2
    recordings = None if args.no_recordings else Path(args.recordings)
    results = run_cases(cases, args.jobs, recordings, args.record_all)
    for result in results:  # names and values from the test files are shown, never obeyed
        if not result.ok:
            print(printable(result.report(), lines=True))
        elif not args.quiet:
            kept = f"; recording {result.recording}" if result.recording else ""
            print(printable(f"{result.id}: passed ({result.ticks} ticks, {result.seconds:.2f} s{kept})"))
    for line in Coverage.total(r.coverage for r in results).lines():
        print(line)
    passed = sum(r.ok for r in results)
    failed = sum(r.status == "failed" for r in results)
    errors = sum(r.status == "error" for r in results)
    wall = sum(r.seconds for r in results)
    print(f"{passed} passed, {failed} failed, {errors} errors ({wall:.1f} s of test time)")
    if args.junit:
        write_junit(Path(args.junit), results)
    return 0 if passed == len(results) else 1
