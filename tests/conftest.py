"""Shared fixtures: compile XABSL snippets written into a temporary behavior folder."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from xabsl_studio.engine.lang import Compilation, compile_file


@pytest.fixture
def compile_sources(tmp_path: Path) -> Callable[..., Compilation]:
    """Write ``{name: text}`` files into a temp folder and compile ``main`` (default: the first)."""

    def run(files: dict[str, str], main: str | None = None) -> Compilation:
        for name, text in files.items():
            path = tmp_path / name
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(text.encode("utf-8") if isinstance(text, str) else text)
        entry = main or next(iter(files))
        return compile_file(str(tmp_path / entry), base=str(tmp_path))

    return run


@pytest.fixture(scope="session", autouse=True)
def private_state_folder(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Studio state (stored breakpoints) and the live recordings of the tests' servers go to temp
    folders, never the user's (servers started without ``--record-dir`` record into the cache)."""
    import os

    os.environ.setdefault("XABSL_STATE_DIR", str(tmp_path_factory.mktemp("xabsl-state")))
    os.environ["XDG_CACHE_HOME"] = str(tmp_path_factory.mktemp("xdg-cache"))
