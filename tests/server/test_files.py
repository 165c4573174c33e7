"""Behavior files: confinement (.., absolute, NUL, symlink escapes, encodings), versions, atomic writes."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from server.files import BehaviorFiles, FileError, version_of


@pytest.fixture
def files(tmp_path: Path) -> BehaviorFiles:
    root = tmp_path / "example"
    (root / "behavior" / "options").mkdir(parents=True)
    (root / "behavior" / "agents.xabsl").write_text('agent a("A", o);\n')
    (root / "behavior" / "options" / "o.xabsl").write_text("option o {}\n")
    (root / "secret.xabsl").write_text("outside the behavior folder\n")
    (tmp_path / "outside.xabsl").write_text("outside the example\n")
    return BehaviorFiles(root, [root / "behavior"])


@pytest.mark.parametrize(
    ("path", "status"),
    [
        ("", 400),
        ("../outside.xabsl", 400),
        ("behavior/../secret.xabsl", 400),
        ("behavior/./agents.xabsl", 400),
        ("/etc/passwd", 400),
        ("C:/windows/x.xabsl", 400),
        ("behavior\\agents.xabsl", 400),
        ("behavior/agents.xabsl\x00.txt", 400),
        ("behavior//agents.xabsl", 400),
        ("behavior/.hidden.xabsl", 400),
        ("secret.xabsl", 403),
        ("behavior/missing.xabsl", 404),
        ("%2e%2e/outside.xabsl", 404),
    ],
)
def test_bad_paths_are_refused(files: BehaviorFiles, path: str, status: int) -> None:
    with pytest.raises(FileError) as refused:
        files.read(path)
    assert refused.value.status == status


def test_symlinks_that_leave_the_behavior_folder_are_refused(files: BehaviorFiles, tmp_path: Path) -> None:
    behavior = files.root / "behavior"
    os.symlink(tmp_path / "outside.xabsl", behavior / "escape.xabsl")
    os.symlink(tmp_path, behavior / "up")
    os.symlink(behavior / "options" / "o.xabsl", behavior / "alias.xabsl")
    for path in ("behavior/escape.xabsl", "behavior/up/outside.xabsl"):
        with pytest.raises(FileError) as refused:
            files.read(path)
        assert refused.value.status == 403
    with pytest.raises(FileError):
        files.create("behavior/up/new.xabsl", "x")
    assert not (tmp_path / "new.xabsl").exists()
    assert files.read("behavior/alias.xabsl")[0] == "option o {}\n", "a link inside the folder is fine"
    listed = [f["path"] for f in files.list()]
    assert "behavior/escape.xabsl" not in listed and "behavior/options/o.xabsl" in listed


def test_read_write_with_versions(files: BehaviorFiles) -> None:
    text, version = files.read("behavior/options/o.xabsl")
    assert version == version_of(text.encode())
    new = files.write("behavior/options/o.xabsl", "option o { }\n", version)
    assert files.read("behavior/options/o.xabsl") == ("option o { }\n", new)
    with pytest.raises(FileError) as conflict:
        files.write("behavior/options/o.xabsl", "lost update\n", version)
    assert conflict.value.status == 409 and conflict.value.extra["version"] == new
    with pytest.raises(FileError) as missing:
        files.write("behavior/options/o.xabsl", "x", None)
    assert missing.value.status == 428
    assert not [p for p in (files.root / "behavior" / "options").iterdir() if p.name.startswith(".")], (
        "no temp files are left behind by the atomic writes"
    )


def test_create_rename_delete(files: BehaviorFiles) -> None:
    version = files.create("behavior/options/new.xabsl", "option n {}\n")
    assert files.read("behavior/options/new.xabsl")[1] == version
    with pytest.raises(FileError) as exists:
        files.create("behavior/options/new.xabsl", "again")
    assert exists.value.status == 409
    with pytest.raises(FileError) as kind:
        files.create("behavior/options/new.py", "import os")
    assert kind.value.status == 400
    with pytest.raises(FileError) as nofolder:
        files.create("behavior/nowhere/new.xabsl", "x")
    assert nofolder.value.status == 404
    assert files.rename("behavior/options/new.xabsl", "behavior/renamed.xabsl", version) == version
    assert not (files.root / "behavior" / "options" / "new.xabsl").exists()
    with pytest.raises(FileError) as taken:
        files.rename("behavior/renamed.xabsl", "behavior/agents.xabsl", None)
    assert taken.value.status == 409
    with pytest.raises(FileError) as out:
        files.rename("behavior/renamed.xabsl", "secret2.xabsl", None)
    assert out.value.status == 403
    with pytest.raises(FileError) as stale:
        files.delete("behavior/renamed.xabsl", "0" * 16)
    assert stale.value.status == 409
    files.delete("behavior/renamed.xabsl", version)
    assert not (files.root / "behavior" / "renamed.xabsl").exists()
