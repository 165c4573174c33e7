"""Tournaments on Ray: a local Ray instance gives exactly the local pool's results for the same seeds.

Needs the ``ray`` extra (``make test`` installs it).
"""

from __future__ import annotations

import socket
import sys

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
