"""``/api/compare``: the Compare view's route against git revisions, folders, recordings, generations."""

from __future__ import annotations

import re
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import orjson
import pytest
from fastapi.testclient import TestClient

from tests.compare.conftest import FILES, edited, write_set
from xabsl_studio.engine.host import BehaviorLoop
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.engine.profile import profile
from xabsl_studio.engine.record import Recorder, Recording
from xabsl_studio.engine.worlds.bench import BenchController, BenchExample, BenchWorld
from xabsl_studio.server.api.app import create_app
from xabsl_studio.server.api.library import RecordingLibrary
from xabsl_studio.server.api.security import SecurityPolicy
from xabsl_studio.server.session.live import Session

TOKEN = "t" * 22
#: the working tree's edit against the commit
EDIT = ("battery < 10", "battery < 20")


def _git(repo: Path, *args: str) -> None:
    subprocess.run(["git", *args], cwd=repo, check=True, capture_output=True)


@pytest.fixture
def repo(tmp_path: Path) -> Path:
    """A git repository whose working tree's set differs from HEAD by one condition."""
    folder = tmp_path / "repo" / "patrol"
    write_set(folder)
    _git(folder.parent, "init", "-q")
    _git(folder.parent, "add", ".")
    _git(folder.parent, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "first")
    write_set(folder, edited(options__patrol_dot_xabsl=EDIT))
    return folder


def _record(path: Path, agents: Path, ticks: int = 120) -> Path:
    program = compile_file(str(agents), base=str(agents.parent)).program
    assert program is not None
    world = BenchWorld(1, 1)
    for agent in world.agents:
        agent.controller = BenchController(agent, program)
    loop = BehaviorLoop(world)
    recorder = Recorder(path, world, {"patrol": program}, example="bench", behavior_hz=40, physics_hz=120)
    for _ in range(ticks):
        now = loop.now_ms
        loop.tick()
        recorder.tick(now)
    recorder.close()
    return path


@pytest.fixture
def client(repo: Path, tmp_path: Path) -> Iterator[TestClient]:
    app = create_app(Session(BenchExample(repo / "agents.xabsl"), seed=1), SecurityPolicy(token=TOKEN), web_dist=None)
    with TestClient(app, base_url="http://127.0.0.1", headers={"Authorization": f"Bearer {TOKEN}"}) as test_client:
        yield test_client


def _get(client: TestClient, path: str, **params: str) -> tuple[int, dict[str, object]]:
    response = client.get(path, params=params)
    return response.status_code, orjson.loads(response.content)


def _changes(body: dict[str, object]) -> list[tuple[object, ...]]:
    diff = body["diff"]
    assert isinstance(diff, dict)
    return [(c["kind"], c["change"], c["option"], c["state"], c["details"][0]["new"]) for c in diff["changes"]]


def test_the_running_set_against_its_last_commit(client: TestClient) -> None:
    status, body = _get(client, "/api/compare", program="patrol", old="git:HEAD")
    assert status == 200, body
    assert _changes(body) == [("condition", "changed", "patrol", "to_post_a", "battery < 20")]
    assert body["diff"]["old"]["commit"] and body["diff"]["new"] == {"title": "Patrol", "spec": "running"}  # type: ignore[index]
    svg = body["svg"]
    assert isinstance(svg, dict) and set(svg["state_machines"]) == {"patrol"}
    assert re.search(r'<g id="leaf_0_2" class="edge changed">', svg["state_machines"]["patrol"])
    assert re.search(r'<g id="option_\d+" class="node changed">\s*<title>o:patrol</title>', svg["option_graph"])
    # the same version on both sides
    status, body = _get(client, "/api/compare", program="patrol", old="running")
    assert status == 200 and _changes(body) == []


def test_a_folder_inside_the_example(client: TestClient, repo: Path) -> None:
    write_set(repo / "versions" / "old")
    status, body = _get(client, "/api/compare", program="patrol", old="versions/old")
    assert status == 200 and _changes(body) == [("condition", "changed", "patrol", "to_post_a", "battery < 20")]
    status, body = _get(client, "/api/compare", program="patrol", old="versions/old/agents.xabsl", new="git:HEAD")
    assert status == 200 and _changes(body) == []


def test_refusals(client: TestClient, repo: Path, tmp_path: Path) -> None:
    write_set(tmp_path / "outside")
    write_set(repo / "versions" / "broken", {**FILES, "options/play.xabsl": "option play {"})
    cases = {
        "../../outside": 403,
        str(tmp_path / "outside"): 403,
        "git:HEAD:../../outside": 403,
        "git:--output=x": 400,
        "git:nosuchrev": 404,
        "versions/nothing": 404,
        "recording:nothing.mcap": 404,
        "versions/broken": 422,
    }
    for spec, expected in cases.items():
        status, body = _get(client, "/api/compare", program="patrol", old=spec)
        assert status == expected, (spec, body)
        assert isinstance(body["detail"], str) and body["detail"]
    status, _ = _get(client, "/api/compare", program="nobody", old="git:HEAD")
    assert status == 404
    status, _ = _get(client, "/api/compare", program="patrol", old="git:HEAD", recording="a.mcap")
    assert status == 404
    assert (
        client.get(
            "/api/compare", params={"program": "patrol", "old": "git:HEAD"}, headers={"Authorization": ""}
        ).status_code
        == 401
    )


def test_recordings_colour_the_graph_by_the_change_of_time_share(
    client: TestClient, repo: Path, tmp_path: Path
) -> None:
    library = tmp_path / "recordings"
    library.mkdir()
    old_set = write_set(tmp_path / "old_set")
    # the new version patrols at another pace: its states' shares differ from the old one's
    new_set = write_set(
        tmp_path / "new_set",
        edited(
            options__patrol_dot_xabsl=(
                "state_time > 4000)\n        goto to_post_b",
                "state_time > 1000)\n        goto to_post_b",
            )
        ),
    )
    _record(library / "new.mcap", new_set)
    _record(library / "old.mcap", old_set)
    client.app.state.studio.library = RecordingLibrary(library)  # type: ignore[attr-defined]
    status, body = _get(
        client, "/api/compare", program="patrol", old="git:HEAD", recording="new.mcap", against="old.mcap"
    )
    assert status == 200, body
    shares = body["shares"]
    assert isinstance(shares, dict) and {"play", "patrol", "rest"} <= set(shares)
    with Recording(library / "new.mcap") as a, Recording(library / "old.mcap") as b:
        expected_a, expected_b = profile(a)["teams"]["patrol"]["options"], profile(b)["teams"]["patrol"]["options"]
    for name, share in shares.items():
        assert share["a"] == expected_a[name]["share"] and share["b"] == expected_b[name]["share"]
    svg = body["svg"]
    assert isinstance(svg, dict)
    # every option with a share has its fill and the share in its tooltip
    for name in shares:
        node = re.search(
            rf'<g id="option_\d+" class="node[^"]*">\s*<title>o:{name}</title>.*?</g>', svg["option_graph"], re.S
        )
        assert node and 'style="fill:#' in node.group(0) and "% of robot time" in node.group(0), name


def test_a_hot_reload_compared_structurally(client: TestClient, repo: Path) -> None:
    session = client.app.state.studio.session  # type: ignore[attr-defined]
    deadline = time.monotonic() + 30
    while session.generation is None:
        assert time.monotonic() < deadline
        time.sleep(0.05)
    first = session.generation.number
    path = "options/patrol.xabsl"
    current = client.get(f"/api/files/{path}").json()
    text = current["text"].replace("goto wait;", "goto to_post_b;")
    response = client.put(f"/api/files/{path}", json={"text": text, "version": current["version"]})
    assert response.status_code == 200, response.text
    while session.generation.number == first:
        assert time.monotonic() < deadline
        time.sleep(0.05)
    number = session.generation.number
    status, body = _get(client, f"/api/compare/generations/{number}")
    assert status == 200, body
    (program,) = body["programs"]  # type: ignore[misc]
    assert program["program"] == "patrol"
    assert [(c["kind"], c["change"], c["state"], c["details"]) for c in program["diff"]["changes"]] == [
        ("transition", "changed", "to_post_a", [{"field": "target", "old": "wait", "new": "to_post_b"}])
    ]
    assert '<g id="leaf_0_2" class="edge changed">' in program["svg"]["state_machines"]["patrol"]
    assert _get(client, "/api/compare/generations/99999")[0] == 404


def test_where_two_library_recordings_first_act_differently(client: TestClient, tmp_path: Path) -> None:
    from tests.compare.test_diverge import first_difference

    library = tmp_path / "recordings"
    library.mkdir()
    old_set = write_set(tmp_path / "old_set")
    # the new version does not rest on a low battery: it patrols from the first tick on
    new_set = write_set(tmp_path / "new_set", edited(options__patrol_dot_xabsl=("battery < 10", "battery < -1")))
    _record(library / "new.mcap", new_set)
    _record(library / "old.mcap", old_set)
    (library / "broken.mcap").write_bytes(b"not an mcap file")
    client.app.state.studio.library = RecordingLibrary(library)  # type: ignore[attr-defined]
    status, body = _get(client, "/api/compare/diverge", recording="new.mcap", against="old.mcap")
    assert status == 200, body
    assert (body["a"], body["b"]) == ("new.mcap", "old.mcap")  # library names, not paths on disk
    earliest = body["earliest"]
    assert isinstance(earliest, dict) and earliest["option"] == "patrol"
    agent = str(earliest["agent"])
    assert earliest["seq"] == first_difference(library / "new.mcap", library / "old.mcap", agent)
    assert "battery < -1" in str(earliest["why_a"]) and "battery < 10" in str(earliest["why_b"])
    assert _get(client, "/api/compare/diverge", recording="new.mcap", against="gone.mcap")[0] == 404
    assert _get(client, "/api/compare/diverge", recording="../new.mcap", against="old.mcap")[0] == 404
    status, body = _get(client, "/api/compare/diverge", recording="new.mcap", against="broken.mcap")
    assert status == 422 and "not an MCAP file" in str(body)
    assert _get(client, "/api/compare/diverge", recording="new.mcap")[0] == 422  # `against` missing
