"""Fuzz the compiler: mutated kit behavior sets give diagnostics, never an exception or a hang.

Complements tests/lang/test_properties.py (token-level edits) with the amplifying edits of
:mod:`tests.fuzz.probes` (thousands of nested parentheses, braces, long operator chains, odd
bytes), through the library and through ``xabsl compile --ic`` (which also emits the IC).
"""

from __future__ import annotations

import io
import random
import tempfile
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

from hypothesis import given
from hypothesis import strategies as st

from tests.fuzz.probes import fuzz_settings, mutate_many, time_bound
from tests.kit import KIT, SETS
from xabsl_studio.engine.cli import main
from xabsl_studio.engine.lang import compile_file

SOURCES = {name: {p.relative_to(KIT / name): p.read_bytes() for p in (KIT / name).rglob("*.xabsl")} for name in SETS}


@fuzz_settings(60)
@given(st.sampled_from(SETS), st.randoms(use_true_random=False))
def test_mutated_behavior_sets_compile_to_diagnostics(name: str, rnd: random.Random) -> None:
    files = dict(SOURCES[name])
    for _ in range(rnd.randint(1, 2)):
        path = rnd.choice(sorted(files))
        files[path] = mutate_many(files[path], rnd)
    with tempfile.TemporaryDirectory() as folder:
        root = Path(folder)
        for path, data in files.items():
            (root / path).parent.mkdir(parents=True, exist_ok=True)
            (root / path).write_bytes(data)
        with time_bound():
            compilation = compile_file(str(root / "agents.xabsl"))
        if compilation.program is None:
            assert compilation.errors, "a failed compilation carries an error"
        for diagnostic in compilation.diagnostics:
            assert diagnostic.format()
        out, err = io.StringIO(), io.StringIO()
        with time_bound(), redirect_stdout(out), redirect_stderr(err):
            status = main(["compile", str(root / "agents.xabsl"), "--ic", str(root / "out.ic")])
        assert status in (0, 1, 2), status
        assert "Traceback" not in err.getvalue()
        assert (status == 0) == (root / "out.ic").is_file()
