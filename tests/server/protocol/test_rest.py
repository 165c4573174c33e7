"""Real REST answers have exactly the shapes server/protocol/rest.py defines (and the web UI is
generated from): no key the definition lacks, none it requires missing."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from pydantic import TypeAdapter

from tests.server.conftest import REPO
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.api.app import create_app
from xabsl_studio.server.protocol import rest
from xabsl_studio.server.session.live import Session
from xabsl_studio.server.session.replay import ReplaySession

BASE = "http://127.0.0.1"


def valid(shape: Any, data: Any) -> None:
    TypeAdapter(shape).validate_python(data, strict=True)


@pytest.fixture
def api(demo_dir: Path) -> Iterator[TestClient]:
    session = Session(BenchExample(demo_dir), seed=2, speed=4.0)
    with TestClient(create_app(session, web_dist=None), base_url=BASE) as client:
        yield client


def test_the_file_and_compile_answers_have_their_shapes(api: TestClient) -> None:
    listed = api.get("/api/files").json()
    valid(rest.FileList, listed)
    read = api.get("/api/files/options/play.xabsl").json()
    valid(rest.FileText, read)
    saved = api.put("/api/files/options/play.xabsl", json={"text": read["text"], "version": read["version"]})
    assert saved.status_code == 200
    valid(rest.SaveResult, saved.json())
    broken = api.put(
        "/api/files/options/play.xabsl", json={"text": read["text"] + "\noption {", "version": saved.json()["version"]}
    )
    assert broken.status_code == 422 and broken.json()["detail"].startswith("saved, but")
    valid(rest.SaveResult, broken.json())
    assert broken.json()["diagnostics"] and broken.json()["diagnostics"][0]["program"] == "demo"
    compiled = api.post("/api/compile", json={"path": "options/play.xabsl", "text": "option {"}).json()
    valid(rest.CompileResult, compiled)
    assert not compiled["ok"] and any(d["severity"] == "error" for d in compiled["diagnostics"])


def test_the_status_programs_and_a_generation_diff_have_their_shapes(api: TestClient) -> None:
    status = api.get("/api/status").json()
    for program in status["programs"].values():
        valid(rest.ProgramStatus, program)
    read = api.get("/api/files/options/play.xabsl").json()
    edited = read["text"].replace("/** Root option", "/** The root option", 1)
    saved = api.put("/api/files/options/play.xabsl", json={"text": edited, "version": read["version"]})
    assert saved.status_code == 200
    number = api.get("/api/status").json()["generation"]
    diff = api.get(f"/api/generations/{number}/diff").json()
    valid(rest.GenerationDiff, diff)
    assert [f["path"] for f in diff["files"]] == ["options/play.xabsl"] and diff["files"][0]["change"] == "changed"


def test_a_replay_status_has_its_shape(tmp_path: Path) -> None:
    path = tmp_path / "run.mcap"
    run = ["run", "examples/soccer", "--duration", "2", "--players", "1", "--record", str(path)]
    subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", *run],
        cwd=REPO,
        check=True,
        capture_output=True,
    )
    with TestClient(create_app(ReplaySession(path), web_dist=None), base_url=BASE) as client:
        replay = client.get("/api/status").json()["replay"]
    valid(rest.ReplayInfo, replay)
    assert replay["ticks"] > 0 and replay["t1"] > replay["t0"]
