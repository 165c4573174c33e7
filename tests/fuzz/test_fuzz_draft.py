"""Fuzz ``POST /api/tests/draft`` on a real uvicorn: a draft, 409 or 422, never a 5xx or a hang.

Names, robots, forced options and their parameters, overrides and active states are drawn from
everything JSON can carry (controls, separators, quotes, deep values, NaN, huge integers); a draft
that is answered is one test of exactly the name sent, and checking it reads no file. Saved drafts
land in the example's ``tests/`` folder and nowhere else.
"""

from __future__ import annotations

import json
import shutil
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import orjson
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.fuzz.probes import fuzz_settings, time_bound
from tests.server.conftest import REPO, LiveServer
from xabsl_studio.engine.testing.spec import parse_suite
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.session.live import Session

_TEXT = st.text(st.characters(blacklist_categories=("Cs",)), max_size=40)
_NAMES = st.one_of(
    _TEXT.filter(bool),
    st.sampled_from(['x\n[[test]]\nname = "i"\ninputs_file = "/dev/zero"\n#', "\u2028", "\r\n", '"""', "'''", "#"]),
)
_JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | _TEXT,
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(_TEXT, inner, max_size=3),
    max_leaves=12,
)


@pytest.fixture(scope="module")
def demo(tmp_path_factory: pytest.TempPathFactory) -> Iterator[LiveServer]:
    folder = tmp_path_factory.mktemp("draft") / "demo"
    shutil.copytree(REPO / "examples" / "demo", folder)
    session = Session(BenchExample(folder), seed=3, speed=2.0)
    with LiveServer(session) as server:
        deadline = time.monotonic() + 20
        while session.ring.latest is None or session.generation is None:
            assert time.monotonic() < deadline, "no frame from the simulation"
            time.sleep(0.05)
        yield server
    session.stop()


def test_any_draft_request_is_a_draft_or_a_4xx(demo: LiveServer) -> None:
    generation = demo.session.generation
    assert generation is not None
    robots = [str(a["name"]) for a in orjson.loads(generation.scene_bytes)["agents"]]
    root = Path(demo.session.example.root)
    bodies = st.fixed_dictionaries(
        {
            "name": _NAMES,
            "robot": st.one_of(st.sampled_from(robots), _TEXT),
            "duration": st.floats(min_value=0.001, max_value=3600),
            "save": st.booleans(),
        },
        optional={
            "force": st.fixed_dictionaries(
                {"kind": st.sampled_from(["option", "behavior"]), "name": _NAMES},
                optional={"params": st.dictionaries(_TEXT, _JSON, max_size=4)},
            ),
            "overrides": st.dictionaries(_TEXT, _JSON, max_size=4),
            "active": st.lists(st.tuples(_TEXT, _TEXT), max_size=4),
            "behaviors": st.lists(_TEXT, max_size=4),
        },
    )

    @fuzz_settings(60)
    @given(body=bodies)
    def probe(body: dict[str, Any]) -> None:
        with time_bound():
            answer = httpx.post(
                f"{demo.url}/api/tests/draft",
                content=json.dumps(body).encode(),  # NaN, Infinity and big integers as Python writes them
                headers={"Content-Type": "application/json"},
                timeout=30,
            )
        assert answer.status_code in (200, 409, 422), (answer.status_code, answer.text)
        if answer.status_code != 200:
            assert "detail" in answer.json()
            return
        data = answer.json()
        suite = parse_suite(data["text"], root / data["path"], read_files=False)
        assert [case.name for case in suite.cases] == [body["name"].strip()]
        if data["saved"]:
            saved = root / data["path"]
            assert saved.parent == root / "tests" and saved.read_text(encoding="utf-8") == data["text"]

    probe()
    assert all(p.parent == root / "tests" for p in root.rglob("*.xabsl-test.toml"))
