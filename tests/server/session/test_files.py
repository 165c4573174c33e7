"""Behavior files: confinement (.., absolute, NUL, symlink escapes, encodings), versions, atomic writes."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from xabsl_studio.server.session.files import BehaviorFiles, FileError, version_of


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


# -- issue 18: bad text, long names, special files -------------------------------------------------


LONG = "behavior/" + "n" * 300 + ".xabsl"
LONG_UTF8 = "behavior/" + "é" * 130 + ".xabsl"  # 130 characters, 260 bytes


def test_a_lone_surrogate_is_a_4xx_not_a_crash(files: BehaviorFiles) -> None:
    _, version = files.read("behavior/options/o.xabsl")
    for act in (
        lambda: files.write("behavior/options/o.xabsl", "option o {} \ud800\n", version),
        lambda: files.create("behavior/options/s.xabsl", "\udfff"),
    ):
        with pytest.raises(FileError) as refused:
            act()
        assert 400 <= refused.value.status < 500 and "surrogate" in refused.value.message
    assert files.read("behavior/options/o.xabsl")[1] == version
    assert not (files.root / "behavior" / "options" / "s.xabsl").exists()


@pytest.mark.parametrize("path", [LONG, LONG_UTF8, "behavior/" + "d/" * 2100 + "x.xabsl", "behavior/\ud800.xabsl"])
def test_over_long_or_unencodable_names_are_400_for_every_operation(files: BehaviorFiles, path: str) -> None:
    for act in (
        lambda: files.read(path),
        lambda: files.write(path, "x", "0"),
        lambda: files.create(path, "x"),
        lambda: files.delete(path, None),
        lambda: files.rename("behavior/options/o.xabsl", path, None),
        lambda: files.rename(path, "behavior/x.xabsl", None),
        lambda: files.resolve(path, must_exist=False),
    ):
        with pytest.raises(FileError) as refused:
            act()
        assert refused.value.status == 400, refused.value.message


def test_a_name_of_exactly_255_bytes_is_fine(files: BehaviorFiles) -> None:
    name = "behavior/" + "n" * (255 - len(".xabsl")) + ".xabsl"
    files.create(name, "option n {}\n")
    assert files.read(name)[0] == "option n {}\n"


def test_a_fifo_is_neither_listed_nor_opened(files: BehaviorFiles) -> None:
    fifo = files.root / "behavior" / "options" / "pipe.xabsl"
    os.mkfifo(fifo)  # reading it blocked GET /api/files for ever
    os.symlink(fifo, files.root / "behavior" / "link-to-pipe.xabsl")
    listed = [f["path"] for f in files.list()]
    assert listed == ["behavior/agents.xabsl", "behavior/options/o.xabsl"]
    for path in ("behavior/options/pipe.xabsl", "behavior/link-to-pipe.xabsl"):
        with pytest.raises(FileError) as refused:
            files.read(path)
        assert refused.value.status == 404
        with pytest.raises(FileError):
            files.write(path, "x", "0")


def test_the_http_api_answers_4xx_for_bad_text_and_long_names(demo_dir: Path) -> None:
    from fastapi.testclient import TestClient

    from xabsl_studio.engine.worlds.bench import BenchExample
    from xabsl_studio.server.api.app import create_app
    from xabsl_studio.server.session.live import Session

    os.mkfifo(demo_dir / "options" / "pipe.xabsl")
    session = Session(BenchExample(demo_dir), seed=2)
    with TestClient(create_app(session, web_dist=None), base_url="http://127.0.0.1") as api:
        listed = api.get("/api/files")
        assert listed.status_code == 200
        assert "options/pipe.xabsl" not in [f["path"] for f in listed.json()["files"]]
        current = api.get("/api/files/options/play.xabsl").json()
        surrogate = b'{"text": "\\ud800"}'
        headers = {"content-type": "application/json", "If-Match": current["version"]}
        put = api.put("/api/files/options/play.xabsl", content=surrogate, headers=headers)
        post = api.post("/api/files/options/new.xabsl", content=surrogate, headers=headers)
        for response in (put, post):
            assert 400 <= response.status_code < 500 and "surrogate" in response.json()["detail"]
        long = "options/" + "n" * 300 + ".xabsl"
        for response in (
            api.get(f"/api/files/{long}"),
            api.put(f"/api/files/{long}", json={"text": "x"}, headers={"If-Match": "0"}),
            api.post(f"/api/files/{long}", json={"text": "x"}),
            api.delete(f"/api/files/{long}"),
            api.patch(f"/api/files/{long}", json={"path": "options/x.xabsl"}),
            api.patch("/api/files/options/play.xabsl", json={"path": long}),
            api.post("/api/compile", json={"path": long, "text": "x"}),
        ):
            assert response.status_code == 400, (response.request.method, response.text)
            assert "255 bytes" in response.json()["detail"]


# -- issue 11: files as they are ---------------------------------------------------------------------


@pytest.mark.parametrize(
    "data",
    [
        b"option o {\r  initial state s {}\r}\r",
        b"option o {\r\n  initial state s {}\r\n}\r\n",
        b"option o {\n  initial state s {}\n}\n",
        b"option o {\r\n mixed \r lone cr \n lf\r\n}",
        b"/* caf\xe9 \xb0C, latin-1 */\r\noption o {}\r\n",
        b"\xef\xbb\xbf/* BOM + caf\xc3\xa9 */\noption o {}\n",
    ],
)
def test_files_round_trip_byte_exact(files: BehaviorFiles, data: bytes) -> None:
    real = files.root / "behavior" / "options" / "o.xabsl"
    real.write_bytes(data)
    text, version = files.read("behavior/options/o.xabsl")
    assert version == version_of(data)
    assert files.write("behavior/options/o.xabsl", text, version) == version
    assert real.read_bytes() == data, "an unchanged save writes the same bytes"
    edited = text.replace("option o", "option p")
    files.write("behavior/options/o.xabsl", edited, version)
    assert real.read_bytes() == data.replace(b"option o", b"option p"), "only the edit changes"


def test_latin1_file_stays_latin1_and_refuses_what_latin1_cannot_hold(files: BehaviorFiles) -> None:
    real = files.root / "behavior" / "options" / "o.xabsl"
    real.write_bytes(b"/* \xe9t\xe9 */\n")
    text, version = files.read("behavior/options/o.xabsl")
    assert text == "/* été */\n"
    version = files.write("behavior/options/o.xabsl", "/* été à 20 °C */\n", version)
    assert real.read_bytes() == "/* été à 20 °C */\n".encode("latin-1")
    with pytest.raises(FileError) as refused:
        files.write("behavior/options/o.xabsl", "/* 20 € */\n", version)
    assert refused.value.status == 400 and "latin-1" in refused.value.message
    assert real.read_bytes() == "/* été à 20 °C */\n".encode("latin-1")


def test_a_new_file_is_utf8(files: BehaviorFiles) -> None:
    files.create("behavior/options/n.xabsl", "/* € */\r\n")
    assert (files.root / "behavior" / "options" / "n.xabsl").read_bytes() == "/* € */\r\n".encode()


def test_symlink_loops_dangling_links_and_folders_are_4xx_and_not_listed(files: BehaviorFiles) -> None:
    behavior = files.root / "behavior"
    os.symlink(behavior / "b.xabsl", behavior / "a.xabsl")
    os.symlink(behavior / "a.xabsl", behavior / "b.xabsl")  # a loop: RuntimeError in Path.resolve
    os.symlink(behavior / "nowhere.xabsl", behavior / "dangling.xabsl")
    (behavior / "folder.xabsl").mkdir()
    assert [f["path"] for f in files.list()] == ["behavior/agents.xabsl", "behavior/options/o.xabsl"]
    for path in ("behavior/a.xabsl", "behavior/dangling.xabsl", "behavior/folder.xabsl"):
        for act in (
            lambda p: files.read(p),
            lambda p: files.write(p, "x", "0"),
            lambda p: files.delete(p, None),
            lambda p: files.rename(p, "behavior/z.xabsl", None),
            lambda p: files.rename("behavior/options/o.xabsl", p, None),
            lambda p: files.create(p, "x"),
        ):
            with pytest.raises(FileError) as refused:
                act(path)
            assert 400 <= refused.value.status < 500, (path, refused.value.message)
    assert (behavior / "options" / "o.xabsl").read_text() == "option o {}\n"
