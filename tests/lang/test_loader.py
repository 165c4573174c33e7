"""The include closure resolves paths as ``os.path.realpath`` does: one file is read once however
it is reached (symlinked folders and files, ``..`` after a symlink), with folders resolved once."""

from __future__ import annotations

import os
from pathlib import Path

from xabsl_studio.engine.lang import compile_file

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
