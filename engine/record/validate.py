"""What a recording's JSON messages must look like before anything reads them.

The reader (``xabsl_studio.engine.record.reader``) checks every message it decodes here, so that
what it hands on (the header, program descriptions, ticks) has the types, ranges and references
every consumer relies on: the replay, the profiler, fork, tests from a recording, the graphs.
A file that passes the MCAP checks (``mcapread``) but says ``"behavior_hz": 0``, names an option
id its program does not have or holds a string where a path is, fails here with a
:class:`Invalid` that says where, which the reader turns into a ``RecordingError`` naming the file.

Shapes are written as data: a Python type (``int`` excludes ``bool``), a tuple of alternatives,
``[shape]`` for a list of them, ``{key: shape}`` for an object with those keys (a key ending in
``?`` may be absent), or a function that raises :class:`Invalid`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from xabsl_studio.engine.errors import RecordError

__all__ = [
    "MAX_NAME",
    "Invalid",
    "check",
    "check_event",
    "check_header",
    "check_path",
    "check_program",
    "check_tick",
]

#: The longest agent, program or symbol name accepted (and no control characters in one).
MAX_NAME = 200
#: Rates above this are not a robot's.
MAX_HZ = 100_000


class Invalid(RecordError):
    """A message that does not have the shape a recording's message has (the text says where)."""


Shape = Any


def check(value: Any, shape: Shape, where: str) -> None:
    """Raise :class:`Invalid` unless ``value`` has ``shape`` (see the module docstring)."""
    if callable(shape) and not isinstance(shape, type):
        shape(value, where)
        return
    if isinstance(shape, type):
        if not _is(value, shape):
            raise Invalid(f"{where} is {_kind(value)}, not {_name(shape)}")
        return
    if isinstance(shape, tuple):
        if not any(_matches(value, s, where) for s in shape):
            raise Invalid(f"{where} is {_kind(value)}, not {' or '.join(_name(s) for s in shape)}")
        return
    if isinstance(shape, list):
        if not isinstance(value, list):
            raise Invalid(f"{where} is {_kind(value)}, not a list")
        for i, item in enumerate(value):
            check(item, shape[0], f"{where}[{i}]")
        return
    if not isinstance(value, dict):
        raise Invalid(f"{where} is {_kind(value)}, not an object")
    for key, sub in shape.items():
        name = key.rstrip("?")
        if name not in value:
            if key.endswith("?"):
                continue
            raise Invalid(f"{where} has no {name!r}")
        check(value[name], sub, f"{where}.{name}")


def _matches(value: Any, shape: Shape, where: str) -> bool:
    try:
        check(value, shape, where)
    except Invalid:
        return False
    return True


def _is(value: Any, kind: type) -> bool:
    if kind is int:
        return isinstance(value, int) and not isinstance(value, bool)
    if kind is float:
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if kind is type(None):
        return value is None
    return isinstance(value, kind)


def _name(shape: Shape) -> str:
    if shape is type(None):
        return "null"
    if isinstance(shape, type):
        return {int: "an integer", float: "a number", str: "a string", bool: "a boolean", dict: "an object"}.get(
            shape, shape.__name__
        )
    if isinstance(shape, list):
        return "a list"
    if isinstance(shape, dict):
        return "an object"
    return getattr(shape, "__doc__", None) or "valid"


def _kind(value: Any) -> str:
    if value is None:
        return "null"
    text = repr(value)
    return f"{type(value).__name__} {text[:40]}{'...' if len(text) > 40 else ''}"


def ranged(low: int, high: int) -> Callable[[Any, str], None]:
    """An integer in ``low .. high``."""

    def checker(value: Any, where: str) -> None:
        if not _is(value, int) or not low <= value <= high:
            raise Invalid(f"{where} is {_kind(value)}, not an integer in {low}..{high}")

    checker.__doc__ = f"an integer in {low}..{high}"
    return checker


def name(value: Any, where: str) -> None:
    """A name: a non-empty string of at most MAX_NAME printable characters."""
    if not isinstance(value, str):
        raise Invalid(f"{where} is {_kind(value)}, not a name")
    if not 0 < len(value) <= MAX_NAME or not value.isprintable():
        raise Invalid(f"{where} {value[:40]!r} is not a name (1..{MAX_NAME} printable characters)")


COUNT = ranged(0, 2**62)
SEQ = ranged(0, 2**40)
OPTIONAL_NAME = (name, type(None))
PARAM = {"name": name, "type": str, "enum?": OPTIONAL_NAME}
SYMBOL = {"name": name, "type": str, "id": COUNT, "enum?": OPTIONAL_NAME}
ACTION = {"type": str, "name?": (str, type(None))}
STATE = {"name": name, "actions": [ACTION]}
OPTION = {"name": name, "id": COUNT, "params": [PARAM], "states": [STATE]}
BEHAVIOR = {"name": name, "id": COUNT, "params": [PARAM]}
ENUM = {"name": name, "elements": [str]}
DESCRIPTION = {
    "options": [OPTION],
    "behaviors": [BEHAVIOR],
    "inputs": [SYMBOL],
    "outputs": [SYMBOL],
    "enums": [ENUM],
}
TABLES = {
    "inputs?": [str],
    "outputs?": [str],
    "enums": dict,
    "read_enums?": dict,
    "behavior_params": dict,
    "assignment_sites": [list],
}
AGENT = {"id": COUNT, "name": name, "program": OPTIONAL_NAME, "team?": (str, type(None)), "number?": (int, type(None))}
HEADER = {
    "format": str,
    "version": ranged(0, 2**31),
    "behavior_hz": ranged(1, MAX_HZ),
    "physics_hz?": (ranged(1, MAX_HZ), type(None)),
    "key_every": ranged(1, 2**31),
    "seed?": int,
    "decimals?": (ranged(0, 15), type(None)),
    "deterministic?": bool,
    "example?": (str, type(None)),
    "world?": (str, type(None)),
    "agents": [AGENT],
    "tables": dict,
    "world_options?": dict,
    "first_seq?": (SEQ, type(None)),
    "forked_from?": (dict, type(None)),
    "cut?": (dict, type(None)),
}


def _enum_table(value: Any, where: str) -> None:
    """An enum table: name -> host value (an integer as a string) -> element."""
    check(value, dict, where)
    for enum, table in value.items():
        check(table, dict, f"{where}.{enum}")
        for host, element in table.items():
            try:
                int(host)
            except ValueError:
                raise Invalid(f"{where}.{enum} has the host value {host[:40]!r}, not an integer") from None
            check(element, str, f"{where}.{enum}.{host}")


def check_header(header: Any) -> None:
    """The ``/xabsl/recording`` message: rates, agents (unique names), tables of each program."""
    check(header, HEADER, "the header")
    names = [a["name"] for a in header["agents"]]
    if len(set(names)) != len(names):
        raise Invalid("the header names an agent twice")
    tables = header["tables"]
    for agent in header["agents"]:
        key = agent["program"]
        if key is not None and key not in tables:
            raise Invalid(f"the header has no tables of program {key!r} (agent {agent['name']!r})")
    for key, table in tables.items():
        where = f"the header's tables.{key[:40]}"
        check(table, TABLES, where)
        _enum_table(table["enums"], f"{where}.enums")
        if "read_enums" in table:
            _enum_table(table["read_enums"], f"{where}.read_enums")
        for behavior, params in table["behavior_params"].items():
            check(params, [[OPTIONAL_NAME]], f"{where}.behavior_params.{behavior[:40]}")


def check_program(data: Any, tables: dict[str, Any]) -> None:
    """A ``/xabsl/program`` message: its key has tables, its description the fields readers use."""
    check(
        data,
        {
            "key": name,
            "gen": COUNT,
            "seq": SEQ,
            "program": DESCRIPTION,
            "changed_files?": [str],
            "sources?": (dict, type(None)),
            "ic?": (str, type(None)),
        },
        "a program message",
    )
    if data["key"] not in tables:
        raise Invalid(f"program {data['key']!r} has no tables in the header")
    description = data["program"]
    for kind in ("options", "behaviors"):
        for i, item in enumerate(description[kind]):
            if item["id"] != i:
                raise Invalid(f"{kind}[{i}] of program {data['key']!r} has the id {item['id']}")
    for i, option in enumerate(description["options"]):
        if not option["states"]:
            raise Invalid(f"option {option['name']!r} of program {data['key']!r} has no state")
        del i


EVENT = {"seq": SEQ, "kind": str, "agent?": (str, type(None)), "data?": dict, "t?": (int, float)}


def check_event(data: Any) -> None:
    """A ``/xabsl/events`` message."""
    check(data, EVENT, "an event")
    if data["kind"] == "reload" and data.get("data", {}).get("tables") is not None:
        check(data["data"], {"key": name, "gen": COUNT, "tables": TABLES}, "a reload event's data")


TICK = {
    "seq": SEQ,
    "t": int,
    "gen": COUNT,
    "tick": COUNT,
    "path": [list],
    "key": bool,
    "inputs": dict,
    "outputs": dict,
    "roots?": [[str]],
    "assignments?": list,
    "unread?": [str],
}


def tick_ok(data: Any) -> bool:
    """The common case of :func:`check_tick`, fast (the profiler and queries check every tick of a recording)."""
    if type(data) is not dict or not _TICK_KEYS.issuperset(data):  # the key check in C
        return False
    seq, t, gen, tick = data.get("seq"), data.get("t"), data.get("gen"), data.get("tick")
    return (
        type(seq) is int
        and 0 <= seq <= 2**40
        and type(t) is int
        and type(gen) is int
        and 0 <= gen <= 2**62
        and type(tick) is int
        and 0 <= tick <= 2**62
        and type(data.get("path")) is list
        and type(data.get("key")) is bool
        and type(data.get("inputs")) is dict
        and type(data.get("outputs")) is dict
        and ("roots" not in data or _roots_ok(data["roots"]))
        and ("assignments" not in data or type(data["assignments"]) is list)
        and ("unread" not in data or (type(data["unread"]) is list and all(type(u) is str for u in data["unread"])))
    )


def _roots_ok(roots: Any) -> bool:
    return type(roots) is list and all(
        type(r) is list and len(r) == 2 and type(r[0]) is str and type(r[1]) is str for r in roots
    )


_TICK_KEYS = frozenset({*(k.rstrip("?") for k in TICK), "reads"})


def check_tick(data: Any) -> None:
    """An ``/xabsl/agents/NAME`` message (the path is checked against its program by check_path)."""
    if tick_ok(data):
        return
    check(data, TICK, "an agent's tick")
    for root in data.get("roots", ()):
        if len(root) != 2:
            raise Invalid(f"a root {root!r:.40} is not [kind, name]")


#: Per program description (by identity, while it lives): the number of states of each option.
_STATES: dict[int, tuple[Any, list[int]]] = {}


def _states_of(description: dict[str, Any]) -> list[int]:
    entry = _STATES.get(id(description))
    if entry is None or entry[0] is not description:
        if len(_STATES) > 256:
            _STATES.clear()
        entry = _STATES[id(description)] = (description, [len(o["states"]) for o in description["options"]])
    return entry[1]


def _path_ok(path: list[Any], states: list[int], behaviors: int) -> bool:
    """The common case of :func:`check_path`, fast: a well-formed path of known ids."""
    depth = -1
    options = len(states)
    for node in path:
        if type(node) is not list or not node:
            return False
        kind = node[0]
        if kind == 0 and type(kind) is int:
            if len(node) != 9:
                return False
            _, d, option, state, t1, t2, decided, leaf, params = node
            if not (
                type(d) is int
                and type(option) is int
                and 0 <= option < options
                and type(state) is int
                and type(decided) is int
                and 0 <= state < states[option]
                and 0 <= decided < states[option]
                and type(leaf) is int
                and type(t1) in (int, float)
                and type(t2) in (int, float)
                and type(params) is list
            ):
                return False
        elif kind == 1 and type(kind) is int:
            if len(node) != 5:
                return False
            _, d, behavior, t1, params = node
            if not (
                type(d) is int
                and type(behavior) is int
                and 0 <= behavior < behaviors
                and type(t1) in (int, float)
                and type(params) is list
            ):
                return False
        else:
            return False
        if not 0 <= d <= depth + 1:
            return False
        depth = d
    return True


def check_path(path: list[list[Any]], description: dict[str, Any]) -> None:
    """Every node of an activation path is well formed and names what its program has."""
    if _path_ok(path, _states_of(description), len(description["behaviors"])):
        return
    options, behaviors = description["options"], description["behaviors"]
    for i, node in enumerate(path):
        where = f"path node {i}"
        if not node or node[0] not in (0, 1) or isinstance(node[0], bool):
            raise Invalid(f"{where} is neither an option nor a behavior: {node!r:.60}")
        if node[0] == 0:
            check(node, _OPTION_NODE, where)
            if len(node) != 9:
                raise Invalid(f"{where} has {len(node)} fields, an option node 9")
            if node[2] >= len(options):
                raise Invalid(f"{where} names option {node[2]}, the program has {len(options)}")
            states = len(options[node[2]]["states"])
            if node[3] >= states or node[6] >= states:
                raise Invalid(f"{where} names state {max(node[3], node[6])}, the option has {states}")
        else:
            check(node, _BEHAVIOR_NODE, where)
            if len(node) != 5:
                raise Invalid(f"{where} has {len(node)} fields, a behavior node 5")
            if node[2] >= len(behaviors):
                raise Invalid(f"{where} names behavior {node[2]}, the program has {len(behaviors)}")
        if i == 0 and node[1] != 0:
            raise Invalid(f"{where} starts at depth {node[1]}, not 0")
        if i and node[1] > path[i - 1][1] + 1:
            raise Invalid(f"{where} is at depth {node[1]} below a node at depth {path[i - 1][1]}")


def _fields(*shapes: Shape) -> Callable[[Any, str], None]:
    def checker(value: Any, where: str) -> None:
        for k, shape in enumerate(shapes):
            if k >= len(value):
                raise Invalid(f"{where} has {len(value)} fields, not {len(shapes)}")
            check(value[k], shape, f"{where}[{k}]")

    checker.__doc__ = "a path node"
    return checker


_NUMBER = (int, float)
_OPTION_NODE = _fields(int, COUNT, COUNT, COUNT, _NUMBER, _NUMBER, COUNT, int, list)
_BEHAVIOR_NODE = _fields(int, COUNT, COUNT, _NUMBER, list)
