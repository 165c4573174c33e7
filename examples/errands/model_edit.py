"""Editing the Dual Dynamics model file from the studio: diagnostics, atomic save, hot swap.

The model loader (:mod:`xabsl_studio.engine.dynamics.model`) names the file, the key path and, for
expressions, the column inside the expression; :func:`check` turns that into editor diagnostics
with a line and column in the JSON text (:func:`locate` finds where a key path's value starts).
:func:`save` writes the text atomically whatever its state (the user's text is never lost, as for
behavior files) and hot-swaps the running DD system only when the model is clean and keeps the
names of behaviors, actuators and slow variables (the activations and actuator values carry over;
a model with other names runs after a reset).
"""

from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

from xabsl_studio.engine.dynamics.model import DDModel, ModelError, ModelSyntaxError, build_model, parse_model_json
from xabsl_studio.engine.files import write_atomically
from xabsl_studio.engine.host import WorldCommandError

if TYPE_CHECKING:
    from xabsl_studio.examples.errands.world import ErrandsWorld

_COLUMN = re.compile(r" at column (\d+)")
_INDEX = re.compile(r"\[(\d+)\]")


def version_of(data: bytes) -> str:
    """The file version the studio uses (SHA-256, first 16 hex digits)."""
    return hashlib.sha256(data).hexdigest()[:16]


def _offsets(text: str) -> dict[tuple[str, ...], int]:
    """Where every value of valid JSON ``text`` starts, by key path (list items by index)."""
    offsets: dict[tuple[str, ...], int] = {}
    n = len(text)

    def ws(i: int) -> int:
        while i < n and text[i] in " \t\r\n":
            i += 1
        return i

    def string(i: int) -> tuple[str, int]:
        j = i + 1
        while text[j] != '"':
            j += 2 if text[j] == "\\" else 1
        return str(json.loads(text[i : j + 1])), j + 1

    def value(i: int, path: tuple[str, ...]) -> int:
        i = ws(i)
        offsets[path] = i
        c = text[i]
        if c in "{[":
            close = "}" if c == "{" else "]"
            i = ws(i + 1)
            index = 0
            if text[i] == close:
                return i + 1
            while True:
                if c == "{":
                    key, i = string(ws(i))
                    i = ws(i) + 1  # the colon
                    i = value(i, (*path, key))
                else:
                    i = value(i, (*path, str(index)))
                    index += 1
                i = ws(i)
                if text[i] == ",":
                    i += 1
                    continue
                return i + 1
        if c == '"':
            return string(i)[1]
        while i < n and text[i] not in ",]} \t\r\n":
            i += 1
        return i

    value(0, ())
    return offsets


def _line_col(text: str, offset: int) -> tuple[int, int]:
    line = text.count("\n", 0, offset) + 1
    return line, offset - (text.rfind("\n", 0, offset) + 1) + 1


def locate(text: str, key: str) -> int:
    """The offset of the value of dotted key path ``key`` in valid JSON ``text`` (its deepest known prefix)."""
    offsets = _offsets(text)
    path = tuple(p for p in _INDEX.sub(r".\1", key).split(".") if p)
    while path and path not in offsets:
        path = path[:-1]
    return offsets.get(path, 0)


def _diagnostic(file: str, text: str, message: str, key: str | None, offset: int, end: int) -> dict[str, Any]:
    line, col = _line_col(text, offset)
    end_line, end_col = _line_col(text, end)
    return {
        "severity": "error",
        "code": "model",
        "message": message,
        "file": file,
        "key": key,
        "span": {
            "file": file,
            "line": line,
            "col": col,
            "end_line": end_line,
            "end_col": end_col,
            "start": offset,
            "end": end,
        },
    }


def check(world: ErrandsWorld, text: str) -> tuple[list[dict[str, Any]], DDModel | None]:
    """Diagnostics for model ``text`` (empty when clean) and the compiled model (None when not)."""
    file = world.model_name
    try:
        data = parse_model_json(text, file)  # bounded nesting and integers (issue 18)
    except ModelSyntaxError as error:
        return [_diagnostic(file, text, error.reason, None, error.pos, error.pos)], None
    if not isinstance(data, dict):
        return [_diagnostic(file, text, "a model is a JSON object", None, 0, 0)], None
    try:
        model = build_model(data, source=file, dt=world.dt)
    except ModelError as error:
        message = str(error).removeprefix(file + ": ")
        key, _, detail = message.partition(": ")
        offset = locate(text, key)
        column = _COLUMN.search(detail)
        if column is not None and text[offset : offset + 1] == '"':
            offset += int(column.group(1))  # inside the expression string, after its quote
        end = offset + 1 if offset < len(text) else offset
        return [_diagnostic(file, text, detail.split("\n", 1)[0] or message, key, offset, end)], None
    return [], model


def source(world: ErrandsWorld) -> dict[str, Any]:
    """The model file: its name (relative to the example), text and version."""
    data = world.model_path.read_bytes()
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise WorldCommandError(f"{world.model_name} is not UTF-8 text (byte {error.start})") from None
    return {"path": world.model_name, "text": text, "version": version_of(data)}


def save(world: ErrandsWorld, text: Any, version: Any) -> dict[str, Any]:
    """Save the model text atomically; hot-swap it into the running robot when clean.

    Raises:
        WorldCommandError: no text, no version, or the file changed on disk since ``version``.
    """
    if not isinstance(text, str) or not isinstance(version, str):
        raise WorldCommandError("text and version (of the file as opened) are required")
    path: Path = world.model_path
    current = version_of(path.read_bytes())
    if version != current:
        raise WorldCommandError(f"the model file changed on disk since it was opened (now version {current})")
    try:
        data = text.encode("utf-8")
    except UnicodeEncodeError as error:
        raise WorldCommandError(
            f"the text has a lone surrogate at character {error.start} (not valid Unicode)"
        ) from None
    diagnostics, model = check(world, text)
    write_atomically(path, data)
    result: dict[str, Any] = {"path": world.model_name, "version": version_of(data), "saved": True}
    if model is None:
        return result | {"ok": False, "reloaded": False, "diagnostics": diagnostics}
    why = world.swap_model(model)
    return result | {"ok": True, "reloaded": why is None, "diagnostics": [], "message": why or "hot-reloaded"}
