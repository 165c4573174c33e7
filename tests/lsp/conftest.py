from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.lsp.client import ROOT, LspClient


@pytest.fixture
def demo(tmp_path: Path) -> Path:
    """A copy of examples/demo (tests may change it)."""
    target = tmp_path / "demo"
    shutil.copytree(ROOT / "examples" / "demo", target)
    return target


@pytest.fixture
def client() -> Iterator[LspClient]:
    c = LspClient()
    yield c
    c.close()
