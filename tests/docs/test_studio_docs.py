"""The studio's ``/docs``: the running behavior's documentation, cached by digest, redone after a reload."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.api.app import create_app
from xabsl_studio.server.api.docs import DocsCache
from xabsl_studio.server.session.live import Session

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture
def studio(tmp_path: Path) -> Iterator[tuple[TestClient, DocsCache, Path]]:
    demo = tmp_path / "demo"
    shutil.copytree(REPO / "examples" / "demo", demo)
    app = create_app(Session(BenchExample(demo), seed=2, speed=4.0), web_dist=None)
    cache = app.state.docs_cache = DocsCache(tmp_path / "cache")
    with TestClient(app, base_url="http://127.0.0.1") as client:
        yield client, cache, demo


def test_docs_redirects_to_the_running_behavior_and_serves_its_pages(
    studio: tuple[TestClient, DocsCache, Path],
) -> None:
    client, cache, _ = studio
    first = client.get("/docs", follow_redirects=False)
    assert first.status_code == 307 and first.headers["location"] == "/docs/demo/index.html"
    index = client.get("/docs/demo/index.html")
    assert index.status_code == 200 and index.headers["content-type"].startswith("text/html")
    assert 'href="options/approach_ball.html"' in index.text
    page = client.get("/docs/demo/options/approach_ball.html")
    assert page.status_code == 200 and "<svg" in page.text and 'id="state-kick"' in page.text
    assert client.get("/docs/demo/style.css").headers["content-type"].startswith("text/css")
    assert client.get("/docs/demo/search-index.js").status_code == 200
    assert client.get("/docs/demo", follow_redirects=False).headers["location"] == "/docs/demo/index.html"
    assert cache.generated == 1  # one generation serves every page


@pytest.mark.parametrize(
    "url",
    ["/docs/nope/index.html", "/docs/demo/nope.html", "/docs/demo/%2e%2e/%2e%2e/etc/passwd", "/docs/demo/options"],
)
def test_unknown_behaviors_and_pages_are_404(studio: tuple[TestClient, DocsCache, Path], url: str) -> None:
    client, _, _ = studio
    response = client.get(url)
    assert response.status_code == 404 and "detail" in response.json()


def test_a_hot_reload_documents_the_new_behavior(studio: tuple[TestClient, DocsCache, Path]) -> None:
    client, cache, _ = studio
    assert "Kicks when it is in front." not in client.get("/docs/demo/options/approach_ball.html").text
    current = client.get("/api/files/options/approach_ball.xabsl").json()
    text = current["text"].replace(
        "kicks when it is in front.", "kicks when it is in front. Kicks when it is in front."
    )
    assert text != current["text"]
    saved = client.put("/api/files/options/approach_ball.xabsl", json={"text": text, "version": current["version"]})
    assert saved.status_code == 200 and saved.json()["reloaded"] == ["demo"], saved.text
    assert "Kicks when it is in front." in client.get("/docs/demo/options/approach_ball.html").text
    assert cache.generated == 2
    folders = sorted(p.name for p in cache.root.iterdir())
    assert len(folders) == 2 and not any(name.startswith(".") for name in folders)
    # an unchanged behavior is served from the cache
    client.get("/docs/demo/index.html")
    assert cache.generated == 2


def test_without_graphviz_docs_answer_503(
    studio: tuple[TestClient, DocsCache, Path], monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    client, _, _ = studio
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    response = client.get("/docs/demo/index.html")
    assert response.status_code == 503 and "Graphviz" in response.json()["detail"]
