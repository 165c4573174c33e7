"""Recordings that survive their writer: ``kill -9`` of a recording studio, then a new studio on its folder.

The studio process is a real ``xabsl serve`` killed with SIGKILL while it records; what it left
(``NAME.mcap.part``: complete chunks, no summary) is read with the ``mcap`` package's stream
reader (an independent reader) for what must be recovered: every tick before the last one seen.
The next ``xabsl serve`` on the folder recovers it on start; its ``GET /api/recordings`` lists it
as cut, it opens as a replay, and it holds exactly those ticks, message for message. A file no
writer holds that is not a recording stays and is listed with its reason; ``xabsl recover`` says
the same in one line.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import sys
import time
from io import BytesIO
from pathlib import Path

import httpx
import orjson
from mcap.reader import make_reader
from mcap.records import Channel, Message
from mcap.stream_reader import StreamReader

from tests.server.conftest import free_port
from xabsl_studio.engine.record import Recording
from xabsl_studio.engine.record import schema as S
from xabsl_studio.engine.record.recover import RecoveryFailed, in_use, recover

ROOT = Path(__file__).resolve().parents[2]
SOCCER = ROOT / "examples" / "soccer"
#: The .part must hold a few complete chunks (512 KiB of records each) before the kill.
PART_BYTES = 900_000
#: Seconds a studio may take to start, or to record PART_BYTES at 20x (a bound, not a timing).
DEADLINE = 240


def _serve(folder: Path, port: int, *more: str) -> subprocess.Popen[str]:
    command = [sys.executable, "-m", "xabsl_studio.engine.cli", "serve", str(SOCCER), "--port", str(port)]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    return subprocess.Popen(
        [*command, "--record-dir", str(folder), *more],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,  # its own group: the simulation process it starts goes with it
    )


def _up(process: subprocess.Popen[str], port: int) -> None:
    deadline = time.monotonic() + DEADLINE
    while True:
        try:
            httpx.get(f"http://127.0.0.1:{port}/api/status", timeout=10)
            return
        except httpx.TransportError:
            assert process.poll() is None, process.stderr.read() if process.stderr else ""
            assert time.monotonic() < deadline, "the studio did not come up"
            time.sleep(0.2)


def _end(process: subprocess.Popen[str], sig: int) -> None:
    """Send ``sig`` to the studio, then end what is left of its process group (its simulation)."""
    os.kill(process.pid, sig)
    process.wait(timeout=60)
    with contextlib.suppress(ProcessLookupError):
        os.killpg(process.pid, signal.SIGKILL)
    process.communicate(timeout=30)


def _complete_messages(part: bytes) -> list[tuple[str, Message]]:
    """``(topic, message)`` of the .part as the mcap package's stream reader reads it, to where it breaks."""
    channels: dict[int, str] = {}
    out: list[tuple[str, Message]] = []
    try:
        for record in StreamReader(BytesIO(part), validate_crcs=True).records:
            if isinstance(record, Channel):
                channels[record.id] = record.topic
            elif isinstance(record, Message):
                out.append((channels[record.channel_id], record))
    except Exception:  # where the cut is, that reader raises whatever it meets
        pass
    return out


def test_a_recording_cut_by_kill_9_is_recovered_by_the_next_studio(tmp_path: Path) -> None:
    folder = tmp_path / "recordings"
    port = free_port()
    first = _serve(folder, port, "--speed", "20")
    try:
        _up(first, port)
        deadline = time.monotonic() + DEADLINE
        while True:
            parts = list(folder.glob("*.mcap.part"))
            if parts and parts[0].stat().st_size >= PART_BYTES:
                break
            assert time.monotonic() < deadline, f"the studio recorded {[p.stat().st_size for p in parts]} bytes"
            time.sleep(0.2)
        [part] = parts
        assert in_use(part)  # the writer's lock: no studio takes a recording being written
    finally:
        _end(first, signal.SIGKILL)
    assert part.exists() and not list(folder.glob("*.mcap"))  # what kill -9 leaves
    assert not in_use(part)  # the kernel dropped the dead writer's lock
    cut = part.read_bytes()
    shutil.copy(part, tmp_path / "cut.part")
    seen = _complete_messages(cut)
    latest = max(m.log_time for _topic, m in seen)  # a tick is complete when a later one began
    kept = [(t, m) for t, m in seen if m.log_time < latest]
    expected = {(t, m.log_time, m.data) for t, m in kept}
    scenes = [orjson.loads(m.data)["seq"] for t, m in kept if t == S.WORLD_SCENE]
    last = len(scenes)
    assert scenes == list(range(last)) and last > 40

    second_port = free_port()
    second = _serve(folder, second_port, "--paused")
    try:
        _up(second, second_port)
        name = part.name.removesuffix(".part")
        listed = httpx.get(f"http://127.0.0.1:{second_port}/api/recordings", timeout=60).json()["recordings"]
        [entry] = [r for r in listed if r["name"] == name]
        assert entry["error"] is None and entry["ticks"] == last, entry
        assert entry["cut"]["file_bytes"] == len(cut) and entry["cut"]["kept_bytes"] <= len(cut)
        opened = httpx.post(f"http://127.0.0.1:{second_port}/api/recordings/open", json={"name": name}, timeout=60)
        assert opened.status_code == 200, opened.text
        status = httpx.get(f"http://127.0.0.1:{second_port}{opened.json()['url']}api/status", timeout=60)
        assert status.status_code == 200, status.text
    finally:
        _end(second, signal.SIGTERM)
    recovered = folder / name
    assert not part.exists()
    with Recording(recovered) as recording:
        assert (recording.first, recording.end) == (0, last)
        assert recording.tick(last - 1).seq == last - 1
        assert recording.cut is not None
    with recovered.open("rb") as stream:  # message for message what the cut file held, read by mcap
        got = set()
        for _schema, channel, message in make_reader(stream).iter_messages(log_time_order=False):
            data = message.data
            if channel.topic == S.RECORDING:
                header = orjson.loads(data)
                assert header.pop("cut")["kept_bytes"] <= len(cut)
                data = next(m.data for t, m in seen if t == S.RECORDING)
                assert orjson.loads(data) == header
            got.add((channel.topic, message.log_time, data))
    assert got == expected


def test_a_part_that_is_no_recording_stays_and_is_listed_with_its_reason(tmp_path: Path) -> None:
    junk = tmp_path / "junk.mcap.part"
    junk.write_bytes(b"\x89MCAP0\r\n" + b"\x06" + (2**63).to_bytes(8, "little"))
    try:
        recover(junk)
    except RecoveryFailed as error:
        assert str(error).startswith(f"{junk}: no complete tick") and "\n" not in str(error), error
    else:
        raise AssertionError("recovered a file without any tick")
    assert junk.exists()
    command = [sys.executable, "-m", "xabsl_studio.engine.cli", "recover", str(tmp_path)]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    done = subprocess.run(command, capture_output=True, text=True, env=env, timeout=120, check=False)
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "junk.mcap.part" in done.stderr, done.stderr
    assert "Traceback" not in done.stderr and junk.exists()

    from xabsl_studio.server.api.library import RecordingLibrary

    [entry] = RecordingLibrary(tmp_path).list()
    assert entry["name"] == "junk.mcap.part" and "cannot be recovered: no complete tick" in entry["error"], entry


def _file_size_limit(limit: int) -> None:
    """In the studio's process before it starts: files may not grow past ``limit`` (a full disk)."""
    import resource

    resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past it fails (EFBIG) instead of killing


def test_a_recording_stopped_by_a_full_disk_is_kept_and_recovered(tmp_path: Path) -> None:
    """Writes past 1.5 MB fail in the studio's process: the studio goes on, the recording so far stays."""
    folder = tmp_path / "recordings"
    port = free_port()
    command = [sys.executable, "-m", "xabsl_studio.engine.cli", "serve", str(SOCCER), "--port", str(port)]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    full = subprocess.Popen(
        [*command, "--record-dir", str(folder), "--speed", "20"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        start_new_session=True,
        preexec_fn=lambda: _file_size_limit(1_500_000),
    )
    try:
        _up(full, port)
        deadline = time.monotonic() + DEADLINE
        while not httpx.get(f"http://127.0.0.1:{port}/api/status", timeout=10).json()["recording"]["failed"]:
            assert time.monotonic() < deadline, "the recording never hit the limit"
            time.sleep(0.2)
        assert httpx.get(f"http://127.0.0.1:{port}/api/status", timeout=10).status_code == 200  # it goes on
        # never deleted: the .part stays until its recovery (at once, off the event loop) replaced it
        while list(folder.glob("*.recovering")) or not list(folder.glob("*.mcap*")):
            assert time.monotonic() < deadline, sorted(p.name for p in folder.iterdir())
            time.sleep(0.2)
    finally:
        _end(full, signal.SIGKILL)
    again = free_port()
    second = _serve(folder, again, "--paused")
    try:
        _up(second, again)
        listed = httpx.get(f"http://127.0.0.1:{again}/api/recordings", timeout=60).json()["recordings"]
    finally:
        _end(second, signal.SIGTERM)
    [entry] = [r for r in listed if r.get("cut")]
    assert entry["error"] is None and entry["ticks"] > 40, entry
    assert not list(folder.glob("*.mcap.part")) or all(r["name"] != entry["name"] + ".part" for r in listed)
