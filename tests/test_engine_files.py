"""xabsl_studio.engine.files: output files written through symlinks, never over devices or FIFOs; bounded reads."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from tests.kit import KIT
from xabsl_studio.engine.cli import main
from xabsl_studio.engine.files import FileTooLarge, NotRegularFile, check_regular, read_regular, write_atomically

AGENTS = KIT / "demo-approach" / "agents.xabsl"


def test_write_goes_through_a_symlink_to_its_target(tmp_path: Path) -> None:
    (tmp_path / "real").mkdir()
    target = tmp_path / "real" / "out.ic"
    target.write_bytes(b"old")
    os.chmod(target, 0o600)
    link = tmp_path / "link.ic"
    link.symlink_to(target)
    write_atomically(link, b"new")
    assert link.is_symlink(), "the link stays a link"
    assert target.read_bytes() == b"new"
    assert stat.S_IMODE(target.stat().st_mode) == 0o600
    assert sorted(p.name for p in (tmp_path / "real").iterdir()) == ["out.ic"], "no temp file left"


def test_write_through_a_chain_of_links_and_a_dangling_one(tmp_path: Path) -> None:
    target = tmp_path / "t.json"
    (tmp_path / "b").symlink_to(target)
    (tmp_path / "a").symlink_to(tmp_path / "b")
    write_atomically(tmp_path / "a", b"1")
    assert target.read_bytes() == b"1" and (tmp_path / "a").is_symlink() and (tmp_path / "b").is_symlink()


@pytest.mark.parametrize("kind", ["fifo", "directory", "link to fifo"])
def test_write_refuses_what_is_not_a_regular_file(tmp_path: Path, kind: str) -> None:
    path = tmp_path / "out"
    if kind == "directory":
        path.mkdir()
    else:
        fifo = tmp_path / "fifo"
        os.mkfifo(fifo)
        if kind == "fifo":
            path = fifo
        else:
            path.symlink_to(fifo)
    with pytest.raises(NotRegularFile) as refused:
        write_atomically(path, b"data")
    assert refused.value.strerror and "not a regular file" in refused.value.strerror
    real = os.path.realpath(path)
    assert not Path(real).is_file(), "the special file was not replaced by a regular one"


def test_compile_refuses_a_fifo_as_ic_and_keeps_a_link(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    fifo = tmp_path / "fifo.ic"
    os.mkfifo(fifo)
    assert main(["compile", str(AGENTS), "--ic", str(fifo)]) == 2
    assert "not a regular file" in capsys.readouterr().err
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    target = tmp_path / "target.ic"
    target.write_text("")
    (tmp_path / "link.ic").symlink_to(target)
    assert main(["compile", str(AGENTS), "--ic", str(tmp_path / "link.ic")]) == 0
    assert (tmp_path / "link.ic").is_symlink()
    assert target.read_bytes() == (KIT / "demo-approach" / "expected.ic").read_bytes()


def test_read_regular_refuses_fifos_devices_and_oversize(tmp_path: Path) -> None:
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)  # opening it for reading would block until a writer came: it must not
    with pytest.raises(NotRegularFile):
        read_regular(fifo, 1000)
    with pytest.raises(NotRegularFile):
        read_regular("/dev/zero", 1000)
    with pytest.raises(NotRegularFile):
        read_regular(tmp_path, 1000)
    big = tmp_path / "big"
    big.write_bytes(b"x" * 1001)
    with pytest.raises(FileTooLarge) as refused:
        read_regular(big, 1000)
    assert "1000" in str(refused.value)
    assert read_regular(big, 1001) == b"x" * 1001
    with pytest.raises(FileNotFoundError):
        read_regular(tmp_path / "missing", 10)


def test_check_regular_refuses_what_a_reader_of_its_own_would_block_on(tmp_path: Path) -> None:
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for path in (fifo, Path("/dev/zero"), tmp_path):
        with pytest.raises(NotRegularFile):
            check_regular(path)
    file = tmp_path / "file"
    file.write_bytes(b"x" * 10)
    link = tmp_path / "link"
    link.symlink_to(file)
    assert check_regular(link) == 10
    with pytest.raises(FileTooLarge):
        check_regular(file, 9)
    fds = len(os.listdir("/proc/self/fd"))
    for _ in range(20):
        with pytest.raises(NotRegularFile):
            check_regular(fifo)
    assert len(os.listdir("/proc/self/fd")) == fds, "a refused file's descriptor is closed"
