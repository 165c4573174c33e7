"""Tournaments on Ray: a local Ray instance gives exactly the local pool's results for the same seeds.

Needs the ``ray`` extra (``make test`` installs it).
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import orjson
import pytest

from tests.tournament.test_tournament import run_cli
from xabsl_studio.engine.cli import UsageError
from xabsl_studio.examples.soccer.run import DEFAULT_AWAY, DEFAULT_HOME


def test_a_local_ray_cluster_gives_the_local_results(capsys):
    argv = [str(DEFAULT_HOME), str(DEFAULT_AWAY), "-n", "2", "--duration", "12", "--json"]
    assert run_cli(*argv, "-j", "1") == 0
    local = orjson.loads(capsys.readouterr().out)
    assert run_cli(*argv, "--ray", "local", "-j", "2") == 0
    on_ray = orjson.loads(capsys.readouterr().out)
    assert on_ray["throughput"]["backend"] == "ray local"
    assert on_ray["played"] == 2 and on_ray["failed"] == []
    del local["throughput"], on_ray["throughput"]
    assert on_ray == local


def test_without_ray_the_message_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray raises ImportError
    with pytest.raises(UsageError, match=r"pip install 'xabsl-studio\[ray\]'"):
        run_cli(str(DEFAULT_HOME), str(DEFAULT_AWAY), "-n", "1", "--duration", "4", "--ray", "local")


def test_an_address_where_no_cluster_runs_is_a_clear_error_at_once():
    with socket.socket() as probe:  # a port nothing listens on once closed
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    with pytest.raises(UsageError, match=f"no Ray cluster answers at 127.0.0.1:{port}"):
        run_cli(str(DEFAULT_HOME), str(DEFAULT_AWAY), "-n", "1", "--duration", "4", "--ray", f"127.0.0.1:{port}")


def _ray(*args: str, env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    ray = Path(sys.executable).with_name("ray")
    return subprocess.run([str(ray), *args], env=env, capture_output=True, text=True, timeout=120)


@pytest.fixture
def cluster(tmp_path: Path) -> Iterator[tuple[str, dict[str, str]]]:
    """A two-node Ray cluster on this machine, as `ray start` makes one: a head on 127.0.0.1 and a
    worker node with an address of its own (127.0.0.2), token authentication on (Ray's default for
    `ray start` since 2.59, made explicit so the test does not depend on the version's default)."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    home = tmp_path / "home"  # the token lands in ~/.ray/auth_token: a home of the test's own
    home.mkdir()
    env = {**os.environ, "HOME": str(home), "RAY_AUTH_MODE": "token", "RAY_USAGE_STATS_ENABLED": "0"}
    token = _ray("get-auth-token", "--generate", env=env)
    assert token.returncode == 0, token.stderr
    # Ray's socket paths must stay under 107 bytes: a short folder of the test's own in /tmp
    temp = Path(tempfile.mkdtemp(prefix="xray", dir="/tmp"))
    head = _ray(
        "start", "--head", "--node-ip-address", "127.0.0.1", "--port", str(port), "--num-cpus", "1",
        "--include-dashboard=false", "--temp-dir", str(temp), "--disable-usage-stats", env=env,
    )  # fmt: skip
    try:
        assert head.returncode == 0, head.stderr
        worker = _ray(
            "start", "--address", f"127.0.0.1:{port}", "--node-ip-address", "127.0.0.2", "--num-cpus", "1",
            "--disable-usage-stats", env=env,
        )  # fmt: skip
        assert worker.returncode == 0, worker.stderr
        # the driver's environment: the token file in its home, but no RAY_AUTH_MODE (what a user has)
        driver = {k: v for k, v in env.items() if k != "RAY_AUTH_MODE"}
        yield f"127.0.0.1:{port}", driver
    finally:
        _ray("stop", "--force", env=env)
        shutil.rmtree(temp, ignore_errors=True)


def test_a_tournament_joins_a_two_node_cluster_by_address_with_its_token(
    cluster: tuple[str, dict[str, str]], tmp_path: Path
) -> None:
    address, env = cluster
    argv = [str(DEFAULT_HOME), str(DEFAULT_AWAY), "-n", "2", "--duration", "8", "--players", "2", "--json"]
    done = subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", "tournament", *argv, "--ray", address],
        env=env,
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    report = orjson.loads(done.stdout)
    assert report["played"] == 2 and report["failed"] == []
    assert report["throughput"]["backend"] == f"ray {address}" and report["throughput"]["jobs"] == 2
