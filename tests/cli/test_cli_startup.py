"""``xabsl`` start-up: the top-level parser imports no compiler, engine or server, and finds the
subcommands of other layers through the entry points exactly as ``importlib.metadata`` does."""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from importlib.metadata import entry_points as metadata_entry_points
from pathlib import Path

import pytest

from xabsl_studio.engine.cli import COMMAND_GROUP, ENGINE_COMMANDS, build_parser, entry_points, load_entry_point, main

ROOT = Path(__file__).resolve().parents[2]


def test_entry_points_are_those_importlib_metadata_finds() -> None:
    expected = sorted((e.name, e.value) for e in metadata_entry_points(group=COMMAND_GROUP))
    assert expected, "the package is not installed: no xabsl.commands entry points"
    assert sorted(entry_points(COMMAND_GROUP)) == expected


def test_entry_points_first_distribution_on_the_path_wins(tmp_path: Path) -> None:
    for folder, value in (("a", "first.module:register"), ("b", "second.module:register")):
        info = tmp_path / folder / "demo_dist-1.0.dist-info"
        info.mkdir(parents=True)
        (info / "entry_points.txt").write_text(f"[other]\nx = y:z\n\n[{COMMAND_GROUP}]\n# comment\ndemo = {value}\n")
    found = entry_points(COMMAND_GROUP, [str(tmp_path / "a"), str(tmp_path / "b"), str(tmp_path / "missing")])
    assert found == [("demo", "first.module:register")]


def test_load_entry_point_resolves_module_and_attribute() -> None:
    assert load_entry_point("os.path:join [extra]") is os.path.join


def test_help_lists_engine_and_entry_point_commands(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exited:
        main(["--help"])
    assert exited.value.code == 0
    out = capsys.readouterr().out
    for command in ("compile", "trace", "plan", "run", "serve"):
        assert f"    {command} " in out


def _modules_after(argv: list[str]) -> set[str]:
    code = (
        "import sys\nfrom xabsl_studio.engine.cli import build_parser\n"
        f"build_parser({argv!r})\nprint(' '.join(sorted(sys.modules)))"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True).stdout
    return set(out.split())


@pytest.mark.parametrize("argv", [["--help"], ["compile", "--help"], ["trace", "x"]])
def test_building_the_parser_imports_nothing_heavy(argv: list[str]) -> None:
    modules = _modules_after(argv)
    heavy = {
        "xabsl_studio.engine.lang",
        "xabsl_studio.engine.ir",
        "xabsl_studio.engine.emit.ic",
        "xabsl_studio.engine.runtime",
        "orjson",
        "importlib.metadata",
    }
    assert modules & heavy == set()
    if argv == ["--help"]:  # not even these (trace imports typing for its annotations)
        assert modules & {"logging", "typing", "shutil", "json"} == set()
    # only the named engine subcommand's module is imported
    commands = {module for module, _ in ENGINE_COMMANDS.values()}
    assert modules & commands == ({ENGINE_COMMANDS[argv[0]][0]} if argv[0] in ENGINE_COMMANDS else set())
    # an engine subcommand needs no entry point: the server's and the language server's modules stay out
    if argv[0] != "--help":
        assert not {"xabsl_studio.server.cli", "xabsl_studio.lsp.cli"} & modules
    else:
        assert {"xabsl_studio.server.cli", "xabsl_studio.lsp.cli"} <= modules


def test_the_command_table_gives_each_module_s_own_help() -> None:
    full = build_parser()  # every subcommand registered by its module
    actions = next(a for a in full._actions if isinstance(a, argparse._SubParsersAction))
    registered = {c.dest: c.help for c in actions._choices_actions}
    assert {name: help_text for name, (_, help_text) in ENGINE_COMMANDS.items()} == {
        name: registered[name] for name in ENGINE_COMMANDS
    }


def test_a_named_subcommand_parses_as_with_the_full_parser() -> None:
    argv = ["compile", "agents.xabsl", "--ic", "out.ic", "--werror"]
    assert vars(build_parser(argv).parse_args(argv)) == vars(build_parser().parse_args(argv))
