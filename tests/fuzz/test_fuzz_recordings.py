"""Hostile recordings through every reader of a recording: one clear error, never a traceback or a 500.

The files come from ``tests.fuzz.recordings`` (seeded: the same files every run), plus what is
not a regular file: a FIFO, a link to ``/dev/zero``, a folder named ``*.mcap``. Each goes through

* ``Recording(...)`` read to its end (ticks, trees, paths, series): a ``RecordingError`` naming
  the file, or nothing;
* the command lines in their own processes: ``xabsl profile``, ``xabsl run ... --fork``,
  ``xabsl test`` with ``from.recording``, ``xabsl serve --replay`` (which either refuses the file
  with exit status 2 or serves it; then its routes are asked for what a replay reads);
* a real studio server listing a record folder of all of them (``GET /api/recordings`` lists
  each, with its error if unreadable) and opening each (``POST /api/recordings/open``: 200 or 4xx
  with a message), then the opened replay's routes.

A file that is damaged only where a reader does not look may pass that reader (a bad world
option passes ``xabsl profile``, not a fork): :data:`READABLE_BY_SOME` lists those; every other
file must be refused.
"""

from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
from websockets.sync.client import connect

from tests.fuzz.recordings import write_all
from tests.server.conftest import LiveServer, WsClient
from xabsl_studio.engine.cli import main
from xabsl_studio.engine.query import query_recording
from xabsl_studio.engine.record import Recording, RecordingError
from xabsl_studio.server.api.library import RecordingLibrary
from xabsl_studio.server.session.replay import ReplaySession

ROOT = Path(__file__).resolve().parents[2]
SOCCER = ROOT / "examples" / "soccer"
#: What a crash prints (each a bug, never a message for a user).
CRASHES = ("Traceback", "MemoryError", "RecursionError", "KeyError", "IndexError", "AssertionError", "struct.error")
#: Seconds one command may take on a hostile file (reading /dev/zero or a FIFO takes until killed).
BOUND = 120
#: Damaged only where some readers do not look (the rest must be refused by every reader).
READABLE_BY_SOME = (
    "world-option-unknown",
    "world-option-wrong-type",
    "seed-missing",
    "program-sources-nul",
    "program-sources-300",
    "program-sources-up",
    "program-ic-garbage",
    "tick-gen-unknown",
    "no-scene-channel",
    "no-ticks-of-one-agent",
    "scene-not-object",
)


#: ... and those the profiler reads past: it reads the activation paths, not the symbol values.
VALUES_UNREAD = ("tick-value-list",)


def _what(path: Path) -> str:
    return path.stem.split("-", 1)[1] if "-" in path.stem else path.stem


def _readable_by_some(path: Path, also: tuple[str, ...] = ()) -> bool:
    return _what(path) in READABLE_BY_SOME + also


#: What a fork reads beyond the reader: the world options, the seed, the recorded sources.
FORK_REFUSES = tuple(what for what in READABLE_BY_SOME if what.startswith(("world-option", "seed", "program-sources")))


def _intact_until(path: Path, stop: int) -> bool:
    """Whether ``Recording(path)`` reads ticks 0 .. ``stop - 1`` without an error."""
    try:
        with Recording(path) as recording:
            return len(list(recording.ticks(0, stop))) == stop
    except RecordingError:
        return False


def _opens(path: Path) -> bool:
    """Whether ``Recording(path)`` opens (the header, programs, events, static scenes read)."""
    try:
        Recording(path).close()
    except RecordingError:
        return False
    return True


def _replays(path: Path) -> bool:
    """Whether a replay of ``path`` starts: it opens, has ticks, its first and last read."""
    try:
        with Recording(path) as recording:
            if not len(recording):
                return False
            recording.tick(recording.first)
            recording.tick(recording.end - 1)
    except RecordingError:
        return False
    return True


def _sample(hostile: list[Path]) -> list[Path]:
    """For the slower command lines: every kind of damage, four of each of the cuts and flips."""
    return [p for p in hostile if not (_what(p).startswith(("cut-", "flip-")) and int(_what(p).split("-")[1]) >= 4)]


@pytest.fixture(scope="module")
def base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A real headless 1 v 1 match of 3 s (deterministic: forks re-simulate it)."""
    path = tmp_path_factory.mktemp("base") / "base.mcap"
    assert main(["run", str(SOCCER), "--duration", "3", "--players", "1", "--record", str(path)]) == 0
    return path


@pytest.fixture(scope="module")
def hostile(base: Path, tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """The hostile files, and a FIFO, a link to /dev/zero and a folder, all named ``*.mcap``."""
    folder = tmp_path_factory.mktemp("hostile")
    paths = write_all(folder, base.read_bytes())
    os.mkfifo(folder / "fifo.mcap")
    (folder / "zero.mcap").symlink_to("/dev/zero")
    (folder / "folder.mcap").mkdir()
    return [*paths, folder / "fifo.mcap", folder / "zero.mcap", folder / "folder.mcap"]


def _read_to_the_end(path: Path) -> None:
    with Recording(path) as recording:
        for view in recording.ticks():
            for agent in view.agents.values():
                agent.tree()
                agent.raw_inputs()
                agent.option_names()
        list(recording.paths())
        for name in recording.agents:
            recording.series(name, ["ball.x", "ball.distance"])
        if len(recording):
            recording.tick(recording.end - 1)
        for view in recording.programs.values():
            view.program()
    if recording.agents:  # a query reads the columns the file stores
        query_recording(path, "ball.distance > 0 || ball.distance <= 0")


def test_the_reader_refuses_each_hostile_file_with_one_line_naming_it(hostile: list[Path]) -> None:
    assert len(hostile) > 90
    readable = []
    for path in hostile:
        try:
            _read_to_the_end(path)
        except RecordingError as error:
            text = str(error)
            assert text.startswith(f"{path}: ") and "\n" not in text, text
            assert error.path == str(path) and error.reason and len(text) < 400, text
            continue
        readable.append(path.name)
        assert _readable_by_some(path), f"{path.name} was read as a good recording"
    assert len(readable) <= len(READABLE_BY_SOME)


def _run(*args: str | Path, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    command = [sys.executable, "-m", "xabsl_studio.engine.cli", *map(str, args)]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    return subprocess.run(command, capture_output=True, text=True, cwd=cwd, timeout=BOUND, env=env, check=False)


def _clean(done: subprocess.CompletedProcess[str], path: Path, also: tuple[str, ...] = ()) -> None:
    """Exit 0, or exit 2 with one message line naming the file; never a crash."""
    output = done.stdout + done.stderr
    assert not [crash for crash in CRASHES if crash in output], output
    if done.returncode == 0:
        assert _readable_by_some(path, also), f"{path.name} passed: {output[-400:]}"
        return
    assert done.returncode == 2, output
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and path.name in lines[0], done.stderr


def test_xabsl_profile_refuses_each_hostile_file(hostile: list[Path]) -> None:
    for path in hostile:
        _clean(_run("profile", path), path, VALUES_UNREAD)


def test_xabsl_run_fork_refuses_each_hostile_file(hostile: list[Path], tmp_path: Path) -> None:
    for path in _sample(hostile):
        done = _run("run", SOCCER, "--fork", path, "--at", "5", "--duration", "1", "--record", tmp_path / "out.mcap")
        output = done.stdout + done.stderr
        assert not [crash for crash in CRASHES if crash in output], output
        if done.returncode == 0:  # the ticks a fork reads are intact (damage further on is not its to see)
            assert _intact_until(path, 6), f"{path.name} was forked: {output[-400:]}"
            assert _what(path) not in FORK_REFUSES, f"{path.name} was forked: {output[-400:]}"
            continue
        assert done.returncode == 2, output
        assert len(done.stderr.strip().splitlines()) == 1 and "--fork" in done.stderr, done.stderr


def test_xabsl_test_from_each_hostile_recording_is_an_error_of_that_test(hostile: list[Path], tmp_path: Path) -> None:
    """One ``xabsl test`` run, one test per file: each an error naming its file, never a crash."""
    tests = "".join(
        f'[[test]]\nname = "from {path.name}"\nduration = 0.5\nfrom = {{ recording = "{path}", tick = 5 }}\n'
        '[[test.expect]]\nalways = true\noption = "play_soccer"\n'
        for path in hostile
    )
    suite = tmp_path / "hostile.xabsl-test.toml"
    suite.write_text(f'[suite]\npath = "{SOCCER}"\noptions = {{ robots = 1 }}\nseed = 1\nrobot = "blue1"\n{tests}')
    done = _run("test", suite, "--no-recordings", cwd=tmp_path)
    output = done.stdout + done.stderr
    assert not [crash for crash in CRASHES if crash in output], output
    assert done.returncode == 1, output
    for path in hostile:  # a test re-simulates ticks 0 .. 4 in its own world: those must be intact
        if not _intact_until(path, 6) or _what(path) == "seed-missing":
            assert f"from {path.name}: error: from tick 5 of {path}: " in output, path.name
        else:
            assert f"from {path.name}: error" not in output, path.name


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _replay_routes(url: str) -> Iterator[tuple[str, int, str]]:
    """``(route, status, body)`` of what a replay's page reads over REST."""
    routes = ("/api/status", "/api/structure", "/api/profile", "/api/graph/behavior", "/api/log?t0=0")
    for route in routes:
        response = httpx.get(url + route, timeout=60)
        yield route, response.status_code, response.text


def test_xabsl_serve_replay_refuses_or_serves_each_hostile_file(hostile: list[Path]) -> None:
    served = []
    # Every file a replay starts from (their routes are what is new here), a quarter of the others
    # (refusing them is Recording's refusal, tested above; a studio start costs seconds).
    refused = [p for p in _sample(hostile) if not _replays(p)]
    for path in [p for p in _sample(hostile) if _replays(p)] + refused[::4]:
        port = _free_port()
        command = [sys.executable, "-m", "xabsl_studio.engine.cli", "serve", "--replay", str(path), "--port", str(port)]
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
        with subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env) as process:
            try:
                assert process.stdout is not None
                line = process.stdout.readline()  # the first line: refused (EOF) or serving
                if not line:
                    assert not _replays(path), f"{path.name} was refused"
                    _out, err = process.communicate(timeout=BOUND)
                    assert process.returncode == 2, err
                    assert not [crash for crash in CRASHES if crash in err], err
                    assert len(err.strip().splitlines()) == 1 and path.name in err, err
                    continue
                assert _replays(path), f"{path.name} was served: {line}"
                served.append(path.name)
                _wait_for(port)
                for route, status, body in _replay_routes(f"http://127.0.0.1:{port}"):
                    assert status < 500, (path.name, route, body[:300])
            finally:
                if process.poll() is None:
                    process.terminate()
                    process.wait(timeout=30)
            err = process.stderr.read() if process.stderr is not None else ""
            assert "Traceback" not in err, err
    assert served, "no hostile file was served: the routes were not probed"


def _wait_for(port: int) -> None:
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=1):
                return
        except OSError:
            time.sleep(0.05)
    raise AssertionError(f"the studio on port {port} did not listen")


def test_the_studio_lists_and_opens_a_folder_of_hostile_recordings(base: Path, hostile: list[Path]) -> None:
    folder = hostile[0].parent
    with LiveServer(ReplaySession(base)) as server:
        server.studio.library = RecordingLibrary(folder)
        server.studio.studios.limits = {"replay": 200, "fork": 1}
        response = httpx.get(f"{server.url}/api/recordings", timeout=120)
        assert response.status_code == 200, response.text
        listed = {r["name"]: r for r in response.json()["recordings"]}
        regular = [p for p in hostile if p.is_file() and not p.is_symlink()]
        assert sorted(listed) == sorted(p.name for p in regular)  # no FIFO, device link or folder
        for path in regular:
            entry = listed[path.name]  # the list reads each header: unreadable ones say why
            assert bool(entry["error"]) == (not _opens(path)), entry
            opened = httpx.post(f"{server.url}/api/recordings/open", json={"name": path.name}, timeout=120)
            assert opened.status_code in (200, 422), (path.name, opened.text)
            assert (opened.status_code == 200) == _replays(path), (path.name, opened.text)
            if opened.status_code == 422:
                assert path.name in opened.json()["detail"], opened.text
                continue
            replay = f"{server.url}{opened.json()['url'].rstrip('/')}"
            for route, status, body in _replay_routes(replay):
                assert status < 500, (path.name, route, body[:300])
            assert httpx.delete(f"{server.url}/api/recordings/open/{opened.json()['id']}").status_code == 200


def test_recover_makes_each_hostile_part_a_readable_recording_or_says_why(hostile: list[Path], tmp_path: Path) -> None:
    """Each hostile file as a cut ``.mcap.part``: recovered to a file that reads, or refused in one line."""
    from xabsl_studio.engine.record.recover import RecoveryFailed, recover

    recovered = 0
    for path in hostile:
        if not path.is_file() or path.is_symlink():
            continue
        part = tmp_path / f"{path.stem}.mcap.part"
        part.write_bytes(path.read_bytes())
        try:
            done = recover(part)
        except RecoveryFailed as error:
            assert str(error).startswith(f"{part}: ") and "\n" not in str(error), error
            assert part.exists()  # never deleted
            continue
        recovered += 1
        assert not part.exists() and done.path.name == f"{path.stem}.mcap"
        with Recording(done.path) as recording:  # it opens, its last tick reads (damage kept is still refused)
            assert len(recording) == done.ticks > 0 and recording.cut is not None
            recording.tick(recording.end - 1)
        with contextlib.suppress(RecordingError):
            _read_to_the_end(done.path)
    assert recovered > 10  # the cuts and the files of a good shape elsewhere


def _damaged_midway(hostile: list[Path]) -> list[Path]:
    """Files a replay starts from (first and last tick read) with a tick between that does not."""
    out = []
    for path in hostile:
        if path.is_file() and _replays(path):
            with Recording(path) as recording:
                try:
                    for _view in recording.ticks():
                        pass
                except RecordingError:
                    out.append(path)
    return out


def test_a_replay_damaged_midway_answers_the_damage_where_it_is_read(hostile: list[Path]) -> None:
    damaged = _damaged_midway(hostile)
    assert damaged, "no hostile file is damaged between its first and last tick"
    for path in damaged:
        session = ReplaySession(path)
        first, end = session.source.first, session.source.end
        with LiveServer(session) as server, connect(server.ws_url, max_size=None, open_timeout=10) as ws:
            client = WsClient(ws)
            client.frame_after()
            errors = 0
            for seq in range(first, end, max(1, (end - first) // 40)):
                reply = client.command("seek", seq=seq)
                if not reply["ok"]:
                    errors += 1
                    assert reply["error"].startswith(f"{path}: ") and "internal error" not in reply["error"], reply
            assert errors, path.name
            assert client.command("status")["ok"]  # the connection and the session go on
            for route, status, body in _replay_routes(server.url):
                assert status < 500, (path.name, route, body[:300])
