"""The profiler: how long options and states were active, transitions, oscillations, coverage.

Reads a recording (:mod:`xabsl_studio.engine.record`) and counts it, as the original toolchain's Xabsl
Profiler read logs of the option activation path:

* :mod:`xabsl_studio.engine.profile.analysis`  one pass over the recorded paths: intervals, leaves, transitions
* :mod:`xabsl_studio.engine.profile.report`    :func:`profile`: the report document (docs/profile.md)
* :mod:`xabsl_studio.engine.profile.terminal`  the report as rich tables
* :mod:`xabsl_studio.engine.profile.html`      the report as one self-contained HTML file with SVG plots
* :mod:`xabsl_studio.engine.profile.against`   the behavioral diff of two profiles (``--against``)
* :mod:`xabsl_studio.engine.profile.against_report`  the behavioral diff as tables and HTML
* :mod:`xabsl_studio.engine.profile.stats`     Wilson intervals, their difference, the order of comparisons
"""

from xabsl_studio.engine.profile.report import FORMAT, ProfileError, build_report, profile

__all__ = ["FORMAT", "ProfileError", "build_report", "profile"]
