"""``GET /api/picture/...`` on a live studio: the graphs as SVG, PNG, PDF files, a robot's tick, bad input.

A real uvicorn serves the demo on the bench world; the pictures come over HTTP (httpx) and are
opened by programs that are not ours: ``xml.etree``, the PNG chunk layout, poppler's ``pdftoppm``.
"""

from __future__ import annotations

import shutil
import subprocess
import xml.etree.ElementTree as ET
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import httpx2 as httpx
import pytest

from tests.cli.test_picture_cli import png_size
from tests.server.conftest import LiveServer, WsClient
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.api.security import SecurityPolicy
from xabsl_studio.server.session.live import Session

TOKEN = "picture-token-0123456789abcdef"
SVG = "{http://www.w3.org/2000/svg}"


@pytest.fixture
def studio(demo_dir: Path, client_for: Callable[..., WsClient]) -> Iterator[tuple[httpx.Client, str, WsClient]]:
    session = Session(BenchExample(demo_dir))
    key = next(iter(session.programs))
    with LiveServer(session, SecurityPolicy(token=TOKEN)) as server:
        headers = {"Authorization": f"Bearer {TOKEN}"}
        with httpx.Client(base_url=server.url, headers=headers, timeout=60) as http:
            client = client_for(server, f"?token={TOKEN}")
            client.wait_hello("connect")
            client.frame_after(lambda f: any(r.get("path") for r in f.get("robots", [])), timeout=20)
            yield http, key, client


def test_the_option_graph_and_a_state_machine_in_each_format(studio: Any, tmp_path: Path) -> None:
    http, key, _ = studio
    svg = http.get(f"/api/picture/{key}")
    assert svg.status_code == 200 and svg.headers["content-type"].startswith("image/svg+xml")
    assert svg.headers["content-disposition"] == f'attachment; filename="{key}-play.svg"'
    root = ET.fromstring(svg.content)
    ids = {e.get("id") for e in root.iter() if e.get("id")}
    assert {"option_0", "option_1", "option_2"} <= ids
    assert "agent chaser" in [t.text for t in root.iter(f"{SVG}text")], "the title"
    below = ET.fromstring(http.get(f"/api/picture/{key}", params={"root": "approach_ball"}).content)
    assert {e.get("id") for e in below.iter() if (e.get("id") or "").startswith("option_")} < ids
    png = http.get(f"/api/picture/{key}/play", params={"format": "png"})
    assert png.status_code == 200 and png.headers["content-type"] == "image/png"
    width, height = png_size(png.content)
    assert width > 100 and height > 50
    pdf = http.get(f"/api/picture/{key}", params={"format": "pdf", "agent": "searcher"})
    assert pdf.status_code == 200 and pdf.headers["content-type"] == "application/pdf"
    (tmp_path / "graph.pdf").write_bytes(pdf.content)
    pdftoppm = shutil.which("pdftoppm")
    assert pdftoppm is not None, "poppler-utils (make test-deps installs it)"
    subprocess.run([pdftoppm, "-png", "-r", "72", str(tmp_path / "graph.pdf"), str(tmp_path / "page")], check=True)
    (page,) = tmp_path.glob("page*.png")
    assert png_size(page.read_bytes())[0] > 50


def test_a_robot_s_tick_is_drawn_with_what_it_ran(studio: Any) -> None:
    http, key, client = studio
    frame = client.frame_after(lambda f: any(r.get("path") for r in f.get("robots", [])))
    seq = frame["seq"]
    answer = http.get(f"/api/picture/{key}", params={"robot": 0, "seq": seq})
    assert answer.status_code == 200, answer.text
    texts = [t.text or "" for t in ET.fromstring(answer.content).iter(f"{SVG}text")]
    assert any(t.startswith(f"robot1 at tick {seq} ") for t in texts), texts
    assert any(t.startswith("▸ ") for t in texts), "the root option's active state"
    machine = http.get(f"/api/picture/{key}/play", params={"robot": 0})
    assert machine.status_code == 200
    texts = [t.text or "" for t in ET.fromstring(machine.content).iter(f"{SVG}text")]
    assert any("robot1 at tick" in t and "play: " in t for t in texts), texts
    filled = [e for e in ET.fromstring(machine.content).iter() if e.get("fill") == "#ffe08a"]
    assert len(filled) == 1, "exactly the active state"


@pytest.mark.parametrize(
    ("path", "params", "status", "message"),
    [
        ("/api/picture/{key}", {"format": "gif"}, 422, "format"),
        ("/api/picture/nope", {}, 404, "no behavior 'nope'"),
        ("/api/picture/{key}", {"root": "nope"}, 404, "no option 'nope'"),
        ("/api/picture/{key}", {"agent": "nobody"}, 404, "no agent 'nobody'"),
        ("/api/picture/{key}/nope", {"format": "png"}, 404, "no option 'nope'"),
        ("/api/picture/{key}", {"robot": 7}, 404, "no robot 7"),
        ("/api/picture/{key}", {"seq": 3}, 422, "seq needs robot"),
        ("/api/picture/{key}/play", {"robot": 0, "seq": 2**40}, 404, "is no longer kept"),
        ("/api/picture/{key}", {"robot": -1}, 422, "robot"),
    ],
)
def test_bad_requests_are_4xx_with_a_message(
    studio: Any, path: str, params: dict[str, Any], status: int, message: str
) -> None:
    http, key, _ = studio
    answer = http.get(path.format(key=key), params=params)
    assert answer.status_code == status, answer.text
    assert message in answer.text


def test_pictures_need_the_token(studio: Any) -> None:
    http, key, _ = studio
    answer = httpx.get(f"{http.base_url}/api/picture/{key}?format=png", timeout=10)
    assert answer.status_code == 401
