"""Save as test: a behavior test file that reproduces what the studio's tester set up, for the user to edit.

:func:`draft_test` writes the TOML of one suite with one test: the world plug-in and its options
(``path``, ``world``, ``options``), the session's seed, the world's situation when the world can
describe it as a setup (a plug-in's optional ``setup_from_scene(scene, status)``; the soccer
world gives robots, ball, game state), the forced option or basic behavior with its parameters,
the input overrides (from t = 0), and one ``eventually`` assertion per option state and basic
behavior that was active, as a starting point. From a breakpoint hit (``hit``), the setup is the
scene at the hit's tick and the assertions say what the breakpoint waited for
(:func:`hit_expects`), with a comment for what the format cannot express. The studio serves it
as ``POST /api/tests/draft`` (docs/tests.md "Save as test"); ``save`` writes it into the
example's ``tests/`` folder.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from xabsl_studio.engine.errors import BehaviorTestError
from xabsl_studio.engine.runtime.breakpoints import Breakpoint
from xabsl_studio.engine.testing.spec import SUFFIX, parse_suite

__all__ = ["DraftError", "draft_file_name", "draft_test", "hit_expects", "toml_value"]

#: ``SYMBOL OP VALUE`` of a condition breakpoint: what a ``symbol`` assertion can say.
_COMPARISON = re.compile(
    r"\s*(?P<symbol>[A-Za-z_][\w.]*)\s*(?P<op><=|>=|==|!=|<|>)\s*"
    r"(?P<value>[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|true|false|[A-Za-z_][\w.]*)\s*"
)
_BOOLEAN = re.compile(r"\s*(?P<neg>!?)\s*(?P<symbol>[A-Za-z_][\w.]*)\s*")
#: A closed range bound for ``<=`` / ``>=`` (the format has ``between``, not ``at most``).
_FAR = 1e300


class DraftError(BehaviorTestError, ValueError):
    """A draft that cannot be written: a bad name or a value TOML cannot hold."""


def draft_file_name(name: str) -> str:
    """``Goalie clears!`` -> ``goalie_clears.xabsl-test.toml``.

    Raises:
        DraftError: nothing usable in ``name``.
    """
    slug = re.sub(r"[^a-z0-9]+", "_", name.lower()).strip("_")[:60]
    if not slug:
        raise DraftError(f"cannot make a file name of {name!r}")
    return slug + SUFFIX


def toml_value(value: Any) -> str:
    """``value`` as an inline TOML value (strings, booleans, finite numbers, arrays, tables).

    Raises:
        DraftError: a non-finite number, None or another type.
    """
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            raise DraftError(f"TOML has no {value}")
        return repr(round(value, 6))
    if isinstance(value, str):
        return '"' + _UNSAFE.sub(_escape, value) + '"'
    if isinstance(value, list | tuple):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        return "{ " + ", ".join(f"{_key(k)} = {toml_value(v)}" for k, v in value.items()) + " }" if value else "{}"
    raise DraftError(f"cannot write {value!r} in a test file")


#: What a TOML basic string or comment cannot hold as it is: the quote and backslash (strings),
#: control characters but the tab, and the line and paragraph separators (legal, but an editor
#: may break the line there, and a reader would see two lines where TOML sees one).
_UNSAFE = re.compile(r'["\\\x00-\x08\x0a-\x1f\x7f\u2028\u2029]')
_ESCAPES = {'"': '\\"', "\\": "\\\\", "\n": "\\n", "\r": "\\r", "\b": "\\b", "\f": "\\f"}


def _escape(match: re.Match[str]) -> str:
    char = match.group()
    return _ESCAPES.get(char) or f"\\u{ord(char):04X}"


def _comment(line: str) -> str:
    """A comment line that stays one comment line whatever text it quotes (names, conditions)."""
    return _UNSAFE.sub(lambda m: m.group() if m.group() in '"\\' else _escape(m), line)


def _key(key: str) -> str:
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else toml_value(key)


def _comparison(clause: str) -> dict[str, Any] | None:
    """The ``symbol`` predicate of one comparison clause, or None when it is not one."""
    match = _COMPARISON.fullmatch(clause)
    if match is None:
        boolean = _BOOLEAN.fullmatch(clause)
        if boolean is None or boolean["symbol"] in ("true", "false"):
            return None
        return {"symbol": boolean["symbol"], "equals": not boolean["neg"]}
    raw = match["value"]
    value: Any
    if raw in ("true", "false"):
        value = raw == "true"
    else:
        try:
            value = float(raw)
            value = int(value) if value.is_integer() and abs(value) < 2**53 else value
        except ValueError:
            value = raw  # an enum element (or a constant: the runner then says it is unknown)
    op, symbol = match["op"], match["symbol"]
    numeric = isinstance(value, int | float) and not isinstance(value, bool)
    if op == "==":
        return {"symbol": symbol, "equals": value}
    if op == "!=":
        return {"symbol": symbol, "not_equals": value}
    if not numeric:
        return None
    if op == "<":
        return {"symbol": symbol, "below": value}
    if op == ">":
        return {"symbol": symbol, "above": value}
    return {"symbol": symbol, "between": [-_FAR, value] if op == "<=" else [value, _FAR]}


def hit_expects(point: Breakpoint, within: float) -> tuple[list[dict[str, Any]], list[str]]:
    """What breakpoint ``point`` waited for as ``within`` assertions, and comments for the rest.

    ``enter_option`` / ``enter_state`` become "option (in state) active within"; a ``leaf`` the
    option in its state (the format has no leaf predicate); a ``condition`` one ``symbol``
    assertion per ``&&`` clause of the form ``SYMBOL OP VALUE`` (or a bare boolean symbol).
    Leaving an option or state, ``||``, arithmetic and function calls have no assertion: the
    comments say so, and the caller keeps the active states as the starting point.
    """
    where = f"within {within:g} s"
    if point.kind == "enter_option":
        return [{"within": within, "option": point.option}], []
    if point.kind == "enter_state":
        return [{"within": within, "option": point.option, "state": point.state}], []
    if point.kind == "leaf":
        return [{"within": within, "option": point.option, "state": point.state}], [
            f"the breakpoint waited for decision leaf {point.leaf} of {point.option}.{point.state}; a test cannot",
            "assert a decision leaf, so this asserts its state (its coverage report lists the leaves reached)",
        ]
    if point.kind in ("leave_option", "leave_state"):
        target = point.option if point.kind == "leave_option" else f"{point.option}.{point.state}"
        return [], [
            f'the breakpoint waited for leaving {target}; a test cannot assert "stops being active"',
            "(only never/always/eventually of being active): the assertions below are what was active at the hit",
        ]
    condition = " ".join((point.condition or "").split())
    clauses = condition.split("&&")
    predicates = [_comparison(c) for c in clauses] if "||" not in condition and "(" not in condition else [None]
    if not condition or any(p is None for p in predicates):
        return [], [
            f"the breakpoint waited for `{condition}`; only comparisons of a symbol with a value",
            "(joined by &&) become assertions, so the assertions below are what was active at the hit",
        ]
    comments = []
    if len(predicates) > 1:
        comments = [
            f"the breakpoint waited for `{condition}`: each clause is asserted {where} on its own;",
            "a test cannot say that they hold in the same tick",
        ]
    return [{"within": within, **p} for p in predicates if p is not None], comments


def draft_test(
    *,
    name: str,
    robot: str,
    tests_folder: Path,
    example_path: Path,
    world: str | None,
    options: Mapping[str, Any],
    seed: int,
    setup: Mapping[str, Any] | None,
    force: tuple[str, str, Mapping[str, Any]] | None,
    overrides: Mapping[str, Any],
    active: Sequence[tuple[str, str]],
    behaviors: Sequence[str],
    duration: float = 5.0,
    hit: tuple[Breakpoint, str, int, int] | None = None,
) -> str:
    """The text of a test file (see the module docstring); it parses as a suite (checked).

    Args:
        name: the test's name.
        robot: the robot the tester drove.
        tests_folder: where the file will be (paths in it are relative to this folder).
        example_path: the path the studio serves (example folder, behavior folder or agents file).
        world: the world plug-in named with ``--world`` (None: the folder's own).
        options: the plug-in's options (``robots``...).
        seed: the session's seed.
        setup: the world's situation as setup keys (None: the world cannot say).
        force: ``(kind, name, params)`` forced as root, params with enum values as element names.
        overrides: input symbol -> value (enums as element names).
        active: ``(option, state)`` pairs that were active, in path order.
        behaviors: basic behaviors that were called.
        duration: seconds the test runs.
        hit: ``(breakpoint, robot name, seq, t in ms)`` of a breakpoint hit the draft reproduces
            (``setup`` is then the scene at that tick); its assertions replace ``active`` and
            ``behaviors`` when the breakpoint can be expressed (:func:`hit_expects`).

    Raises:
        DraftError: a bad name or value.
    """
    if not name.strip():
        raise DraftError("the test needs a name")
    if not (0 < duration <= 3600):
        raise DraftError(f"duration must be in (0, 3600] s, got {duration!r}")
    path = Path(os.path.relpath(example_path, tests_folder)).as_posix()
    hit_blocks: list[dict[str, Any]] = []
    notes: list[str] = []
    if hit is None:
        lines = [f"# Saved from the studio's tester: {name}. Edit the assertions to say what must happen"]
    else:
        point, hit_robot, seq, t = hit
        hit_blocks, notes = hit_expects(point, float(duration))
        lines = [
            f"# Saved from breakpoint `{point.describe()}` that hit on {hit_robot} after tick {seq}"
            f" (t = {t / 1000:g} s): {name}.",
            "# The setup is the world at that tick (the engine starts afresh there). Edit the assertions",
        ]
    lines += [
        "# (docs/tests.md); run it with `xabsl test` on this file.",
        *(f"# {note}" for note in notes),
        "",
        "[suite]",
        f"path = {toml_value(path)}",
    ]
    if world is not None:
        lines.append(f"world = {toml_value(world)}")
    if options:
        lines.append(f"options = {toml_value(dict(options))}")
    lines += [f"seed = {int(seed)}", f"robot = {toml_value(robot)}", ""]
    lines += ["[[test]]", f"name = {toml_value(name.strip())}", f"duration = {toml_value(float(duration))}"]
    if setup:
        lines.append(f"setup = {toml_value(dict(setup))}")
    else:
        lines.append("# this world offers no setup from its scene: the test starts from the world's own start")
    if force is not None:
        kind, target, params = force
        lines.append(f"force = {toml_value({kind: target, 'params': dict(params)})}")
    if overrides:
        lines.append(f"inputs = [{{ t = 0, set = {toml_value(dict(overrides))} }}]")
    expects = [
        "[[test.expect]]\n" + "\n".join(f"{_key(k)} = {toml_value(v)}" for k, v in block.items())
        for block in hit_blocks
    ]
    if hit_blocks:
        active, behaviors = [], []  # the hit says what happened
    for option, state in active:
        expects.append(
            f"[[test.expect]]\nwithin = {toml_value(float(duration))}\n"
            f"option = {toml_value(option)}\nstate = {toml_value(state)}"
        )
    for behavior in dict.fromkeys(behaviors):
        expects.append(f"[[test.expect]]\nwithin = {toml_value(float(duration))}\nbehavior = {toml_value(behavior)}")
    if not expects:
        expects.append('[[test.expect]]\nnever = true\nsymbol = "CHANGE.ME"\nequals = 0')
    lines = [_comment(line) if line.startswith("#") else line for line in lines]
    text = "\n".join(lines) + "\n\n" + "\n\n".join(expects) + "\n"
    # What we write must be a valid suite of exactly this one test, and checking it reads no file.
    suite = parse_suite(text, tests_folder / draft_file_name(name), read_files=False)
    if [case.name for case in suite.cases] != [name.strip()]:
        raise DraftError(f"the draft of {name!r} is not one test of that name")
    return text
