"""``/api/graph-groups`` and ``/api/graph?collapse=``: a team-sized option graph grouped by folder."""

from __future__ import annotations

import re
from collections.abc import Iterator

import pytest
from fastapi.testclient import TestClient

from tests import navset
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.api.app import create_app
from xabsl_studio.server.session.live import Session


@pytest.fixture(scope="module")
def api(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[TestClient, str]]:
    root = tmp_path_factory.mktemp("team")
    navset.write_set(root)
    session = Session(BenchExample(root, robots=2), seed=2)
    with TestClient(create_app(session, web_dist=None), base_url="http://127.0.0.1") as client:
        (program,) = client.get("/api/status").json()["programs"]
        yield client, program


def test_groups_list_the_folders_with_their_options(api: tuple[TestClient, str]) -> None:
    client, program = api
    groups = client.get(f"/api/graph-groups/{program}").json()["groups"]
    keys = [g["key"] for g in groups]
    assert set(keys) == {f.removeprefix("Options/") for f in navset.FOLDERS} | {"(basic behaviors)"}
    assert sum(len(g["options"]) for g in groups) == 200
    assert client.get(f"/api/graph-groups/{program}?agent=nobody").status_code == 404
    assert client.get("/api/graph-groups/nope").status_code == 404


def test_collapse_all_draws_one_node_per_group(api: tuple[TestClient, str]) -> None:
    client, program = api
    groups = client.get(f"/api/graph-groups/{program}").json()["groups"]
    overview = client.get(f"/api/graph/{program}?collapse=*")
    assert overview.status_code == 200 and overview.headers["content-type"].startswith("image/svg+xml")
    nodes = re.findall(r'<g id="([a-z]+_\d+)" class="node"', overview.text)
    assert sorted(nodes) == sorted(f"group_{n}" for n in range(len(groups)))
    plain = client.get(f"/api/graph/{program}").text
    assert len(re.findall(r'class="node"', plain)) > 200


def test_collapse_all_but_one_folder(api: tuple[TestClient, str]) -> None:
    client, program = api
    groups = client.get(f"/api/graph-groups/{program}").json()["groups"]
    keep = next(g for g in groups if g["key"] == "Kicks")
    collapse = [g["key"] for g in groups if g is not keep]
    svg = client.get(f"/api/graph/{program}", params={"collapse": "|".join(collapse)}).text
    assert set(re.findall(r'<g id="(option_\d+)" class="node"', svg)) == {f"option_{i}" for i in keep["options"]}
    # empty: grouped, nothing collapsed (every option in its folder's cluster)
    grouped = client.get(f"/api/graph/{program}?collapse=").text
    assert len(re.findall(r'<g id="option_\d+" class="node"', grouped)) == 200
    assert len(re.findall(r'class="cluster"', grouped)) == len(groups)


def test_long_collapse_lists_are_refused(api: tuple[TestClient, str]) -> None:
    client, program = api
    refused = client.get(f"/api/graph/{program}", params={"collapse": "x|" * 2001})
    assert refused.status_code == 422 and "4000" in refused.text
    # keys that name no folder (a reload removed it) collapse nothing
    assert client.get(f"/api/graph/{program}", params={"collapse": "gone|Options"}).status_code == 200
