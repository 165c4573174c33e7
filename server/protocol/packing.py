"""The program descriptions as the studio sends them to a browser: every span packed.

A description (``xabsl_studio.engine.emit.json``) places a span on every option, state, decision
node, leaf, transition and action; as objects with the file path spelled out, spans are more
than half of a description's bytes, and the description is the bulk of the first message of a
session (``hello``; 186 KB for a 31-option set, 2 MB for a 180-option team set). On the wire to
a browser each description therefore carries ``span_files`` (the paths, once) and every span
becomes ``[file index, line, col, end_line, end_col, start, end]``. An option's ``transitions``
(the leaves of its states' decision trees, in order) and ``calls`` (its states' option and
behavior calls) are derived data, a fifth of a team set's description: they stay off the wire when
every option's are what its trees and actions give (:func:`derived_transitions`,
:func:`derived_calls`), and the description's ``derived`` names the fields the receiver derives.
``web/src/description.ts`` ``unpackDescription`` restores all of it when the hello arrives, so no
panel sees the packed form. Recordings, ``xabsl compile --json`` and ``GET /api/structure`` keep
the plain description.

A ``hello`` whose structure is still over :data:`COMPRESS_FROM` (a team's set: 700 KB for 200
options) carries it compressed (:func:`compress_structure`: zlib, then base64, in
``structure_z``, ``structure`` null): a tenth of the bytes. The browser inflates it with its own
``DecompressionStream`` (``web/src/connection.ts``) before anything sees the hello;
:func:`decode_hello` does the same for Python clients. Smaller structures (a set of a few dozen
options: about 100 KB) go as they are: nothing to wait for.
"""

from __future__ import annotations

import base64
import binascii
import zlib
from typing import Any

import orjson

__all__ = [
    "COMPRESS_FROM",
    "SPAN_FIELDS",
    "compress_structure",
    "decode_hello",
    "derived_calls",
    "derived_transitions",
    "pack_structure",
    "unpack_description",
]

#: An encoded structure this large (bytes) travels compressed in a ``hello``.
COMPRESS_FROM = 128 * 1024
#: The most a compressed structure may inflate to in :func:`decode_hello` (a hostile server).
MAX_STRUCTURE_BYTES = 256 * 1024 * 1024

#: The order of a packed span's numbers after the file index (``xabsl_studio.engine.types.Span``).
SPAN_FIELDS = ("line", "col", "end_line", "end_col", "start", "end")


def pack_structure(structure: dict[str, Any]) -> dict[str, Any]:
    """``structure`` (a hello's robots and programs) with each program's spans packed; a new dict."""
    programs = structure.get("programs") or {}
    return {**structure, "programs": {key: _pack_description(d) for key, d in programs.items()}}


def _pack_description(description: dict[str, Any]) -> dict[str, Any]:
    files: dict[str, int] = {}

    def pack(value: Any) -> Any:
        if isinstance(value, dict):
            out = {}
            for key, item in value.items():
                if key == "span" and isinstance(item, dict) and "file" in item:
                    index = files.setdefault(item["file"], len(files))
                    out[key] = [index, *(item[f] for f in SPAN_FIELDS)]
                else:
                    out[key] = pack(item)
            return out
        if isinstance(value, list):
            return [pack(item) for item in value]
        return value

    packed = pack(description)
    packed["span_files"] = list(files)
    options = packed.get("options") or []
    derived = [
        field
        for field, derive in (("transitions", derived_transitions), ("calls", derived_calls))
        # only what the receiver derives exactly (a foreign description may say otherwise)
        if options and all(field in o and o[field] == derive(o) for o in options)
    ]
    if derived:
        for option in options:
            for field in derived:
                del option[field]
        packed["derived"] = derived
    return packed  # type: ignore[no-any-return]


def derived_transitions(option: dict[str, Any]) -> list[dict[str, Any]]:
    """The transitions of an option: each state's decision leaves in pre-order (then before else)."""
    out: list[dict[str, Any]] = []
    for state in option.get("states", ()):
        stack = [state.get("decision")]
        while stack:  # no recursion: an else-if chain of a thousand links is a tree that deep
            node = stack.pop()
            if not isinstance(node, dict):
                continue
            if "if" in node:
                stack.extend((node.get("else"), node.get("then")))
            else:
                out.append(
                    {
                        "from": state["name"],
                        "to": node["to"],
                        "leaf": node["leaf"],
                        "stay": node["stay"],
                        "span": node["span"],
                    }
                )
    return out


def derived_calls(option: dict[str, Any]) -> list[dict[str, Any]]:
    """The option and basic-behavior calls of an option's states, in state and action order."""
    return [
        {"state": state["name"], "type": action["type"], "name": action["name"]}
        for state in option.get("states", ())
        for action in state.get("actions", ())
        if action.get("type") in ("option", "behavior")
    ]


def unpack_description(packed: dict[str, Any]) -> dict[str, Any]:
    """The plain description of a packed one (what the web UI's ``unpackDescription`` does)."""
    files = packed["span_files"]

    def unpack(value: Any) -> Any:
        if isinstance(value, dict):
            return {
                key: (
                    {"file": files[item[0]], **dict(zip(SPAN_FIELDS, item[1:], strict=True))}
                    if key == "span" and isinstance(item, list)
                    else unpack(item)
                )
                for key, item in value.items()
                if key not in ("span_files", "derived")
            }
        if isinstance(value, list):
            return [unpack(item) for item in value]
        return value

    plain: dict[str, Any] = unpack(packed)
    derive = {"transitions": derived_transitions, "calls": derived_calls}
    for field in packed.get("derived", ()):
        for option in plain.get("options", ()):
            option[field] = derive[field](option)
    return plain


def compress_structure(encoded: bytes) -> bytes | None:
    """The hello's ``structure_z`` for an encoded structure (ASCII bytes), None when it goes as it is."""
    if len(encoded) < COMPRESS_FROM:
        return None
    return base64.b64encode(zlib.compress(encoded, 6))


def decode_hello(message: dict[str, Any]) -> dict[str, Any]:
    """A hello as received, with a compressed structure inflated into ``structure`` (others as they are).

    Raises:
        ValueError: ``structure_z`` is not base64 of zlib data of a JSON object, or inflates past
            :data:`MAX_STRUCTURE_BYTES`.
    """
    packed = message.get("structure_z")
    if message.get("type") != "hello" or packed is None:
        return message
    try:
        inflater = zlib.decompressobj()
        data = inflater.decompress(base64.b64decode(packed, validate=True), MAX_STRUCTURE_BYTES)
        if inflater.unconsumed_tail:
            raise ValueError(f"the structure inflates past {MAX_STRUCTURE_BYTES} bytes")
        structure = orjson.loads(data)
    except (zlib.error, orjson.JSONDecodeError, binascii.Error) as error:
        raise ValueError(f"a hello's structure_z does not decode: {error}") from None
    decoded = {key: value for key, value in message.items() if key != "structure_z"}
    decoded["structure"] = structure
    return decoded
