"""Fuzz the studio's file API paths and texts: a result or a 4xx FileError, never another exception.

The behavior folder holds the odd entries that broke it before (issue 18): a FIFO named
``*.xabsl``, a symlink loop, a dangling link, a folder named ``*.xabsl``, a link out of the folder.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from hypothesis import given
from hypothesis import strategies as st

from tests.fuzz.probes import fuzz_settings, time_bound
from xabsl_studio.server.session.files import BehaviorFiles, FileError

_SEGMENTS = st.one_of(
    st.sampled_from(["behavior", "options", "o.xabsl", "pipe.xabsl", "loop.xabsl", "dangling.xabsl", "dir.xabsl",
                     "out.xabsl", "..", ".", "", ".hidden.xabsl", "C:", "x" * 300 + ".xabsl", "é" * 130 + ".xabsl"]),
    st.text(st.characters(blacklist_categories=()), max_size=12),
)  # fmt: skip
PATHS = st.lists(_SEGMENTS, min_size=1, max_size=5).map("/".join)
TEXTS = st.one_of(st.text(st.characters(blacklist_categories=()), max_size=40), st.sampled_from(["\ud800", "\r\n"]))


def _folder(root: Path) -> BehaviorFiles:
    behavior = root / "example" / "behavior"
    (behavior / "options").mkdir(parents=True)
    (behavior / "o.xabsl").write_bytes(b"option o {}\r")
    (behavior / "options" / "o.xabsl").write_bytes(b"/* caf\xe9 */\n")
    os.mkfifo(behavior / "pipe.xabsl")
    os.symlink(behavior / "loop.xabsl", behavior / "loop.xabsl")
    os.symlink(behavior / "nowhere.xabsl", behavior / "dangling.xabsl")
    (behavior / "dir.xabsl").mkdir()
    (root / "secret.xabsl").write_text("outside")
    os.symlink(root / "secret.xabsl", behavior / "out.xabsl")
    return BehaviorFiles(root / "example", [behavior])


@fuzz_settings(150)
@given(st.sampled_from(["read", "write", "create", "delete", "rename", "rename to", "resolve"]), PATHS, TEXTS)
def test_file_operations_answer_or_refuse_with_4xx(op: str, path: str, text: str) -> None:
    with tempfile.TemporaryDirectory() as folder:
        files = _folder(Path(folder))
        version = files.read("behavior/o.xabsl")[1]
        calls = {
            "read": lambda: files.read(path),
            "write": lambda: files.write(path, text, version),
            "create": lambda: files.create(path, text),
            "delete": lambda: files.delete(path, None),
            "rename": lambda: files.rename(path, "behavior/new.xabsl", None),
            "rename to": lambda: files.rename("behavior/o.xabsl", path, None),
            "resolve": lambda: files.resolve(path, must_exist=False),
        }
        try:
            with time_bound():
                calls[op]()
                files.list()
        except FileError as error:
            assert 400 <= error.status < 500, (error.status, error.message)
        assert (Path(folder) / "secret.xabsl").read_text() == "outside"
