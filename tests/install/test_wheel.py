"""The product as a user installs it: the sdist and wheel built from this checkout, installed into a
fresh venv outside the repository, run on a behavior folder that has nothing to do with the examples.

What a RoboCup team does (``pipx install xabsl-studio``, then ``xabsl serve my/agents.xabsl``) must
work without the checkout: the wheel carries the built studio UI and the examples, installs one
import package of our own, and every subcommand runs from it. The venv's packages come from the
registry (pip's cache makes it quick after the first run); nothing of the repository is on its path.
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
import urllib.parse
import urllib.request
import zipfile
from collections.abc import Iterator
from pathlib import Path

import pytest
from websockets.sync.client import connect

import xabsl_studio

REPO = Path(__file__).resolve().parents[2]

AGENTS = """\
include "symbols.xabsl";
include "walk.xabsl";
/** Walks to the line and waits. */
agent walker("Walker", walk);
"""
SYMBOLS = """\
namespace line_symbols("Line") {
  float input distance "mm";
  float output speed "mm/s";
}
"""
WALK = """\
option walk {
  initial state approach {
    decision {
      if (distance < 100) goto wait;
      else stay;
    }
    action { speed = 200; }
  }
  state wait {
    decision { stay; }
    action { speed = 0; }
  }
}
"""


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
        return port


@pytest.fixture(scope="module")
def built(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The sdist and the wheel built from it (``python -m build``: the wheel comes out of the sdist)."""
    assert (REPO / "web" / "dist" / "index.html").is_file(), "build the studio UI first (make web)"
    out = tmp_path_factory.mktemp("dist")
    subprocess.run(
        [sys.executable, "-m", "build", "--outdir", str(out), str(REPO)], check=True, capture_output=True, text=True
    )
    (wheel,) = out.glob("xabsl_studio-*.whl")
    (sdist,) = out.glob("xabsl_studio-*.tar.gz")
    return {"wheel": wheel, "sdist": sdist}


@pytest.fixture(scope="module")
def venv(built: dict[str, Path], tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A fresh venv outside the repository with the wheel installed; its ``bin`` folder."""
    root = tmp_path_factory.mktemp("user")
    subprocess.run([sys.executable, "-m", "venv", str(root / "venv")], check=True)
    bin_dir = root / "venv" / "bin"
    subprocess.run(
        [
            str(bin_dir / "python"),
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
            str(built["wheel"]),
        ],
        check=True,
        capture_output=True,
        text=True,
    )
    return bin_dir


@pytest.fixture()
def user(venv: Path, tmp_path: Path) -> Iterator[dict[str, object]]:
    """A user's folder with a behavior of their own, and an environment without the checkout on it."""
    behavior = tmp_path / "team" / "behavior"
    behavior.mkdir(parents=True)
    (behavior / "agents.xabsl").write_text(AGENTS)
    (behavior / "symbols.xabsl").write_text(SYMBOLS)
    (behavior / "walk.xabsl").write_text(WALK)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PATH"] = f"{venv}{os.pathsep}{env.get('PATH', '')}"
    env["XDG_CACHE_HOME"] = str(tmp_path / "cache")
    yield {"cwd": tmp_path, "env": env, "xabsl": str(venv / "xabsl"), "python": str(venv / "python")}


def xabsl(user: dict[str, object], *args: str, timeout: float = 120) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(user["xabsl"]), *args],
        cwd=str(user["cwd"]),
        env=user["env"],  # type: ignore[arg-type]
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def test_the_wheel_installs_one_import_package_of_our_own_with_the_ui_and_the_examples(
    built: dict[str, Path],
) -> None:
    names = zipfile.ZipFile(built["wheel"]).namelist()
    top = {name.split("/")[0] for name in names if not name.split("/")[0].endswith(".dist-info")}
    assert top == {"xabsl_studio"}
    assert "xabsl_studio/web/index.html" in names
    assert any(n.startswith("xabsl_studio/web/assets/") and n.endswith(".js") for n in names)
    assert "xabsl_studio/examples/soccer/behavior/agents.xabsl" in names
    assert "xabsl_studio/examples/soccer/tests/striker.xabsl-test.toml" in names
    # nothing of the tests or the checkout's tooling
    assert not [n for n in names if n.startswith(("tests/", "xabsl_studio/tests"))]


def test_the_installed_package_is_not_the_checkout(user: dict[str, object]) -> None:
    where = subprocess.run(
        [str(user["python"]), "-c", "import xabsl_studio, sys; print(xabsl_studio.__file__); print(sys.path)"],
        cwd=str(user["cwd"]),
        env=user["env"],  # type: ignore[arg-type]
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert str(REPO) not in where
    assert xabsl(user, "--version").stdout.strip() == f"xabsl {xabsl_studio.__version__}"


def test_compile_docs_and_trace_run_on_a_users_behavior(user: dict[str, object]) -> None:
    cwd = Path(str(user["cwd"]))
    compiled = xabsl(user, "compile", "team/behavior/agents.xabsl", "--ic", "walker.ic")
    assert compiled.returncode == 0, compiled.stderr
    assert (cwd / "walker.ic").read_bytes().count(b"\r\n") > 5
    docs = xabsl(user, "docs", "team/behavior/agents.xabsl", "-o", "site")
    assert docs.returncode == 0, docs.stderr
    assert "walk" in (cwd / "site" / "index.html").read_text()
    (cwd / "in.jsonl").write_text('{"t":0,"set":{"distance":500}}\n{"t":100,"set":{"distance":50}}\n{"t":200}\n')
    traced = xabsl(user, "trace", "team/behavior/agents.xabsl", "--inputs", "in.jsonl")
    assert traced.returncode == 0, traced.stderr
    states = [json.loads(line)["tree"][0]["state"] for line in traced.stdout.splitlines()]
    assert states == ["approach", "wait", "wait"]


@pytest.mark.parametrize("target", [["team/behavior/agents.xabsl"], ["--example", "soccer"]])
def test_serve_answers_with_the_studio_and_a_hello(user: dict[str, object], target: list[str]) -> None:
    port = free_port()
    server = subprocess.Popen(
        [str(user["xabsl"]), "serve", *target, "--port", str(port), "--no-record"],
        cwd=str(user["cwd"]),
        env=user["env"],  # type: ignore[arg-type]
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        base = f"http://127.0.0.1:{port}"
        deadline = time.monotonic() + 60
        while True:
            try:
                page = urllib.request.urlopen(base + "/", timeout=5).read().decode()
                break
            except OSError:
                assert server.poll() is None, server.stdout.read() if server.stdout else ""
                assert time.monotonic() < deadline, "the studio did not answer within 60 s"
                time.sleep(0.3)
        assert '<div id="app"' in page or "<script" in page
        script = page.split('src="', 1)[1].split('"', 1)[0]
        assert urllib.request.urlopen(urllib.parse.urljoin(base + "/", script), timeout=5).status == 200
        with connect(f"ws://127.0.0.1:{port}/ws", origin=base, open_timeout=10) as ws:  # type: ignore[arg-type]
            hello = json.loads(ws.recv(timeout=20))
        assert hello["type"] == "hello"
        expected = "walk" if target[0] != "--example" else "play_soccer"
        assert expected in json.dumps(hello["structure"]["programs"])
    finally:
        server.terminate()
        server.communicate(timeout=20)


def test_lsp_answers_initialize_over_stdio(user: dict[str, object]) -> None:
    def frame(message: dict[str, object]) -> bytes:
        body = json.dumps(message).encode()
        return b"Content-Length: %d\r\n\r\n%s" % (len(body), body)

    lsp = subprocess.Popen(
        [str(user["xabsl"]), "lsp"],
        cwd=str(user["cwd"]),
        env=user["env"],  # type: ignore[arg-type]
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    assert lsp.stdin is not None and lsp.stdout is not None
    try:
        lsp.stdin.write(frame({"jsonrpc": "2.0", "id": 1, "method": "initialize", "params": {"capabilities": {}}}))
        lsp.stdin.flush()
        headers = b""
        while not headers.endswith(b"\r\n\r\n"):
            headers += lsp.stdout.read(1)
        length = int(headers.split(b"Content-Length:")[1].split(b"\r\n")[0])
        reply = json.loads(lsp.stdout.read(length))
        assert reply["id"] == 1 and "textDocumentSync" in reply["result"]["capabilities"]
        lsp.stdin.write(frame({"jsonrpc": "2.0", "id": 2, "method": "shutdown"}))
        lsp.stdin.write(frame({"jsonrpc": "2.0", "method": "exit"}))
        lsp.stdin.close()
        assert lsp.wait(timeout=30) == 0
    finally:
        lsp.kill()
        lsp.wait()
        for stream in (lsp.stdin, lsp.stdout, lsp.stderr):
            if stream is not None:
                stream.close()


def test_run_record_profile_and_test_from_the_installed_examples(user: dict[str, object]) -> None:
    ran = xabsl(user, "run", "soccer", "--duration", "10", "--players", "2", "--record", "match.mcap")
    assert ran.returncode == 0, ran.stderr
    profiled = xabsl(user, "profile", "match.mcap", "--json")
    assert profiled.returncode == 0, profiled.stderr
    assert json.loads(profiled.stdout)["teams"]
    suites = subprocess.run(
        [
            str(user["python"]),
            "-c",
            "import xabsl_studio.examples as e, pathlib; print(pathlib.Path(e.__file__).parent)",
        ],
        cwd=str(user["cwd"]),
        env=user["env"],  # type: ignore[arg-type]
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    tested = xabsl(user, "test", f"{suites}/soccer/tests/forced.xabsl-test.toml", "-q", timeout=300)
    assert tested.returncode == 0, tested.stdout + tested.stderr
