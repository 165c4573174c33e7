"""The pytest plugin: collects ``*.xabsl-test.toml`` files, one pytest item per ``[[test]]``.

Registered as the ``pytest11`` entry point ``xabsl_studio.engine.testing.plugin`` (so ``-p
xabsl_studio.engine.testing.plugin`` loads the same module once, also before the package is reinstalled).
A team adds its test folders to ``testpaths`` and runs ``pytest``: each test shows as
``FILE::TEST``, a failure prints the assertions that failed with tick and values and the path of
the recording it left (``--xabsl-recordings DIR``, default ``$TMPDIR/xabsl-test-recordings``).
At the end the suite's coverage is printed in the terminal summary.
"""

from __future__ import annotations

import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from xabsl_studio.engine.errors import BehaviorTestError
from xabsl_studio.engine.testing.coverage import Coverage
from xabsl_studio.engine.testing.runner import CaseResult, run_case
from xabsl_studio.engine.testing.spec import SUFFIX, Case, SpecError, load_suite

_RESULTS = pytest.StashKey[list[CaseResult]]()


def pytest_addoption(parser: pytest.Parser) -> None:
    """The plugin's option: where failing tests leave their recordings."""
    group = parser.getgroup("xabsl", "XABSL behavior tests")
    group.addoption(
        "--xabsl-recordings",
        metavar="DIR",
        default=None,
        help="folder for the recordings of failing behavior tests (default: $TMPDIR/xabsl-test-recordings)",
    )


def pytest_configure(config: pytest.Config) -> None:
    """Start collecting the results (for the coverage summary)."""
    config.stash[_RESULTS] = []


def pytest_collect_file(file_path: Path, parent: pytest.Collector) -> pytest.Collector | None:
    """Collect ``*.xabsl-test.toml`` files."""
    if file_path.name.endswith(SUFFIX):
        return SuiteFile.from_parent(parent, path=file_path)
    return None


class SuiteFile(pytest.File):
    """A test file: its ``[[test]]`` tables are the items."""

    def collect(self) -> Iterator[pytest.Item]:
        """One item per ``[[test]]``; a bad file is a collection error with the file's message."""
        try:
            suite = load_suite(self.path)
        except SpecError as error:
            raise self.CollectError(str(error)) from None
        for case in suite.cases:
            yield BehaviorTest.from_parent(self, name=case.name, case=case)


class BehaviorFailure(BehaviorTestError):
    """A behavior test failed or could not run (the report is the message)."""


class BehaviorTest(pytest.Item):
    """One ``[[test]]`` of a test file."""

    def __init__(self, *, case: Case, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.case = case

    def runtest(self) -> None:
        """Run the test; a failure raises :class:`BehaviorFailure` with the report."""
        config = self.config
        folder = config.getoption("--xabsl-recordings")
        recordings = Path(folder) if folder else Path(tempfile.gettempdir()) / "xabsl-test-recordings"
        result = run_case(self.case, recordings)
        config.stash[_RESULTS].append(result)
        if not result.ok:
            raise BehaviorFailure(result.report())

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException], style: Any = None) -> str:
        """The report (assertions, ticks, values, recording) instead of a traceback."""
        if isinstance(excinfo.value, BehaviorFailure):
            return str(excinfo.value)
        return str(super().repr_failure(excinfo))

    def reportinfo(self) -> tuple[Path, int, str]:
        """Where the test is: the file."""
        return self.path, 0, f"behavior test {self.case.id}"


def pytest_terminal_summary(terminalreporter: Any, exitstatus: int, config: pytest.Config) -> None:
    """The coverage of the behavior tests that ran."""
    results = config.stash.get(_RESULTS, [])
    if not results:
        return
    terminalreporter.section("xabsl behavior test coverage")
    for line in Coverage.total(r.coverage for r in results).lines():
        terminalreporter.write_line(line)
