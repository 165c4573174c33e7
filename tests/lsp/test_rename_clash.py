"""Rename to a name already in use is refused with a clear error (it would break the build).

The soccer behavior through ``xabsl lsp`` on stdio: an option renamed to another option's name, a
state to a sibling state's, a parameter to a sibling parameter's. A free name still renames.
"""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.lsp.client import ROOT, LspClient, position, uri


@pytest.fixture
def soccer(tmp_path: Path) -> Path:
    target = tmp_path / "behavior"
    shutil.copytree(ROOT / "examples" / "soccer" / "behavior", target)
    return target


@pytest.fixture
def opened(soccer: Path) -> Iterator[tuple[LspClient, Path, str]]:
    client = LspClient()
    try:
        client.initialize(soccer)
        kick = soccer / "options" / "kick_ball.xabsl"
        text = client.open(kick)
        client.wait_diagnostics(kick)
        yield client, kick, text
    finally:
        client.close()


@pytest.mark.parametrize(
    ("needle", "delta", "new", "taken"),
    [
        ("option kick_ball", 8, "striker", "striker"),  # another option
        ("initial state prepare", 15, "kick", "kick"),  # a sibling state
        ("@direction [", 1, "strength", "@strength"),  # a sibling parameter
        ("@direction [", 1, "@strength", "@strength"),
    ],
)
def test_a_name_in_use_is_refused(
    opened: tuple[LspClient, Path, str], needle: str, delta: int, new: str, taken: str
) -> None:
    client, kick, text = opened
    at = position(text, needle, delta)
    answer = client.call("textDocument/rename", {"textDocument": {"uri": uri(kick)}, "position": at, "newName": new})
    assert "result" not in answer, answer
    message = answer["error"]["message"]
    assert "cannot rename" in message and f"'{new}'" in message, message
    assert taken in message and "defined more than once" in message, message
    assert "traceback" not in str(answer["error"].get("data")), answer


def test_a_free_name_renames(opened: tuple[LspClient, Path, str]) -> None:
    client, kick, text = opened
    at = position(text, "initial state prepare", 15)
    edit = client.request(
        "textDocument/rename", {"textDocument": {"uri": uri(kick)}, "position": at, "newName": "line_up"}
    )
    assert {e["newText"] for e in edit["changes"][uri(kick)]} == {"line_up"}
