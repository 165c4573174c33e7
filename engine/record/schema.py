"""The recording format: topic names, JSON Schemas and the constants every writer and reader shares.

A recording is an MCAP file whose messages are JSON (``message_encoding="json"``) described by
JSON Schemas (schema encoding ``"jsonschema"``, draft 2020-12), so Foxglove and any MCAP reader can
open it. docs/recordings.md is the user-facing description; this module is the single source of
the names and schemas (the writer registers them, the tests validate every message against them).

Time: every message's ``log_time`` and ``publish_time`` is the recording tick ``seq`` times the
behavior period, in nanoseconds (:func:`tick_time_ns`), so a tick's messages share one timestamp
and seeking tick ``k`` is a time lookup in MCAP's own chunk index. ``seq`` counts the ticks the
recording saw (0, 1, 2, ...), monotonic across resets and reloads; ``t`` is the world's engine
clock of that tick (ms), which a reset sets back.
"""

from __future__ import annotations

from typing import Any

#: ``format`` of the header message; readers refuse other formats.
FORMAT = "xabsl-recording"
#: Bumped when a message changes incompatibly; readers refuse newer versions.
VERSION = 1
#: MCAP profile written into the file header.
PROFILE = "xabsl"
#: Symbol values are written in full (a key frame) every this many ticks, changes only in between.
KEY_EVERY = 40

# -- topics -------------------------------------------------------------------------------------

#: Once, first: format, rates, seed, agents, per program the symbol and parameter tables.
RECORDING = "/xabsl/recording"
#: Per program generation (the start, each hot reload): the behavior description (program JSON).
PROGRAM = "/xabsl/program"
#: Debugging and session events: reloads, forcing, overrides, pause/step/speed, resets, breakpoints.
EVENTS = "/xabsl/events"
#: Once (and after a reset that rebuilds the world): the world's static scene.
WORLD_STATIC = "/world/static"
#: Every tick: the world's dynamic scene, as the world's ``dynamic_scene()`` returns it.
WORLD_SCENE = "/world/scene"
#: Every key frame: the world's status (score, game state, ...).
WORLD_STATUS = "/world/status"
#: Once: the static part of the world as a Foxglove scene (field lines, goals).
FOXGLOVE_FIELD = "/foxglove/field"
#: Every tick: the moving part of the world as a Foxglove scene (robots, ball).
FOXGLOVE_SCENE = "/foxglove/scene"


def agent_topic(agent: str) -> str:
    """The topic of an agent's ticks (activation path and symbol values, ``xabsl.AgentTick``)."""
    return f"/xabsl/agents/{agent}"


def fault_topic(agent: str) -> str:
    """The topic of an agent's fault changes (``xabsl.Fault``)."""
    return f"/xabsl/agents/{agent}/fault"


#: Event kinds (``/xabsl/events`` ``kind``); ``data`` per kind is documented in docs/recordings.md.
EVENT_KINDS = (
    "reload",
    "reset",
    "reset_agent",
    "select_agent",
    "force",
    "release",
    "override",
    "release_input",
    "pause",
    "resume",
    "step",
    "speed",
    "breakpoint",
    "note",
)


def tick_time_ns(seq: int, behavior_hz: int) -> int:
    """The MCAP timestamp of recording tick ``seq`` (rounded from the tick count, never accumulated)."""
    return (seq * 1_000_000_000 + behavior_hz // 2) // behavior_hz


# -- JSON Schemas -------------------------------------------------------------------------------

_DRAFT = "https://json-schema.org/draft/2020-12/schema"

_SEQ = {"type": "integer", "minimum": 0, "description": "recording tick (0, 1, ...)"}
_T = {"type": "integer", "description": "the world's engine clock of the tick [ms]"}
_VALUE = {"type": ["number", "boolean", "string", "null"]}
_OBJECT = {"type": "object"}

_SCALAR_TREE: dict[str, Any] = {
    "description": "symbol values by name, nested at each '.' of the XABSL name (ball.distance -> ball/distance)",
    "type": "object",
    "additionalProperties": {"anyOf": [_VALUE, {"$ref": "#/$defs/values"}]},
}

_OPTION_NODE = {
    "description": "[0, depth, option id, active state id, option_time, state_time, decided-in state id, leaf, params]",
    "type": "array",
    "prefixItems": [
        {"const": 0},
        {"type": "integer", "minimum": 0},
        {"type": "integer", "minimum": 0},
        {"type": "integer", "minimum": 0},
        {"type": "integer", "minimum": 0},
        {"type": "integer", "minimum": 0},
        {"type": "integer", "minimum": 0},
        {"type": "integer", "minimum": -1},
        {"type": "array", "items": _VALUE},
    ],
    "items": False,
    "minItems": 9,
}
_BEHAVIOR_NODE = {
    "description": "[1, depth, basic behavior id, time of execution, params]",
    "type": "array",
    "prefixItems": [
        {"const": 1},
        {"type": "integer", "minimum": 0},
        {"type": "integer", "minimum": 0},
        {"type": "integer", "minimum": 0},
        {"type": "array", "items": _VALUE},
    ],
    "items": False,
    "minItems": 5,
}

_READ = {
    "description": (
        "one value a decision read: [input id, value], [input id, arguments..., result] (an input function, its"
        " arguments in declaration order), [-1 - output id, value], ['p', parameter position, value],"
        " ['st', state_time], ['ot', option_time], ['done', action_done], ['conflict', value]; raw values"
        " (decimals exact, enums as host values; null: not representable)"
    ),
    "type": "array",
    "minItems": 2,
    "prefixItems": [{"type": ["integer", "string"]}],
    "items": _VALUE,
}

RECORDING_SCHEMA: dict[str, Any] = {
    "$schema": _DRAFT,
    "title": "xabsl.Recording",
    "description": "What was recorded: format, world, seed, rates, agents and per program the value tables",
    "type": "object",
    "required": ["format", "version", "example", "seed", "behavior_hz", "physics_hz", "key_every", "agents", "tables"],
    "properties": {
        "format": {"const": FORMAT},
        "version": {"type": "integer", "minimum": 1},
        "example": {"type": "string"},
        "world": {"type": "string", "description": "the static scene's kind (soccer, errands, ...)"},
        "seed": {"type": "integer"},
        "behavior_hz": {"type": "integer", "minimum": 1},
        "physics_hz": {"type": "integer", "minimum": 1},
        "key_every": {"type": "integer", "minimum": 1},
        "decimals": {"type": ["integer", "null"], "description": "fractional digits kept of decimal symbols"},
        "deterministic": {"type": "boolean", "description": "the run is a pure function of seed and programs"},
        "world_options": {"type": "object", "description": "how the world was built (the plug-in's options)"},
        "first_seq": {"type": "integer", "minimum": 0, "description": "seq of the first tick (default 0)"},
        "forked_from": {
            "type": "object",
            "description": "the recording this run was forked from, and the tick",
            "required": ["file", "seq"],
            "properties": {"file": {"type": "string"}, "seq": {"type": "integer", "minimum": 0}},
        },
        "agents": {
            "type": "array",
            "items": {
                "type": "object",
                "required": ["id", "name", "team", "number", "program"],
                "properties": {
                    "id": {"type": "integer", "minimum": 0},
                    "name": {"type": "string"},
                    "team": {"type": "string"},
                    "number": {"type": "integer"},
                    "program": {"type": ["string", "null"], "description": "program key, null: no XABSL engine"},
                },
            },
        },
        "tables": {
            "description": "per program key: what the ids and value lists of the agent channels mean",
            "type": "object",
            "additionalProperties": {
                "type": "object",
                "required": ["inputs", "outputs", "enums", "behavior_params", "assignment_sites"],
                "properties": {
                    "inputs": {"type": "array", "items": {"type": "string"}},
                    "outputs": {"type": "array", "items": {"type": "string"}},
                    "enums": {
                        "description": "enum name -> host value (as a string) -> element name",
                        "type": "object",
                        "additionalProperties": {"type": "object", "additionalProperties": {"type": "string"}},
                    },
                    "read_enums": {
                        "description": (
                            "enum name -> host value (as a string) -> element name of the raw enum values in"
                            " reads (absent: those of enums; a studio recording's enums name element indices)"
                        ),
                        "type": "object",
                        "additionalProperties": {"type": "object", "additionalProperties": {"type": "string"}},
                    },
                    "behavior_params": {
                        "description": "basic behavior name -> its parameters as [name, enum] in path order",
                        "type": "object",
                        "additionalProperties": {
                            "type": "array",
                            "items": {
                                "type": "array",
                                "prefixItems": [{"type": "string"}, {"type": ["string", "null"]}],
                            },
                        },
                    },
                    "assignment_sites": {
                        "description": "per site: [option id, state id, action position, output symbol, kind, enum]",
                        "type": "array",
                        "items": {
                            "type": "array",
                            "prefixItems": [{"type": "integer"}] * 3
                            + [
                                {"type": "string"},
                                {"enum": ["decimal", "boolean", "enum"]},
                                {"type": ["string", "null"]},
                            ],
                        },
                    },
                },
            },
        },
    },
}

PROGRAM_SCHEMA: dict[str, Any] = {
    "$schema": _DRAFT,
    "title": "xabsl.Program",
    "description": "A program generation: the behavior description (engine/emit/json.py) agents run from seq on",
    "type": "object",
    "required": ["seq", "gen", "key", "reason", "program"],
    "properties": {
        "seq": _SEQ,
        "gen": {"type": "integer", "minimum": 0},
        "key": {"type": "string"},
        "reason": {"type": "string", "description": "start, reload, reset"},
        "program": {"type": "object", "description": "the program JSON of docs/protocol.md"},
        "changed_files": {"type": "array", "items": {"type": "string"}},
        "sources": {
            "type": "object",
            "description": "the source files (names relative to the agents file's folder): what a fork re-runs",
            "required": ["agents", "files"],
            "properties": {
                "agents": {"type": "string"},
                "files": {"type": "object", "additionalProperties": {"type": "string"}},
            },
        },
        "ic": {
            "type": "string",
            "description": "the generation's XABSL intermediate code, from which a reader rebuilds the program",
        },
    },
}

EVENT_SCHEMA: dict[str, Any] = {
    "$schema": _DRAFT,
    "title": "xabsl.Event",
    "description": "Something a user or the session did between ticks",
    "type": "object",
    "required": ["seq", "t", "kind"],
    "properties": {
        "seq": _SEQ,
        "t": _T,
        "kind": {"enum": list(EVENT_KINDS)},
        "agent": {"type": ["string", "null"]},
        "data": _OBJECT,
    },
}

STATIC_SCHEMA: dict[str, Any] = {
    "$schema": _DRAFT,
    "title": "xabsl.StaticScene",
    "description": "The world's static scene (World.static_scene(); keys are the world's)",
    "type": "object",
    "required": ["seq", "scene"],
    "properties": {"seq": _SEQ, "scene": _OBJECT},
}

SCENE_SCHEMA: dict[str, Any] = {
    "$schema": _DRAFT,
    "title": "xabsl.DynamicScene",
    "description": "The world's dynamic scene of one tick (World.dynamic_scene(); keys are the world's)",
    "type": "object",
    "required": ["seq", "t", "scene"],
    "properties": {"seq": _SEQ, "t": _T, "scene": _OBJECT},
}

STATUS_SCHEMA: dict[str, Any] = {
    "$schema": _DRAFT,
    "title": "xabsl.WorldStatus",
    "description": "The world's status (World.status()): score, game state, time",
    "type": "object",
    "required": ["seq", "t", "status"],
    "properties": {"seq": _SEQ, "t": _T, "status": _OBJECT},
}

AGENT_TICK_SCHEMA: dict[str, Any] = {
    "$schema": _DRAFT,
    "title": "xabsl.AgentTick",
    "description": (
        "One agent after one tick: its activation path (pre-order; ids index the program JSON) and its"
        " input and output symbol values (all of them on key frames, else the changed ones)"
    ),
    "type": "object",
    "required": ["seq", "t", "gen", "tick", "path", "key", "inputs", "outputs"],
    "$defs": {"values": _SCALAR_TREE},
    "properties": {
        "seq": _SEQ,
        "t": _T,
        "gen": {"type": "integer", "minimum": 0, "description": "the program generation in force"},
        "tick": {"type": "integer", "minimum": 0, "description": "the engine's own tick counter"},
        "path": {"type": "array", "items": {"oneOf": [_OPTION_NODE, _BEHAVIOR_NODE]}},
        "roots": {
            "description": "the root actions as [kind, name]; present on key frames and when they changed",
            "type": "array",
            "items": {"type": "array", "prefixItems": [{"enum": ["option", "behavior", "output"]}, {"type": "string"}]},
        },
        "assignments": {
            "description": "per assignment site the value it last wrote (null: never); on key frames and changes",
            "type": "array",
            "items": _VALUE,
        },
        "key": {"type": "boolean", "description": "true: every symbol value is present (a key frame)"},
        "inputs": {"$ref": "#/$defs/values"},
        "outputs": {"$ref": "#/$defs/values"},
        "unread": {
            "description": "symbols whose host getter raised this tick (their values are absent)",
            "type": "array",
            "items": {"type": "string"},
        },
        "reads": {
            "description": (
                "what the tick's decisions read, in the order they ran (every tick): an option id starts that"
                " option's decision, the reads after it (up to the next id) are what it read"
            ),
            "type": "array",
            "items": {"anyOf": [{"type": "integer", "minimum": 0}, _READ]},
        },
    },
}

FAULT_SCHEMA: dict[str, Any] = {
    "$schema": _DRAFT,
    "title": "xabsl.Fault",
    "description": "An agent's fault state, written when it changes (null: the agent runs again)",
    "type": "object",
    "required": ["seq", "t", "fault"],
    "properties": {
        "seq": _SEQ,
        "t": _T,
        "fault": {
            "anyOf": [
                {"type": "null"},
                {
                    "type": "object",
                    "required": ["message"],
                    "properties": {
                        "message": {"type": "string"},
                        "option": {"type": ["string", "null"]},
                        "state": {"type": ["string", "null"]},
                        "error": {"type": "string"},
                        "span": {"type": ["array", "null"], "items": {"type": ["string", "integer"]}},
                    },
                },
            ]
        },
    },
}

#: schema name -> JSON Schema, for the writer and for validation.
SCHEMAS: dict[str, dict[str, Any]] = {
    s["title"]: s
    for s in (
        RECORDING_SCHEMA,
        PROGRAM_SCHEMA,
        EVENT_SCHEMA,
        STATIC_SCHEMA,
        SCENE_SCHEMA,
        STATUS_SCHEMA,
        AGENT_TICK_SCHEMA,
        FAULT_SCHEMA,
    )
}
