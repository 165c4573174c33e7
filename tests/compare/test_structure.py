"""Known edits of a behavior set written for these tests, each reported once, in the right place."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.compare.conftest import FILES, compile_set, edited
from xabsl_studio.engine.compare import Change, diff_programs
from xabsl_studio.engine.ir.model import Program

PATROL = "options/patrol.xabsl"


def line(file: str, snippet: str, files: dict[str, str] | None = None) -> str:
    """``file:line`` of the one line of ``file`` that contains ``snippet``."""
    lines = (files or FILES)[file].splitlines()
    found = [i + 1 for i, text in enumerate(lines) if snippet in text]
    assert len(found) == 1, (file, snippet, found)
    return f"{file}:{found[0]}"


def rows(changes: list[Change]) -> list[tuple[object, ...]]:
    """What a reader sees of each change: kind, change, where, details, both places."""
    return [
        (
            c.kind,
            c.change,
            c.where,
            tuple(c.path) if c.path is not None else None,
            tuple((d.field, d.old, d.new) for d in c.details),
            str(c.old) if c.old else None,
            str(c.new) if c.new else None,
        )
        for c in changes
    ]


def diff(tmp_path: Path, original: Program, files: dict[str, str]) -> list[tuple[object, ...]]:
    return rows(diff_programs(original, compile_set(tmp_path / "new", files)).changes)


def test_the_same_set_has_no_changes(tmp_path: Path, original: Program) -> None:
    assert diff(tmp_path, original, FILES) == []


def test_layout_comments_and_state_order_are_no_changes(tmp_path: Path, original: Program) -> None:
    text = FILES[PATROL]
    # move the state `chase` behind `wait`, re-indent a condition, add a comment
    start, end = text.index("  state chase {"), text.index("  state wait {")
    moved = text[:start] + text[end:].rstrip()[:-1] + text[start:end] + "}\n"
    moved = moved.replace("else if (battery < 10)", "else if ( battery<10 )  // low").replace(
        "(state_time > 4000)\n        goto to_post_b", "(state_time>4000) goto to_post_b"
    )
    assert moved != text
    assert diff(tmp_path, original, {**FILES, PATROL: moved}) == []


def test_a_renamed_state_is_one_rename(tmp_path: Path, original: Program) -> None:
    files = {**FILES, PATROL: FILES[PATROL].replace("to_post_b", "to_post_c")}
    assert diff(tmp_path, original, files) == [
        (
            "state",
            "renamed",
            "patrol/to_post_c",
            None,
            (("name", "to_post_b", "to_post_c"),),
            line(PATROL, "state to_post_b"),
            line(PATROL, "state to_post_c", files),
        )
    ]


def test_a_renamed_state_with_another_body_is_removed_and_added(tmp_path: Path, original: Program) -> None:
    files = {
        **FILES,
        PATROL: FILES[PATROL]
        .replace("to_post_b", "to_post_c")
        .replace("walk(speed = @speed, direction = 180);", "walk(speed = @speed, direction = 90);"),
    }
    assert diff(tmp_path, original, files) == [
        (
            "transition",
            "changed",
            "patrol/to_post_a",
            ("state_time > 4000",),
            (("target", "to_post_b", "to_post_c"),),
            line(PATROL, "goto to_post_b"),
            line(PATROL, "goto to_post_c", files),
        ),
        ("state", "added", "patrol/to_post_c", None, (), None, line(PATROL, "state to_post_c", files)),
        ("state", "removed", "patrol/to_post_b", None, (), line(PATROL, "state to_post_b"), None),
    ]


def test_a_new_transition_is_one_added_transition(tmp_path: Path, original: Program) -> None:
    files = edited(
        options__patrol_dot_xabsl=(
            "        goto wait;\n",
            "        goto wait;\n      else if (ball.distance > 5000)\n        goto to_post_b;\n",
        )
    )
    changes = diff_programs(original, compile_set(tmp_path / "new", files)).changes
    assert rows(changes) == [
        (
            "transition",
            "added",
            "patrol/to_post_a",
            ("ball.distance > 5000",),
            (("target", None, "to_post_b"),),
            None,
            f"{PATROL}:{int(line(PATROL, 'ball.distance > 5000', files).rsplit(':', 1)[1]) + 1}",  # its goto
        )
    ]
    # the leaf id the state machine's edge has: after the common leaf and the two before it
    assert [(r.state, r.leaf) for r in changes[0].new_leaves] == [(0, 3)]


def test_a_changed_target_is_one_changed_transition(tmp_path: Path, original: Program) -> None:
    files = edited(options__patrol_dot_xabsl=("        goto wait;\n", "        goto to_post_b;\n"))
    assert diff(tmp_path, original, files) == [
        (
            "transition",
            "changed",
            "patrol/to_post_a",
            ("battery < 10",),
            (("target", "wait", "to_post_b"),),
            line(PATROL, "goto wait"),
            line(PATROL, "goto wait"),  # same line: only the target changed
        )
    ]


def test_a_changed_condition_is_one_change_at_its_if(tmp_path: Path, original: Program) -> None:
    files = edited(options__patrol_dot_xabsl=("battery < 10", "battery < 20"))
    assert diff(tmp_path, original, files) == [
        (
            "condition",
            "changed",
            "patrol/to_post_a",
            ("battery < 20",),
            (("condition", "battery < 10", "battery < 20"),),
            line(PATROL, "battery < 10"),
            line(PATROL, "battery < 10"),
        )
    ]


def test_a_changed_common_condition_is_reported_once_not_per_state(tmp_path: Path, original: Program) -> None:
    files = edited(options__patrol_dot_xabsl=("ball.distance < near)", "ball.distance < near + 100)"))
    changes = diff_programs(original, compile_set(tmp_path / "new", files)).changes
    assert rows(changes) == [
        (
            "condition",
            "changed",
            "patrol/(common)",
            ("ball.seen && ball.distance < near + 100",),
            (("condition", "ball.seen && ball.distance < near", "ball.seen && ball.distance < near + 100"),),
            line(PATROL, "if (ball.seen"),
            line(PATROL, "if (ball.seen"),
        )
    ]
    # its edge is drawn in every one of the four states
    assert sorted(r.state for r in changes[0].new_leaves) == [0, 1, 2, 3]


def test_a_condition_above_two_leaves_is_one_change(tmp_path: Path) -> None:
    nested = FILES[PATROL].replace(
        "      else if (battery < 10)\n        goto wait;\n",
        "      else if (battery < 10) {\n        if (ball.seen) goto chase; else goto wait;\n      }\n",
    )
    before = compile_set(tmp_path / "old", {**FILES, PATROL: nested})
    files = {**FILES, PATROL: nested.replace("battery < 10", "battery < 5")}
    changes = rows(diff_programs(before, compile_set(tmp_path / "new", files)).changes)
    assert changes == [
        (
            "condition",
            "changed",
            "patrol/to_post_a",
            ("battery < 5",),
            (("condition", "battery < 10", "battery < 5"),),
            line(PATROL, "battery < 10", {PATROL: nested}),
            line(PATROL, "battery < 5", files),
        )
    ]


def test_a_removed_option_is_one_removal_and_its_call_one_action(tmp_path: Path, original: Program) -> None:
    files = edited(
        options__rest_dot_xabsl=None,
        agents_dot_xabsl=('include "options/rest.xabsl";\n', ""),
        options__patrol_dot_xabsl=("rest(seconds = 5);", "stand();"),
    )
    assert diff(tmp_path, original, files) == [
        ("option", "removed", "rest", None, (), line("options/rest.xabsl", "option rest"), None),
        (
            "action",
            "removed",
            "patrol/wait",
            None,
            (("action", "rest(seconds = 5)", None),),
            line(PATROL, "rest(seconds = 5)"),
            None,
        ),
        ("action", "added", "patrol/wait", None, (("action", None, "stand()"),), None, line(PATROL, "stand();", files)),
    ]


def test_a_renamed_option_is_one_rename_and_its_callers_are_unchanged(tmp_path: Path, original: Program) -> None:
    files = edited(
        options__rest_dot_xabsl=None,
        agents_dot_xabsl=('include "options/rest.xabsl";', 'include "options/pause.xabsl";'),
        options__patrol_dot_xabsl=("rest(seconds = 5);", "pause(seconds = 5);"),
    )
    files["options/pause.xabsl"] = FILES["options/rest.xabsl"].replace("option rest", "option pause")
    result = diff_programs(original, compile_set(tmp_path / "new", files))
    assert rows(result.changes) == [
        (
            "option",
            "renamed",
            "pause",
            None,
            (("name", "rest", "pause"), ("file", "options/rest.xabsl", "options/pause.xabsl")),
            line("options/rest.xabsl", "option rest"),
            line("options/pause.xabsl", "option pause", files),
        ),
    ]
    assert result.option_renames == {"rest": "pause"}


def test_a_changed_call_argument_is_one_changed_action(tmp_path: Path, original: Program) -> None:
    # XABSL parameters have no declared default: a caller's value is what a parameter gets
    files = edited(options__play_dot_xabsl=("patrol(speed = 200)", "patrol(speed = 250)"))
    assert diff(tmp_path, original, files) == [
        (
            "action",
            "changed",
            "play/patrolling",
            None,
            (("argument speed", "200", "250"),),
            line("options/play.xabsl", "patrol(speed"),
            line("options/play.xabsl", "patrol(speed"),
        )
    ]


def test_a_changed_parameter_declaration_is_one_changed_parameter(tmp_path: Path, original: Program) -> None:
    files = edited(options__rest_dot_xabsl=('float @seconds [0..60] "s";', 'float @seconds [0..120] "min";'))
    assert diff(tmp_path, original, files) == [
        (
            "parameter",
            "changed",
            "rest",
            None,
            (("range", "0..60", "0..120"), ("unit", "s", "min")),
            line("options/rest.xabsl", "@seconds ["),
            line("options/rest.xabsl", "@seconds ["),
        )
    ]


def test_an_added_parameter(tmp_path: Path, original: Program) -> None:
    files = edited(
        options__rest_dot_xabsl=('float @seconds [0..60] "s";\n', 'float @seconds [0..60] "s";\n  bool @sit;\n')
    )
    assert diff(tmp_path, original, files) == [
        ("parameter", "added", "rest", None, (), None, line("options/rest.xabsl", "@sit", files)),
    ]


def test_a_new_symbol_is_one_added_input(tmp_path: Path, original: Program) -> None:
    files = edited(
        symbols_dot_xabsl=("  bool input ball.seen;\n", '  bool input ball.seen;\n  float input ball.angle "deg";\n')
    )
    assert diff(tmp_path, original, files) == [
        ("input", "added", "ball.angle", None, (), None, line("symbols.xabsl", "ball.angle", files)),
    ]


def test_a_changed_constant_is_reported_at_the_constant_only(tmp_path: Path, original: Program) -> None:
    files = edited(symbols_dot_xabsl=("near = 300", "near = 350"))
    assert diff(tmp_path, original, files) == [
        (
            "constant",
            "changed",
            "near",
            None,
            (("value", "300", "350"),),
            line("symbols.xabsl", "const near"),
            line("symbols.xabsl", "const near"),
        )
    ]


def test_symbols_enums_behaviors_and_agents(tmp_path: Path, original: Program) -> None:
    files = edited(
        symbols_dot_xabsl=("enum mode { idle, walk, kick };", "enum mode { idle, walk, kick, dance };"),
        behaviors_dot_xabsl=("  behavior stand { }\n", "  behavior stand { }\n  behavior sit { }\n"),
        agents_dot_xabsl=('agent patroller("Patroller", play);', 'agent patroller("Guard", play);'),
    )
    assert diff(tmp_path, original, files) == [
        (
            "agent",
            "changed",
            "patroller",
            None,
            (("title", "Patroller", "Guard"),),
            *(line("agents.xabsl", "agent "),) * 2,
        ),
        ("enum", "changed", "mode", None, (("elements", None, "dance"),), *(line("symbols.xabsl", "enum mode {"),) * 2),
        ("behavior", "added", "sit", None, (), None, line("behaviors.xabsl", "behavior sit", files)),
    ]


def test_a_new_state_is_listed_once_with_the_transition_into_it(tmp_path: Path, original: Program) -> None:
    files = edited(
        options__patrol_dot_xabsl=(
            "  state wait {",
            "  state dock {\n    action { stand(); }\n  }\n  state wait {",
        )
    )
    files[PATROL] = files[PATROL].replace("        goto wait;\n", "        goto dock;\n")
    assert diff(tmp_path, original, files) == [
        (
            "transition",
            "changed",
            "patrol/to_post_a",
            ("battery < 10",),
            (("target", "wait", "dock"),),
            line(PATROL, "goto wait"),
            line(PATROL, "goto dock", files),
        ),
        ("state", "added", "patrol/dock", None, (), None, line(PATROL, "state dock", files)),
    ]


@pytest.mark.parametrize(
    ("edit", "expected"),
    [
        (("initial state to_post_a", "state to_post_a"), None),
        (("target state done", "state done"), ("state", "changed", "rest/done", (("target", "true", "false"),))),
    ],
)
def test_state_flags(
    tmp_path: Path, original: Program, edit: tuple[str, str], expected: tuple[object, ...] | None
) -> None:
    if expected is None:  # the initial state moves to the option's first state
        files = edited(options__rest_dot_xabsl=("initial state stand_still", "state stand_still"))
        files["options/rest.xabsl"] = files["options/rest.xabsl"].replace(
            "target state done", "initial target state done"
        )
        got = diff(tmp_path, original, files)
        assert [(r[0], r[1], r[2], r[4]) for r in got] == [
            ("option", "changed", "rest", (("initial state", "stand_still", "done"),))
        ]
        return
    files = edited(options__rest_dot_xabsl=edit)
    got = diff(tmp_path, original, files)
    assert [(r[0], r[1], r[2], r[4]) for r in got] == [expected]


def test_swapped_branches_are_one_change_of_the_decision_order(tmp_path: Path, original: Program) -> None:
    first = "      else if (state_time > 4000)\n        goto to_post_b;\n"
    second = "      else if (battery < 10)\n        goto wait;\n"
    files = edited(options__patrol_dot_xabsl=(first + second, second + first))
    assert diff(tmp_path, original, files) == [
        (
            "decision",
            "changed",
            "patrol/to_post_a",
            None,
            (("order", "state_time > 4000 | battery < 10 | else", "battery < 10 | state_time > 4000 | else"),),
            line(PATROL, "goto to_post_b"),
            line(PATROL, "goto wait", files),
        )
    ]


def test_swapped_action_items_are_one_change_of_their_order(tmp_path: Path, original: Program) -> None:
    files = edited(
        options__patrol_dot_xabsl=(
            "      laps = laps + 1;\n      rest(seconds = 5);",
            "      rest(seconds = 5);\n      laps = laps + 1;",
        )
    )
    assert diff(tmp_path, original, files) == [
        (
            "action",
            "changed",
            "patrol/wait",
            None,
            (("order", "laps = ..., rest()", "rest(), laps = ..."),),
            line(PATROL, "laps = laps"),
            line(PATROL, "rest(seconds", files),
        )
    ]
