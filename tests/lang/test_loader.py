"""The include closure resolves paths as ``os.path.realpath`` does: one file is read once however
it is reached (symlinked folders and files, ``..`` after a symlink), with folders resolved once."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from xabsl_studio.engine.lang import compile_file
from xabsl_studio.engine.lang.loader import display_path

SYMBOLS = 'namespace s("S") {{ float output {name}; }}\n'
OPTION = "option o {{ initial state s {{ action {{ {name} = 1; }} }} }}\n"


def _compile(root: Path, includes: list[str], output: str) -> list[str]:
    # the first include is in the agents file, the others in the option file (one file may not
    # include the same file twice)
    others = "".join(f'include "{i}";\n' for i in includes[1:])
    (root / "o.xabsl").write_text(others + OPTION.format(name=output))
    lines = "".join(f'include "{i}";\n' for i in [*includes[:1], "o.xabsl"])
    (root / "agents.xabsl").write_text(lines + 'agent a("A", o);\n')
    compilation = compile_file(str(root / "agents.xabsl"), base=str(root))
    assert [d.format() for d in compilation.errors] == []
    return compilation.files


def test_a_file_reached_through_a_symlinked_folder_is_read_once(tmp_path: Path) -> None:
    (tmp_path / "real_lib").mkdir()
    (tmp_path / "real_lib" / "s.xabsl").write_text(SYMBOLS.format(name="x"))
    os.symlink(tmp_path / "real_lib", tmp_path / "lib")
    files = _compile(tmp_path, ["lib/s.xabsl", "real_lib/s.xabsl"], "x")
    assert files.count("real_lib/s.xabsl") == 1 and len(files) == 3


def test_a_symlinked_file_is_its_target(tmp_path: Path) -> None:
    (tmp_path / "s.xabsl").write_text(SYMBOLS.format(name="x"))
    os.symlink(tmp_path / "s.xabsl", tmp_path / "alias.xabsl")
    files = _compile(tmp_path, ["alias.xabsl", "s.xabsl"], "x")
    assert files.count("s.xabsl") == 1 and "alias.xabsl" not in files


def test_dot_dot_after_a_symlink_leaves_the_link_s_target(tmp_path: Path) -> None:
    # link -> deep/dir, so link/../s.xabsl is deep/s.xabsl (not ./s.xabsl, as a lexical join says)
    (tmp_path / "deep" / "dir").mkdir(parents=True)
    (tmp_path / "deep" / "s.xabsl").write_text(SYMBOLS.format(name="from_deep"))
    (tmp_path / "s.xabsl").write_text(SYMBOLS.format(name="from_top"))
    os.symlink(tmp_path / "deep" / "dir", tmp_path / "link")
    files = _compile(tmp_path, ["link/../s.xabsl"], "from_deep")
    assert "deep/s.xabsl" in files and "s.xabsl" not in files


def test_a_file_outside_the_base_folder_is_named_relative_to_it(tmp_path: Path) -> None:
    """Files beside the named folder printed as absolute paths (issue 23): `../common/s.xabsl`."""
    team = tmp_path / "team"
    (tmp_path / "common").mkdir()
    team.mkdir()
    (tmp_path / "common" / "s.xabsl").write_text(SYMBOLS.format(name="x") + "namespace")  # a syntax error
    files = _compile_any(team, ["../common/s.xabsl"], "x")
    assert files.files == ["../common/s.xabsl", "o.xabsl", "agents.xabsl"]
    assert [d.file for d in files.errors] == ["../common/s.xabsl"]
    assert files.errors[0].format().startswith("../common/s.xabsl:")


def test_a_file_that_meets_the_base_folder_only_at_the_root_is_named_absolutely(tmp_path: Path) -> None:
    assert display_path("/usr/share/s.xabsl", str(tmp_path)) == "/usr/share/s.xabsl"
    assert display_path(str(tmp_path / "a" / "s.xabsl"), str(tmp_path / "b")) == "../a/s.xabsl"


def _compile_any(root: Path, includes: list[str], output: str) -> Any:
    others = "".join(f'include "{i}";\n' for i in includes[1:])
    (root / "o.xabsl").write_text(others + OPTION.format(name=output))
    lines = "".join(f'include "{i}";\n' for i in [*includes[:1], "o.xabsl"])
    (root / "agents.xabsl").write_text(lines + 'agent a("A", o);\n')
    return compile_file(str(root / "agents.xabsl"), base=str(root))
