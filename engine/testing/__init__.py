"""Behavior tests: TOML suites that set a world up, run an agent or a forced option, and assert over time.

* :mod:`xabsl_studio.engine.testing.spec`     the test file format (docs/tests.md): TOML -> :class:`Suite`
* :mod:`xabsl_studio.engine.testing.expect`   the temporal assertions, evaluated tick by tick
* :mod:`xabsl_studio.engine.testing.runner`   runs one test case in its world; a failure leaves a recording
* :mod:`xabsl_studio.engine.testing.coverage` options, states, transitions and decision leaves reached
* :mod:`xabsl_studio.engine.testing.report`   the JUnit XML and the text summary
* :mod:`xabsl_studio.engine.testing.cli`      ``xabsl test PATH... [-k EXPR] [--junit OUT] [--jobs N]``
* :mod:`xabsl_studio.engine.testing.plugin`   the pytest plugin collecting ``*.xabsl-test.toml``
* :mod:`xabsl_studio.engine.testing.save`     "Save as test": a test file from the studio tester's state

Worlds come through the world plug-ins (``xabsl_studio.engine.host.Example``, loaded by
``xabsl_studio.engine.worlds.loader.load_example``); a world that offers a setup (positions, game state) implements
:class:`xabsl_studio.engine.testing.runner.ArrangeableExample`. Nothing here is imported by ``engine/``.
"""

from __future__ import annotations

TYPE_CHECKING = False  # typing.TYPE_CHECKING without importing typing: `xabsl --help` stays light
if TYPE_CHECKING:
    from xabsl_studio.engine.testing.spec import Case, Expect, SpecError, Suite, load_suite

__all__ = ["Case", "Expect", "SpecError", "Suite", "load_suite"]


def __getattr__(name: str) -> object:
    # The format's names load with the format (PEP 562): registering `xabsl test` on the command
    # line imports this package, and `xabsl --help` must not pay for TOML, JSON and dataclasses.
    if name in __all__:
        from xabsl_studio.engine.testing import spec

        return getattr(spec, name)
    raise AttributeError(f"module 'xabsl_studio.engine.testing' has no attribute {name!r}")
