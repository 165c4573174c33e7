"""The generated behavior sets the benchmarks share (the tests own the generators).

benchmarks/ is no package, and tests/ is not on the path of a benchmark run as a script: the
generator is loaded from its file.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

REPO = Path(__file__).resolve().parents[1]


def navset() -> ModuleType:
    """``tests/navset.py``: a team-shaped set of 200 options in 15 folders (``write_set(folder)``)."""
    spec = importlib.util.spec_from_file_location("navset", REPO / "tests" / "navset.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module
