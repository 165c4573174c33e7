"""Programs of the conformance kit for the engine tests: from expected.ic and from the sources.

The IC alone cannot tell the declaration order of external enum elements or input-symbol
parameters (see xabsl_studio.engine.ir.ic_reader), so when the source compiler is importable the IC is read
with the compiled program's declarations; without it, from the IC alone (inference).
"""

from __future__ import annotations

import json
import os
from functools import cache
from pathlib import Path
from typing import Any

from tests.kit import KIT
from xabsl_studio.engine.ir.ic_reader import read_ic_file
from xabsl_studio.engine.ir.model import Program

try:
    from xabsl_studio.engine.lang import compile_file
except ImportError:  # the source compiler is written concurrently; the IC still works alone
    compile_file = None  # type: ignore[assignment]

MODES = ("ic", "source") if compile_file is not None else ("ic",)


@cache
def compiled(name: str) -> Program:
    assert compile_file is not None
    cwd = os.getcwd()
    os.chdir(KIT / name)
    try:
        compilation = compile_file("agents.xabsl")
    finally:
        os.chdir(cwd)
    assert compilation.program is not None, [d.format() for d in compilation.errors]
    return compilation.program


def program(name: str, mode: str) -> Program:
    if mode == "source":
        return compiled(name)
    declarations = compiled(name) if compile_file is not None else None
    return read_ic_file(KIT / name / "expected.ic", declarations)


def lines(path: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
