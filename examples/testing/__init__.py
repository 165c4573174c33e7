"""Behavior tests: TOML suites that set a world up, run an agent or a forced option, and assert over time.

* :mod:`examples.testing.spec`     the test file format (docs/tests.md): TOML -> :class:`Suite`
* :mod:`examples.testing.expect`   the temporal assertions, evaluated tick by tick
* :mod:`examples.testing.runner`   runs one test case in its world; a failure leaves a recording
* :mod:`examples.testing.coverage` options, states, transitions and decision leaves reached
* :mod:`examples.testing.report`   the JUnit XML and the text summary
* :mod:`examples.testing.cli`      ``xabsl test PATH... [-k EXPR] [--junit OUT] [--jobs N]``
* :mod:`examples.testing.plugin`   the pytest plugin collecting ``*.xabsl-test.toml``
* :mod:`examples.testing.save`     "Save as test": a test file from the studio tester's state

Worlds come through the world plug-ins (``engine.host.Example``, loaded by
``server.examples.load_example``); a world that offers a setup (positions, game state) implements
:class:`examples.testing.runner.ArrangeableExample`. Nothing here is imported by ``engine/``.
"""

from examples.testing.spec import Case, Expect, SpecError, Suite, load_suite

__all__ = ["Case", "Expect", "SpecError", "Suite", "load_suite"]
