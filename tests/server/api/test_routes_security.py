"""Every route behind the token, and the smaller HTTP defects of issue 25 (items 5 and 11).

Against a real uvicorn on loopback whose policy is the one of a server bound off loopback (a
token, no Host check). :func:`routes` walks the app's routes (included routers, the web UI's
static mount, websocket routes), so a route added later without the token fails
:func:`test_every_route_needs_the_token_off_loopback` by itself; the replays and forks served
beside the main studio are walked under their prefixes, and unknown ids must not answer
differently from known ones without the token.
"""

from __future__ import annotations

import contextlib
import re
from collections.abc import Iterator
from pathlib import Path
from urllib.parse import quote

import httpx
import pytest
from starlette.routing import BaseRoute, Mount
from websockets.exceptions import ConnectionClosed, InvalidStatus
from websockets.sync.client import connect

from tests.server.conftest import LiveServer, WsClient
from xabsl_studio.engine.cli import main as xabsl
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.api.app import create_app
from xabsl_studio.server.api.library import RecordingLibrary
from xabsl_studio.server.api.security import SecurityPolicy
from xabsl_studio.server.protocol.limits import MAX_CLIENTS, CloseCode
from xabsl_studio.server.session.live import Session

REPO = Path(__file__).resolve().parents[3]
TOKEN = "k" * 30
AUTH = {"Authorization": f"Bearer {TOKEN}"}
#: Paths that need no token: the API's schema and its viewer (documentation of the routes, no
#: behavior data). The web UI's static files are the other public part (``STATIC``).
PUBLIC = {"/api/openapi.json", "/api/docs", "/api/docs/oauth2-redirect"}
#: Sample values for path parameters.
SAMPLES = {"path": "options/play.xabsl", "program": "demo", "option": "play", "number": "1", "ident": "1"}
APP_JS = b"console.log('the studio');\n"


class UiServer(LiveServer):
    """A :class:`LiveServer` that serves a built web UI (``web_dist``) as ``xabsl serve`` does."""

    def __init__(self, session: Session, policy: SecurityPolicy, web_dist: Path) -> None:
        super().__init__(session, policy)
        self.app = create_app(session, self.policy, web_dist=web_dist)
        self.server.config.app = self.app


@pytest.fixture(scope="module")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A record folder with one short soccer match (a replay to open beside the main studio)."""
    folder = tmp_path_factory.mktemp("recordings")
    soccer = REPO / "examples" / "soccer"
    assert xabsl(["run", str(soccer), "--duration", "2", "--players", "1", "--record", str(folder / "m.mcap")]) == 0
    return folder


@pytest.fixture
def web_dist(tmp_path: Path) -> Path:
    """A built web UI: its page and one asset."""
    dist = tmp_path / "dist"
    (dist / "assets").mkdir(parents=True)
    (dist / "index.html").write_text('<!doctype html><script src="./assets/app.js"></script>')
    (dist / "assets" / "app.js").write_bytes(APP_JS)
    return dist


@pytest.fixture
def guarded(demo_dir: Path, web_dist: Path, recordings: Path) -> Iterator[UiServer]:
    """The demo studio with a token and no Host check (as off loopback), its UI and a record folder."""
    session = Session(BenchExample(demo_dir), seed=2, speed=2.0)
    server = UiServer(session, SecurityPolicy(token=TOKEN, loopback=False), web_dist)
    server.studio.library = RecordingLibrary(recordings)
    with server:
        yield server
    session.stop()


def routes(items: list[BaseRoute]) -> Iterator[BaseRoute]:
    """Every route below ``items``: into included routers (``original_router``) and mounts' routes."""
    for route in items:
        included = getattr(route, "original_router", None)
        if included is not None:
            yield from routes(included.routes)
        elif isinstance(route, Mount) and route.routes:
            yield from routes(route.routes)
        else:
            yield route


def concrete(path: str) -> str:
    """A route's path with sample values for its parameters."""
    return re.sub(r"\{(\w+)(?::\w+)?\}", lambda m: SAMPLES[m.group(1)], path)


def refused_handshake(url: str) -> int:
    """The HTTP status that refused a websocket handshake to ``url`` (fails if it was accepted)."""
    with pytest.raises(InvalidStatus) as refused, connect(url, open_timeout=10):
        pass
    return refused.value.response.status_code


def open_replay(server: LiveServer) -> str:
    opened = httpx.post(f"{server.url}/api/recordings/open", json={"name": "m.mcap"}, headers=AUTH)
    assert opened.status_code == 200, opened.text
    return str(opened.json()["url"]).rstrip("/")


def test_every_route_needs_the_token_off_loopback(guarded: UiServer) -> None:
    found = list(routes(guarded.app.routes))
    websockets = [r for r in found if type(r).__name__.endswith("WebSocketRoute")]
    static = [r for r in found if isinstance(r, Mount)]
    http = [r for r in found if r not in websockets and r not in static]
    assert {getattr(r, "path", None) for r in websockets} >= {"/ws", "/lsp"}
    assert len(static) == 1 and len(http) >= 25, [getattr(r, "path", r) for r in found]
    replay = open_replay(guarded)
    prefixes = ["", replay, "/replay/999", "/fork/999"]
    open_doors = []
    for prefix in prefixes:
        for route in http:
            path = getattr(route, "path", "")
            for method in sorted(getattr(route, "methods", None) or {"GET"}):
                url = guarded.url + prefix + concrete(path)
                answer = httpx.request(method, url, json={}, timeout=30)
                public = path in PUBLIC
                if public and answer.status_code >= 400:
                    open_doors.append(f"{method} {prefix}{path}: public, yet {answer.status_code}")
                if not public and answer.status_code != 401:
                    open_doors.append(f"{method} {prefix}{path}: {answer.status_code} without the token")
        for route in websockets:
            url = guarded.url.replace("http", "ws") + prefix + getattr(route, "path", "")
            status = refused_handshake(url)
            if status != 403:
                open_doors.append(f"websocket {prefix}{getattr(route, 'path', '')}: {status}")
        # The web UI's files carry no behavior data: public, the same bytes under every prefix.
        for page in ("/", "/index.html", "/assets/app.js"):
            answer = httpx.get(guarded.url + prefix + page, timeout=30)
            if answer.status_code != 200 or (page.endswith(".js") and answer.content != APP_JS):
                open_doors.append(f"GET {prefix}{page}: {answer.status_code} for the UI")
        for page in ("/assets/../../etc/passwd", "/no-such-page.html", "/index.html/x"):
            assert httpx.get(guarded.url + prefix + page).status_code in (401, 404), page
    assert not open_doors, "\n".join(open_doors)


def test_unknown_replays_and_forks_answer_as_open_ones_without_the_token(guarded: UiServer) -> None:
    replay = open_replay(guarded)
    for prefix in (replay, "/replay/999", "/fork/1", "/fork/999"):
        gone = httpx.get(f"{guarded.url}{prefix}/api/status")
        assert gone.status_code == 401, (prefix, gone.status_code)
        slashless = httpx.get(f"{guarded.url}{prefix}", follow_redirects=False)
        assert slashless.status_code == 307 and slashless.headers["location"] == f"{prefix}/"
    assert httpx.get(f"{guarded.url}{replay}/api/status", headers=AUTH).status_code == 200
    unknown = httpx.get(f"{guarded.url}/replay/999/api/status", headers=AUTH)
    assert unknown.status_code == 404 and "no replay 999" in unknown.json()["detail"]


def test_docs_need_the_token_and_a_cookie_carries_it_from_page_to_page(guarded: UiServer) -> None:
    with httpx.Client(base_url=guarded.url, timeout=60) as browser:
        assert browser.get("/docs").status_code == 401
        assert browser.get("/docs/demo/index.html").status_code == 401
        first = browser.get(f"/docs?token={TOKEN}", follow_redirects=False)
        assert first.status_code == 307
        cookie = first.headers["set-cookie"]
        assert "HttpOnly" in cookie and "SameSite=strict" in cookie.replace("Strict", "strict") and TOKEN not in cookie
        # the page's relative links carry no token: the cookie does, for the documentation only
        index = browser.get(first.headers["location"])
        assert index.status_code == 200 and "approach_ball" in index.text
        assert browser.get("/docs/demo/options/approach_ball.html").status_code == 200
        assert browser.get("/docs/demo/style.css").status_code == 200
        assert browser.get("/api/status").status_code == 401, "the docs cookie opens no API"
        assert browser.get("/api/files/options/play.xabsl").status_code == 401
        assert browser.post("/api/command", json={"op": "pause"}).status_code == 401
        cookie_header = "; ".join(f"{k}={v}" for k, v in browser.cookies.items())
        with pytest.raises(InvalidStatus), connect(guarded.ws_url, additional_headers={"Cookie": cookie_header}):
            pass
    stranger = {"Cookie": cookie.split(";")[0].split("=")[0] + "=forged"}
    assert httpx.get(f"{guarded.url}/docs/demo/index.html", headers=stranger).status_code == 401


def test_get_on_a_post_only_route_is_405_with_allow(guarded: UiServer) -> None:
    for path in ("/api/command", "/api/tests/draft", "/api/compile", "/api/recordings/open", "/api/fork"):
        answer = httpx.get(guarded.url + path, headers=AUTH)
        assert answer.status_code == 405, (path, answer.status_code)
        assert answer.headers["allow"] == "POST" and answer.json()["detail"] == "Method Not Allowed"
    assert httpx.get(f"{guarded.url}/no-such-page", headers=AUTH).status_code == 404


def test_a_query_parameter_given_twice_is_refused(guarded: UiServer) -> None:
    for query in ("t0=abc&t0=5", "t0=5&t0=abc", "t0=1&t0=2", "t1=3&t0=1&t1=4"):
        answer = httpx.get(f"{guarded.url}/api/log?{query}", headers=AUTH)
        assert answer.status_code == 422, (query, answer.status_code)
        assert "given more than once" in answer.text
    assert httpx.get(f"{guarded.url}/api/log?t0=0&t1=0", headers=AUTH).status_code == 200
    assert httpx.get(f"{guarded.url}/api/log?t0=0&token={TOKEN}&token={TOKEN}").status_code == 200


@pytest.mark.parametrize(
    "name",
    [
        " .xabsl",
        "\u2028.xabsl",
        "\u2029x.xabsl",
        "\t.xabsl",
        "a\x01b.xabsl",
        "a\x7fb.xabsl",
        "a\u202eb.xabsl",
        " kick.xabsl",
        "kick .xabsl",
        "\u00a0.xabsl",
    ],
)
def test_a_new_file_name_must_be_visible(guarded: UiServer, name: str) -> None:
    path = f"options/{name}"
    answer = httpx.post(f"{guarded.url}/api/files/{quote(path)}", json={"text": "option x {}"}, headers=AUTH)
    assert answer.status_code == 400, (name, answer.status_code, answer.text)
    assert "file name" in answer.json()["detail"]
    current = httpx.get(f"{guarded.url}/api/files/options/play.xabsl", headers=AUTH).json()
    moved = httpx.patch(
        f"{guarded.url}/api/files/options/play.xabsl",
        json={"path": path},  # the new name travels in the body
        headers={**AUTH, "If-Match": current["version"]},
    )
    assert moved.status_code == 400, (name, moved.status_code)
    listed = [f["path"] for f in httpx.get(f"{guarded.url}/api/files", headers=AUTH).json()["files"]]
    assert path not in listed and "options/play.xabsl" in listed


def test_a_colon_in_a_file_name_is_not_an_absolute_path(guarded: UiServer) -> None:
    for path in ("a:b.xabsl", "options/c:d.xabsl"):
        created = httpx.post(f"{guarded.url}/api/files/{path}", json={"text": "/* x */"}, headers=AUTH)
        assert created.status_code in (201, 422), (path, created.status_code, created.text)
        read = httpx.get(f"{guarded.url}/api/files/{path}", headers=AUTH)
        assert read.status_code == 200 and read.json()["text"] == "/* x */"


def test_replay_websockets_are_capped_too(guarded: UiServer) -> None:
    replay = open_replay(guarded)
    url = guarded.url.replace("http", "ws") + replay + f"/ws?token={TOKEN}"
    with contextlib.ExitStack() as stack:
        for _ in range(MAX_CLIENTS):
            ws = stack.enter_context(connect(url, open_timeout=10, max_size=None))
            assert WsClient(ws).receive()["type"] == "hello"
        extra = stack.enter_context(connect(url, open_timeout=10, max_size=None))
        with pytest.raises(ConnectionClosed):
            extra.recv(timeout=10)
        assert extra.close_code == CloseCode.TRY_AGAIN_LATER
