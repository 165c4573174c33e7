"""``POST /api/tests/draft`` with hostile requests (issue 25, item 4), against a real uvicorn.

A name is data: whatever it holds (newlines, TOML, NUL, separators), the draft is one test with
that name, and saving it writes that one test. Saving stays inside the example's ``tests/``
folder after resolving links, and never writes through a link or over something that is there.
"""

from __future__ import annotations

import os
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import orjson
import pytest

from tests.server.conftest import LiveServer
from xabsl_studio.engine.testing.spec import parse_suite
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.session.live import Session

#: A name that wrote a second test reading /dev/zero into the file (within the 120 characters).
INJECTION = (
    'x\n[[test]]\nname = "injected"\ninputs_file = "/dev/zero"\n[[test.expect]]\nalways = true\noption = "play"\n#'
)

NAMES = [
    INJECTION,
    "cr\rinside",
    "nul\x00inside",
    "tab\tand\x1b[31m escape",
    "separators \u2028 and \u2029",
    'quote " and back \\ slash',
    "#hash first",
    "]] [[test]] [suite]",
    "\x7f del",
]


@pytest.fixture
def demo(demo_dir: Path) -> Iterator[LiveServer]:
    session = Session(BenchExample(demo_dir), seed=3, speed=2.0)
    with LiveServer(session) as server:
        deadline = time.monotonic() + 20
        while session.ring.latest is None or session.generation is None:
            assert time.monotonic() < deadline, "no frame from the simulation"
            time.sleep(0.05)
        yield server
    session.stop()


def robot(server: LiveServer) -> str:
    generation = server.session.generation
    assert generation is not None
    return str(orjson.loads(generation.scene_bytes)["agents"][0]["name"])


def draft(server: LiveServer, name: str, save: bool = True) -> httpx.Response:
    body = {"name": name, "robot": robot(server), "active": [["play", "idle"]], "duration": 1, "save": save}
    return httpx.post(f"{server.url}/api/tests/draft", json=body, timeout=30)


@pytest.mark.parametrize("name", NAMES)
def test_a_name_is_one_test_whatever_it_holds(demo: LiveServer, name: str) -> None:
    answer = draft(demo, name)
    assert answer.status_code == 200, answer.text
    data = answer.json()
    file = Path(demo.session.example.root) / data["path"]
    assert file.read_text(encoding="utf-8") == data["text"]
    suite = parse_suite(data["text"], file, read_files=False)
    assert [case.name for case in suite.cases] == [name.strip()]
    head = data["text"].split("[suite]")[0].splitlines()
    assert all(line.startswith("#") or not line for line in head), head


def test_a_name_without_letters_is_a_422(demo: LiveServer) -> None:
    for name in ("\n\n", "!!!", "\u2028"):
        answer = draft(demo, name)
        assert answer.status_code == 422, (name, answer.status_code)
        assert "detail" in answer.json()


def test_saving_stays_inside_the_tests_folder(demo: LiveServer, tmp_path: Path) -> None:
    tests = Path(demo.session.example.root) / "tests"
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    tests.symlink_to(elsewhere)
    answer = draft(demo, "out of the folder")
    assert answer.status_code == 403, answer.text
    assert "tests" in answer.json()["detail"] and list(elsewhere.iterdir()) == []
    tests.unlink()
    tests.mkdir()
    (tests / "dangling.xabsl-test.toml").symlink_to(elsewhere / "written-through.toml")
    answer = draft(demo, "dangling")
    assert answer.status_code == 409, answer.text
    assert list(elsewhere.iterdir()) == []
    os.mkfifo(tests / "pipe.xabsl-test.toml")
    assert draft(demo, "pipe").status_code == 409
    assert draft(demo, "pipe", save=False).status_code == 200  # a draft that is not saved writes nothing


def test_a_tests_path_that_is_a_file_is_a_clear_refusal(demo: LiveServer) -> None:
    (Path(demo.session.example.root) / "tests").write_text("not a folder")
    answer = draft(demo, "no folder")
    assert answer.status_code in (403, 409), answer.text
    assert "tests" in answer.json()["detail"]
