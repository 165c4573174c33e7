"""World plug-ins: how ``xabsl serve PATH`` finds the world that runs PATH, and errands served live.

The loader (``xabsl_studio.engine.worlds.loader``) must find a folder's ``studio.py`` (inside the package or
anywhere on disk), an installed ``xabsl.worlds`` entry point, or fall back to the bench world for
a behavior folder or an agents file; the simulation process must get the same plug-in (it is
pickled as the way to load it again), and the server itself must name no example.
"""

from __future__ import annotations

import gc
import importlib.metadata
import multiprocessing
import pickle
import re
import shutil
import textwrap
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx2 as httpx
import pytest

from tests.server.conftest import REPO, LiveServer, WsClient
from xabsl_studio.engine.host import Example, ExampleError
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.engine.worlds.loader import WorldPlugin, load_example
from xabsl_studio.examples.errands.studio import ErrandsExample
from xabsl_studio.examples.soccer.studio import SoccerExample
from xabsl_studio.server.session.live import Session

# -- finding the plug-in -------------------------------------------------------------------------


def test_example_folders_name_their_world_through_studio_py() -> None:
    soccer = load_example(REPO / "examples" / "soccer")
    errands = load_example(REPO / "examples" / "errands")
    assert isinstance(soccer.example, SoccerExample) and isinstance(errands.example, ErrandsExample)
    assert [s.key for s in soccer.sources] == ["behavior", "chase"]
    assert (errands.behavior_hz, errands.physics_hz) == (50, 100)
    # the factory's module is importable by name, so the forkserver preloads it
    assert (
        errands.preload[0] == "xabsl_studio.examples.errands.studio"
        and "xabsl_studio.examples.errands.world" in errands.preload
    )
    assert isinstance(errands, Example)


def test_a_behavior_folder_and_an_agents_file_run_in_the_bench_world() -> None:
    folder = load_example(REPO / "examples" / "errands" / "behavior")
    file = load_example(REPO / "examples" / "demo" / "agents.xabsl")
    assert isinstance(folder.example, BenchExample) and isinstance(file.example, BenchExample)
    assert folder.sources[0].agents_file == REPO / "examples" / "errands" / "behavior" / "agents.xabsl"
    assert file.root == REPO / "examples" / "demo" and file.name == "demo"


def test_an_agents_file_deep_in_a_tree_serves_its_include_closure_only(tmp_path: Path, client_for: Any) -> None:
    team = tmp_path / "team"
    shutil.copytree(REPO / "examples" / "demo", team / "src" / "behavior" / "deep")
    deep = team / "src" / "behavior" / "deep"
    common = team / "src" / "common"
    common.mkdir()
    # Move the symbols out of the agents file's folder: the include closure spans two folders.
    (deep / "symbols.xabsl").rename(common / "symbols.xabsl")
    agents = deep / "agents.xabsl"
    agents.write_text(agents.read_text().replace('include "symbols.xabsl"', 'include "../../common/symbols.xabsl"'))
    (deep / "agents.xabsl").rename(deep / "TeamAgents.xabsl")
    unrelated = team / "src" / "tools"
    unrelated.mkdir()
    (unrelated / "other.xabsl").write_text("/* not part of the behavior */\n")

    plugin = load_example(deep / "TeamAgents.xabsl")
    source = plugin.sources[0]
    assert source.key == "TeamAgents" and plugin.root == team / "src"
    assert set(source.file_folders) == {deep, common}
    session = Session(plugin, seed=1, speed=5.0)
    try:
        state = session.programs["TeamAgents"]
        assert state.compilation is not None and state.compilation.ok, [d.format() for d in state.compilation.errors]
        with LiveServer(session) as server:
            listed = {f["path"] for f in httpx.get(server.url + "/api/files").json()["files"]}
            assert "common/symbols.xabsl" in listed and "behavior/deep/TeamAgents.xabsl" in listed
            assert not any(p.startswith("tools/") for p in listed)
            assert httpx.get(server.url + "/api/files/tools/other.xabsl").status_code == 403
            client = client_for(server)
            frame = client.frame_after(lambda f: bool(f["robots"][0]["path"]))
            assert frame["scene"]["robots"]
    finally:
        session.stop()


def test_a_users_folder_outside_the_package_runs_through_its_studio_py(tmp_path: Path, client_for: Any) -> None:
    world = tmp_path / "my_world"
    shutil.copytree(REPO / "examples" / "demo", world / "behavior")
    # A sibling module imported relatively: the folder is loaded as a package of its own.
    (world / "robots.py").write_text("COUNT = 3\n")
    (world / "studio.py").write_text(
        textwrap.dedent(
            '''
            """A user's world: the bench world with a name of its own and three robots."""
            from pathlib import Path

            from xabsl_studio.engine.worlds.bench import BenchExample

            from .robots import COUNT


            class Mine(BenchExample):
                name = "mine"

                def __init__(self, path: Path) -> None:
                    super().__init__(path / "behavior", robots=COUNT)
                    self.name = "mine"


            def example(path: Path) -> Mine:
                return Mine(path)
            '''
        )
    )
    plugin = load_example(world)
    assert plugin.name == "mine" and plugin.module is None and len(plugin.build_world(1).agents) == 3
    # What the simulation process receives: loaded again from the folder, in a fresh interpreter.
    context = multiprocessing.get_context("spawn")
    with context.Pool(1) as pool:
        assert pool.apply(_robots_after_unpickling, (pickle.dumps(plugin),)) == ("mine", 3)
    session = Session(plugin, seed=2, speed=5.0)
    try:
        with LiveServer(session) as server:
            client = client_for(server)
            hello = client.until(lambda m: m["type"] == "hello")
            assert len(hello["structure"]["robots"]) == 3
            frame = client.frame_after(lambda f: all(a["path"] for a in f["robots"]))
            assert len(frame["scene"]["robots"]) == 3
    finally:
        session.stop()


def _robots_after_unpickling(data: bytes) -> tuple[str, int]:
    plugin = pickle.loads(data)
    return plugin.name, len(plugin.build_world(1).agents)


def test_world_option_picks_an_installed_entry_point(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    shutil.copytree(REPO / "examples" / "soccer" / "behavior", tmp_path / "behavior")
    points = importlib.metadata.EntryPoints(
        [importlib.metadata.EntryPoint("football", "xabsl_studio.examples.soccer.studio:example", "xabsl.worlds")]
    )
    monkeypatch.setattr(importlib.metadata, "entry_points", lambda **kw: points.select(**kw))
    plugin = load_example(tmp_path, "football", robots=2)
    assert isinstance(plugin.example, SoccerExample) and plugin.example.players_per_team == 2
    assert pickle.loads(pickle.dumps(plugin)).example.players_per_team == 2
    assert isinstance(load_example(tmp_path / "behavior", "bench").example, BenchExample)
    with pytest.raises(ExampleError, match=r"unknown world 'nope'.*football"):
        load_example(tmp_path, "nope")


@pytest.mark.parametrize(
    ("path", "options", "message"),
    [
        ("examples/nowhere", {}, "no such folder"),
        ("examples", {}, "no agents.xabsl here, no file declaring agents and no studio.py"),
        ("examples/errands", {"robots": 3}, "one robot"),
        ("examples/errands", {"noise": float("nan")}, "noise must be a finite number"),
        ("examples/soccer", {"robots": 0}, r"1\.\.7"),
        ("examples/soccer", {"colour": "red"}, "unexpected keyword argument 'colour'"),
        ("examples/demo", {"robots": 500}, r"1\.\.20"),
    ],
)
def test_bad_paths_and_options_are_clear_errors(path: str, options: dict[str, Any], message: str) -> None:
    with pytest.raises(ExampleError, match=message):
        load_example(REPO / path, **options)


def test_a_broken_studio_py_is_an_error_naming_the_file(tmp_path: Path) -> None:
    (tmp_path / "studio.py").write_text("import no_such_module_here\n")
    with pytest.raises(ExampleError, match=r"studio\.py: ModuleNotFoundError"):
        load_example(tmp_path)
    other = tmp_path / "other"
    other.mkdir()
    (other / "studio.py").write_text("example = 3\n")
    with pytest.raises(ExampleError, match=r"defines no callable example"):
        load_example(other)


def test_the_server_names_no_example() -> None:
    names = re.compile(r"soccer|errands", re.IGNORECASE)
    found = [
        f"{path.relative_to(REPO)}:{n}: {line.strip()}"
        for path in sorted((REPO / "server").rglob("*.py"))
        for n, line in enumerate(path.read_text().splitlines(), 1)
        if names.search(line)
    ]
    assert not found, found


# -- errands, served live ------------------------------------------------------------------------


@pytest.fixture
def errands_session(tmp_path: Path) -> Iterator[Session]:
    root = tmp_path / "errands"
    root.mkdir()
    shutil.copytree(REPO / "examples" / "errands" / "behavior", root / "behavior")
    (root / "studio.py").write_text(
        '"""The errands plug-in."""\n\nfrom xabsl_studio.examples.errands.studio import example\n'
    )
    plugin = load_example(root)
    session = Session(plugin, seed=1, speed=10.0, behavior_hz=plugin.behavior_hz, physics_hz=plugin.physics_hz)
    yield session
    session.stop()
    del session
    gc.collect()  # pymunk spaces must be freed while the interpreter runs


def _names(client: WsClient) -> list[str]:
    program = client.program(0)
    options = {o["id"]: o["name"] for o in program["options"]}
    behaviors = {b["id"]: b["name"] for b in program["behaviors"]}
    assert client.frame is not None
    return [options[n[2]] if n[0] == 0 else behaviors[n[2]] for n in client.frame["robots"][0]["path"]]


def test_errands_runs_live_with_the_plan_monitor_as_the_robots_engine(
    errands_session: Session, client_for: Any
) -> None:
    assert isinstance(errands_session.example, WorldPlugin)
    with LiveServer(errands_session) as server:
        client = client_for(server)
        hello = client.until(lambda m: m["type"] == "hello")
        scene = hello["scene"]
        assert scene["kind"] == "errands" and scene["field"] == {"x": [0, 8000], "y": [0, 8000]}
        assert len(scene["walls"]) == 4 and scene["robot_radius"] == 200
        labels = {s.get("label") for s in scene["shapes"]}
        assert {"a", "b", "c"} <= labels and sum(s["shape"] == "rect" for s in scene["shapes"]) == 3
        assert hello["structure"]["robots"] == [
            {"id": 0, "name": "robot", "team": "errands", "number": 1, "program": "behavior", "engine": True}
        ]
        # The monitor plans, then drives the first operator: goto a c.
        frame = client.frame_after(lambda f: f["scene"]["op"] == "goto a c", timeout=30)
        assert _names(client)[0] == "execute_plan" and "run_goto" in str(client.program(0)["options"])
        dynamic = frame["scene"]
        shapes = {s.get("caption"): s for s in dynamic["shapes"] if "caption" in s}
        assert shapes["book"]["x"] == 6500 and shapes["mug"]["x"] == 4000
        assert sum(s["shape"] == "segment" for s in dynamic["shapes"]) == 3  # two rays and the gripper
        assert client.values[0]["outputs"], "the monitor's output symbols are in the frames"
        start = dynamic["robots"][0]
        moved = client.frame_after(lambda f: f["scene"]["robots"][0][:2] != start[:2], timeout=20)
        assert moved["scene"]["s"]["goto a c"] > 0.0
        # Forcing works on the plan monitor like on any behavior: hold it in `finished`.
        reply = client.command("force_option", robot=0, option="execute_plan")
        assert reply["ok"], reply
        status = httpx.get(server.url + "/api/status").json()
        assert status["example"] == "errands" and status["programs"]["behavior"]["ok"]


def test_a_save_hot_reloads_the_plan_monitor_and_the_errand_goes_on(errands_session: Session, client_for: Any) -> None:
    with LiveServer(errands_session) as server:
        client = client_for(server)
        client.frame_after(lambda f: f["scene"]["op"] == "goto a c", timeout=30)
        with httpx.Client(base_url=server.url) as http:
            got = http.get("/api/files/behavior/symbols.xabsl")
            text = got.json()["text"].replace("goto_timeout = 60000", "goto_timeout = 61000")
            response = http.put(
                "/api/files/behavior/symbols.xabsl", json={"text": text}, headers={"If-Match": got.headers["etag"]}
            )
            assert response.status_code == 200, response.text
            assert response.json()["reloaded"] == ["behavior"]
        hello = client.wait_hello("reload")
        constants = {c["name"]: c["value"] for c in hello["structure"]["programs"]["behavior"]["constants"]}
        assert constants["goto_timeout"] == 61000
        # The same world and the same monitor state: the robot is still on its first operator.
        frame = client.frame_after(lambda f: f["gen"] == hello["generation"], timeout=10)
        assert frame["scene"]["op"] == "goto a c" and _names(client)[0] == "execute_plan"


def test_a_behavior_folder_without_agents_xabsl_uses_its_one_file_declaring_agents(tmp_path: Path) -> None:
    folder = tmp_path / "Behavior"
    shutil.copytree(REPO / "examples" / "demo", folder)
    (folder / "agents.xabsl").rename(folder / "Soccer.xabsl")
    plugin = load_example(folder)
    assert plugin.sources[0].agents_file == folder / "Soccer.xabsl" and plugin.sources[0].key == "Soccer"
    (folder / "Other.xabsl").write_text((folder / "Soccer.xabsl").read_text())
    with pytest.raises(ExampleError, match=r"several files declare agents \(Other\.xabsl, Soccer\.xabsl\)"):
        load_example(folder)
    assert load_example(folder / "Other.xabsl").sources[0].key == "Other"
