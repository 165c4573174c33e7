"""Save as test: a behavior test file that reproduces what the studio's tester set up, for the user to edit.

:func:`draft_test` writes the TOML of one suite with one test: the world plug-in and its options
(``path``, ``world``, ``options``), the session's seed, the world's situation when the world can
describe it as a setup (a plug-in's optional ``setup_from_scene(scene, status)``; the soccer
world gives robots, ball, game state), the forced option or basic behavior with its parameters,
the input overrides (from t = 0), and one ``eventually`` assertion per option state and basic
behavior that was active, as a starting point. The studio serves it as ``POST /api/tests/draft``
(docs/tests.md "Save as test"); ``save`` writes it into the example's ``tests/`` folder.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from examples.testing.spec import SUFFIX, parse_suite

__all__ = ["DraftError", "draft_file_name", "draft_test", "toml_value"]


class DraftError(ValueError):
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
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'
    if isinstance(value, list | tuple):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, Mapping):
        return "{ " + ", ".join(f"{_key(k)} = {toml_value(v)}" for k, v in value.items()) + " }" if value else "{}"
    raise DraftError(f"cannot write {value!r} in a test file")


def _key(key: str) -> str:
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else toml_value(key)


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

    Raises:
        DraftError: a bad name or value.
    """
    if not name.strip():
        raise DraftError("the test needs a name")
    if not (0 < duration <= 3600):
        raise DraftError(f"duration must be in (0, 3600] s, got {duration!r}")
    path = Path(os.path.relpath(example_path, tests_folder)).as_posix()
    lines = [
        f"# Saved from the studio's tester: {name}. Edit the assertions to say what must happen",
        "# (docs/tests.md); run it with `xabsl test` on this file.",
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
    expects = []
    for option, state in active:
        expects.append(
            f"[[test.expect]]\nwithin = {toml_value(float(duration))}\n"
            f"option = {toml_value(option)}\nstate = {toml_value(state)}"
        )
    for behavior in dict.fromkeys(behaviors):
        expects.append(f"[[test.expect]]\nwithin = {toml_value(float(duration))}\nbehavior = {toml_value(behavior)}")
    if not expects:
        expects.append('[[test.expect]]\nnever = true\nsymbol = "CHANGE.ME"\nequals = 0')
    text = "\n".join(lines) + "\n\n" + "\n\n".join(expects) + "\n"
    parse_suite(text, tests_folder / draft_file_name(name))  # what we write must be a valid suite
    return text
