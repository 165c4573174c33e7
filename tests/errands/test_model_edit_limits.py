"""The studio's model editing (model_check / model_save) under hostile text: diagnostics or a
WorldCommandError, never another exception ("internal error" in the studio). Issue 18."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from types import SimpleNamespace

import pytest

from xabsl_studio.engine.host import WorldCommandError
from xabsl_studio.examples.errands import model_edit
from xabsl_studio.examples.errands.world import MODEL_PATH

RAW = json.loads(MODEL_PATH.read_text(encoding="utf-8"))


@pytest.fixture
def world(tmp_path: Path) -> SimpleNamespace:
    path = tmp_path / "model" / "errands_dd.json"
    path.parent.mkdir()
    shutil.copy(MODEL_PATH, path)
    return SimpleNamespace(model_path=path, model_name="model/errands_dd.json", dt=0.02)


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("[" * 3000 + "]" * 3000, "nested too deeply"),  # RecursionError before
        (json.dumps(RAW).replace('"lambda_m": 8.0', '"lambda_m": ' + "9" * 5000), "parameters.lambda_m"),  # ValueError
        ('{"format": 1', "not valid JSON"),
    ],
)
def test_check_gives_a_diagnostic_with_a_place(world: SimpleNamespace, text: str, words: str) -> None:
    diagnostics, model = model_edit.check(world, text)  # type: ignore[arg-type]
    assert model is None and len(diagnostics) == 1
    message = diagnostics[0]["message"] + " " + str(diagnostics[0]["key"])
    assert words in message, diagnostics[0]
    assert diagnostics[0]["span"]["line"] >= 1


def test_save_refuses_text_that_is_not_unicode(world: SimpleNamespace) -> None:
    before = world.model_path.read_bytes()
    version = model_edit.version_of(before)
    with pytest.raises(WorldCommandError, match="surrogate"):
        model_edit.save(world, json.dumps(RAW)[:-1] + ', "doc": "\ud800"}', version)  # type: ignore[arg-type]
    assert world.model_path.read_bytes() == before


def test_source_of_a_file_that_is_not_utf8_is_a_world_command_error(world: SimpleNamespace) -> None:
    world.model_path.write_bytes(b'{"name": "caf\xe9"}')
    with pytest.raises(WorldCommandError, match="UTF-8"):
        model_edit.source(world)  # type: ignore[arg-type]
