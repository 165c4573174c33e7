"""The language server reads only the behavior set it serves (docs/security.md, "The language server").

A real uvicorn serves the studio's ``/lsp`` (and ``xabsl lsp`` runs as its own process over
stdio); the client asks for files outside the behavior folders in every way a URI or a buffer
can name them: unopened paths, ``..``, percent-encoding, symlinks out of the folder, an agents
file elsewhere, ``include`` lines in a buffer, devices and FIFOs. Nothing of the outside file
may come back (its names, its comments), every request gets its answer in time, the connection
keeps answering afterwards, and no log record carries a traceback.
"""

from __future__ import annotations

import os
import shutil
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from websockets.sync.client import connect

from tests.lsp.client import ROOT, LspClient, uri
from tests.lsp.wire import WsRpc, server_log
from tests.server.conftest import LiveServer
from xabsl_studio.engine.worlds.bench import BenchExample
from xabsl_studio.server.api.security import SecurityPolicy
from xabsl_studio.server.protocol.limits import MAX_LSP_WORKERS
from xabsl_studio.server.session.live import Session

#: words of the outside file that must never reach a client
SECRETS = ("secret_input", "SECRET_COMMENT", "hidden_plan", "hidden_state", "root:x:0")

SECRET_SYMBOLS = """/** SECRET_COMMENT of the namespace */
namespace secret("SECRET_COMMENT title") {
  /** SECRET_COMMENT of the input */
  float input secret_input;
}
"""
SECRET_OPTION = """/** SECRET_COMMENT of the option */
option hidden_plan {
  initial state hidden_state {
    decision { if (secret_input > 1) goto hidden_state; else stay; }
    action { }
  }
}
"""
SECRET_AGENTS = """include "secret.xabsl";
include "plan.xabsl";
/** SECRET_COMMENT of the agent */
agent spy("SECRET_COMMENT agent", hidden_plan);
"""


def make_outside(tmp_path: Path) -> Path:
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "secret.xabsl").write_text(SECRET_SYMBOLS)
    (outside / "plan.xabsl").write_text(SECRET_OPTION)
    (outside / "agents.xabsl").write_text(SECRET_AGENTS)
    return outside


@pytest.fixture
def outside(tmp_path: Path) -> Path:
    return make_outside(tmp_path)


@pytest.fixture
def live(tmp_path: Path, outside: Path) -> Iterator[LiveServer]:
    demo = tmp_path / "demo"
    shutil.copytree(ROOT / "examples" / "demo", demo)
    session = Session(BenchExample(demo), seed=3, speed=5.0)
    with LiveServer(session, SecurityPolicy(token="s3cret")) as server:
        yield server
    session.stop()


def lsp_url(live: LiveServer) -> str:
    return f"ws://127.0.0.1:{live.port}/lsp?token=s3cret"


def assert_no_secret(text: str) -> None:
    leaked = [s for s in SECRETS if s in text]
    assert not leaked, f"the outside file leaked: {leaked}"


def no_traceback(answer: dict[str, Any]) -> None:
    assert "traceback" not in str(answer.get("error", {}).get("data", "")), answer


#: the requests that name one document and read it
def document_requests(target: str) -> list[tuple[str, dict[str, Any]]]:
    doc = {"uri": target}
    at = {"line": 3, "character": 16}  # on 'secret_input'
    return [
        ("textDocument/hover", {"textDocument": doc, "position": at}),
        ("textDocument/documentSymbol", {"textDocument": doc}),
        ("textDocument/completion", {"textDocument": doc, "position": at}),
        ("textDocument/definition", {"textDocument": doc, "position": at}),
        ("textDocument/references", {"textDocument": doc, "position": at, "context": {"includeDeclaration": True}}),
        ("textDocument/semanticTokens/full", {"textDocument": doc}),
        ("textDocument/foldingRange", {"textDocument": doc}),
        ("textDocument/prepareRename", {"textDocument": doc, "position": at}),
        ("textDocument/rename", {"textDocument": doc, "position": at, "newName": "x"}),
    ]


def hostile_uris(root: str, demo: Path, outside: Path) -> list[str]:
    """Every way of naming the outside file from a client that knows the behavior folder's URI."""
    (demo / "options" / "link.xabsl").symlink_to(outside / "secret.xabsl")
    (demo / "linked").symlink_to(outside, target_is_directory=True)
    return [
        (outside / "secret.xabsl").as_uri(),
        root + "/../outside/secret.xabsl",
        root + "/options/../../outside/secret.xabsl",
        root + "/%2e%2e/outside/secret.xabsl",
        root + "/%2E%2E/outside/%73ecret.xabsl",
        root + "/..%2foutside%2fsecret.xabsl",
        root + "/options/link.xabsl",
        root + "/linked/secret.xabsl",
        root + "/linked/agents.xabsl",
    ]


def test_unopened_files_outside_the_behavior_folder_are_not_read(live: LiveServer, outside: Path) -> None:
    demo = Path(live.session.example.root)
    with server_log() as log, connect(lsp_url(live), open_timeout=10, max_size=None) as ws:
        rpc = WsRpc(ws)
        rpc.initialize()
        root = rpc.request("xabsl/root", None)["uri"]
        for target in hostile_uris(root, demo, outside):
            for method, params in document_requests(target):
                answer = rpc.call(method, params)
                no_traceback(answer)
                assert_no_secret(str(answer))
            # a change to a document the client never opened reads nothing either
            rpc.notify(
                "textDocument/didChange",
                {"textDocument": {"uri": target, "version": 2}, "contentChanges": [{"text": "x"}]},
            )
            rpc.notify("textDocument/didSave", {"textDocument": {"uri": target}})
        rpc.settle()
        symbols = rpc.request("workspace/symbol", {"query": ""})
        assert_no_secret(str(symbols))
        assert_no_secret(rpc.text())
        # the behavior folder itself is served
        play = root + "/options/play.xabsl"
        outline = rpc.request("textDocument/documentSymbol", {"textDocument": {"uri": play}})
        assert [s["name"] for s in outline] == ["play"]
    assert log.tracebacks() == []


def test_an_agents_file_outside_the_folder_is_refused(live: LiveServer, outside: Path) -> None:
    with connect(lsp_url(live), open_timeout=10, max_size=None) as ws:
        rpc = WsRpc(ws)
        answer = rpc.call(
            "initialize",
            {
                "processId": None,
                "rootUri": outside.as_uri(),
                "capabilities": {},
                "initializationOptions": {"agents": str(outside / "agents.xabsl")},
            },
        )
        rpc.notify("initialized", {})
        root = rpc.request("xabsl/root", None)["uri"]
        assert root == Path(live.session.example.root).resolve().as_uri()  # not the client's rootUri
        play = Path(live.session.example.root) / "options" / "play.xabsl"
        rpc.open(root + "/options/play.xabsl", play.read_text())
        rpc.diagnostics(root + "/options/play.xabsl")
        rpc.settle()
        symbols = rpc.request("workspace/symbol", {"query": ""})
        assert "play" in {s["name"] for s in symbols}
        assert_no_secret(str(answer) + rpc.text())


def test_includes_in_a_buffer_reach_only_the_behavior_folder(live: LiveServer, outside: Path) -> None:
    demo = Path(live.session.example.root)
    (demo / "zero.xabsl").symlink_to("/dev/zero")
    os.mkfifo(demo / "fifo.xabsl")
    with server_log() as log, connect(lsp_url(live), open_timeout=10, max_size=None) as ws:
        rpc = WsRpc(ws)
        rpc.initialize()
        root = rpc.request("xabsl/root", None)["uri"]
        agents = root + "/agents.xabsl"
        text = (demo / "agents.xabsl").read_text()
        hostile = (
            'include "/etc/passwd";\n'
            'include "../outside/secret.xabsl";\n'
            f'include "{outside / "agents.xabsl"}";\n'
            'include "/dev/zero";\n'
            'include "zero.xabsl";\n'
            'include "fifo.xabsl";\n'
        )
        rpc.open(agents, hostile + text)
        diagnostics = rpc.diagnostics(agents)
        refused = [d for d in diagnostics if d["range"]["start"]["line"] < 6]
        # 'zero.xabsl' is '/dev/zero' once its link is resolved: included twice
        assert [d["code"] for d in refused] == ["missing-include-file"] * 4 + ["include-twice", "missing-include-file"]
        assert all("outside the behavior folders" in d["message"] for d in refused[:4])
        assert "not a regular file" in refused[5]["message"]
        # a buffer outside the folder (the client sent it) is compiled, but its includes are not read
        stray = (outside.parent / "stray.xabsl").as_uri()
        rpc.open(stray, 'include "outside/secret.xabsl";\ninclude "outside/agents.xabsl";\n')
        rpc.diagnostics(stray)
        rpc.settle()
        symbols = rpc.request("workspace/symbol", {"query": ""})
        assert_no_secret(str(symbols) + rpc.text())
    assert log.tracebacks() == []


def _connection_threads() -> int:
    """Threads of the language server's connections: not the shared worker pool's (``xabsl-lsp``, at
    most MAX_LSP_WORKERS, kept for the next connection: checked on their own) nor the studio's own
    thread pools (its file watcher's asyncio executor, Starlette's AnyIO workers)."""
    ignored = ("xabsl-lsp", "asyncio_", "AnyIO worker thread")
    return sum(1 for t in threading.enumerate() if not t.name.startswith(ignored))


def test_devices_and_fifos_answer_at_once_and_the_connection_lives_on(live: LiveServer) -> None:
    demo = Path(live.session.example.root)
    os.mkfifo(demo / "options" / "fifo.xabsl")
    (demo / "options" / "zero.xabsl").symlink_to("/dev/zero")
    os.mkfifo(demo / "other.xabsl")  # the folder's files are looked through for agents files
    threads = _connection_threads()
    with server_log() as log, connect(lsp_url(live), open_timeout=10, max_size=None) as ws:
        rpc = WsRpc(ws)
        rpc.initialize()
        root = rpc.request("xabsl/root", None)["uri"]
        for target in ("file:///dev/zero", root + "/options/zero.xabsl", root + "/options/fifo.xabsl"):
            for method, params in document_requests(target):
                started = time.monotonic()
                answer = rpc.call(method, params, timeout=10)
                assert time.monotonic() - started < 10
                no_traceback(answer)
        play = root + "/options/play.xabsl"
        rpc.open(play, (demo / "options" / "play.xabsl").read_text())
        errors = [d for d in rpc.diagnostics(play) if d["severity"] == 1]
        assert errors == []
    deadline = time.monotonic() + 10
    while _connection_threads() > threads and time.monotonic() < deadline:
        time.sleep(0.05)
    assert _connection_threads() <= threads, "a thread of the connection is left behind"
    pool = [t for t in threading.enumerate() if t.name.startswith("xabsl-lsp")]
    assert len(pool) <= MAX_LSP_WORKERS, "the language server's worker pool grew past its bound"
    assert log.tracebacks() == []


# -- xabsl lsp on stdio: the client's workspace folders are the roots -------------------------------------


def test_stdio_serves_the_workspace_and_reads_nothing_outside(tmp_path: Path, outside: Path) -> None:
    demo = tmp_path / "demo"
    shutil.copytree(ROOT / "examples" / "demo", demo)
    (demo / "options" / "link.xabsl").symlink_to(outside / "secret.xabsl")
    os.mkfifo(demo / "options" / "fifo.xabsl")
    client = LspClient()
    try:
        client.initialize(demo)
        targets = [
            uri(outside / "secret.xabsl"),
            demo.as_uri() + "/%2e%2e/outside/secret.xabsl",
            demo.as_uri() + "/options/link.xabsl",
            "file:///dev/zero",
            demo.as_uri() + "/options/fifo.xabsl",
        ]
        for target in targets:
            for method, params in document_requests(target):
                answer = client.call(method, params, timeout=10)
                no_traceback(answer)
                assert_no_secret(str(answer))
        agents = demo / "agents.xabsl"
        title, rest = agents.read_text().split("*/\n", 1)
        client.open(agents, title + '*/\ninclude "../outside/secret.xabsl";\n' + rest)
        diagnostics = client.wait_diagnostics(agents)
        assert any(d["code"] == "missing-include-file" and "outside" in d["message"] for d in diagnostics)
        symbols = client.request("workspace/symbol", {"query": ""})
        assert "play" in {s["name"] for s in symbols}
        assert_no_secret(str(symbols) + "\n".join(client.received))
    finally:
        client.close()


def test_stdio_agents_option_adds_its_folder(tmp_path: Path, outside: Path) -> None:
    # On stdio the client is the user's own editor: the agents file it names is served with its folder.
    client = LspClient()
    try:
        client.initialize(tmp_path / "nowhere", agents=str(outside / "agents.xabsl"))
        client.open(outside / "agents.xabsl")
        assert [d for d in client.wait_diagnostics(outside / "agents.xabsl") if d["severity"] == 1] == []
        names = {s["name"] for s in client.request("workspace/symbol", {"query": ""})}
        assert {"hidden_plan", "secret_input"} <= names
    finally:
        client.close()
