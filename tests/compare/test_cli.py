"""``xabsl diff`` end to end: folders, agents files, git revisions, --json, --html, refusals."""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import orjson
import pytest

from tests.compare.conftest import FILES, edited, write_set
from xabsl_studio.engine.cli import main


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(["diff", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def _git(repo: Path, *args: str) -> None:
    subprocess.run(["git", *args], cwd=repo, check=True, capture_output=True)


@pytest.fixture
def sets(tmp_path: Path) -> tuple[Path, Path]:
    old = write_set(tmp_path / "old").parent
    new = write_set(tmp_path / "new", edited(options__patrol_dot_xabsl=("battery < 10", "battery < 20"))).parent
    return old, new


def test_folders_print_one_line_per_change(sets: tuple[Path, Path], capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, str(sets[0]), str(sets[1]))
    assert code == 0
    assert out.splitlines()[1:] == [
        "1 change: 0 added, 0 removed, 0 renamed, 1 changed",
        "~ changed condition patrol/to_post_a: condition: battery < 10 -> battery < 20  "
        "(options/patrol.xabsl:13 -> options/patrol.xabsl:13)",
    ]


def test_agents_files_and_json(sets: tuple[Path, Path], capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, str(sets[0] / "agents.xabsl"), str(sets[1] / "agents.xabsl"), "--json")
    assert code == 0
    document = orjson.loads(out)
    assert document["format"] == "xabsl-diff/1"
    assert document["counts"] == {"added": 0, "removed": 0, "renamed": 0, "changed": 1}
    assert document["changes"] == [
        {
            "kind": "condition",
            "change": "changed",
            "name": "battery < 20",
            "option": "patrol",
            "state": "to_post_a",
            "path": ["battery < 20"],
            "details": [{"field": "condition", "old": "battery < 10", "new": "battery < 20"}],
            # the place of its `if`
            "old": {"file": "options/patrol.xabsl", "line": 13, "col": 12},
            "new": {"file": "options/patrol.xabsl", "line": 13, "col": 12},
        }
    ]
    assert FILES["options/patrol.xabsl"].splitlines()[12].index("if (battery") + 1 == 12
    assert document["old"]["title"] == document["new"]["title"] == "Patrol"


def test_git_revisions(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    repo = tmp_path / "repo"
    write_set(repo / "team")
    _git(repo, "init", "-q")
    _git(repo, "add", ".")
    _git(repo, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "first")
    write_set(
        repo / "team",
        edited(symbols_dot_xabsl=("float internal laps;", "float internal laps;\n  bool internal tired;")),
    )
    cwd = Path.cwd()
    os.chdir(repo)
    try:
        full = run(capsys, "git:HEAD:team", "team")
        alone = run(capsys, "git:HEAD", "team")  # the other side's path at HEAD
        agents = run(capsys, "git:HEAD:team/agents.xabsl", "team/agents.xabsl")
        same = run(capsys, "git:HEAD:team", "git:HEAD")
        unknown = run(capsys, "git:nosuchrev:team", "team")
    finally:
        os.chdir(cwd)
    for code, out, _ in (full, alone, agents):
        assert code == 0
        assert out.splitlines()[2:] == ["+ added internal: tired  (symbols.xabsl:9)"]
    assert same[0] == 0 and same[1].splitlines()[1].startswith("0 changes")
    assert unknown[0] == 2 and "unknown revision" in unknown[2]


def test_refusals(tmp_path: Path, sets: tuple[Path, Path], capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(capsys, str(tmp_path / "nowhere"), str(sets[1]))
    assert code == 2 and err == f"xabsl diff: no such behavior folder or agents file: {tmp_path / 'nowhere'}\n"
    (tmp_path / "empty").mkdir()
    code, _, err = run(capsys, str(tmp_path / "empty"), str(sets[1]))
    assert code == 2 and "no agents.xabsl in" in err
    broken = write_set(tmp_path / "broken", {**FILES, "options/play.xabsl": "option play {"}).parent
    code, _, err = run(capsys, str(broken), str(sets[1]))
    assert code == 1 and f"{broken}: options/play.xabsl:1:" in err and " has 3 errors" in err
    code, _, err = run(capsys, str(sets[0]), str(sets[1]), "--html", str(tmp_path))
    assert code == 2 and "--html names a folder" in err


def test_html_marks_the_changes_in_the_drawings(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    old = write_set(tmp_path / "old").parent
    files = edited(
        options__rest_dot_xabsl=None,
        agents_dot_xabsl=('include "options/rest.xabsl";\n', ""),
        options__patrol_dot_xabsl=("rest(seconds = 5);", "stand();"),
    )
    files["options/patrol.xabsl"] = files["options/patrol.xabsl"].replace("battery < 10", "battery < 20")
    new = write_set(tmp_path / "new", files).parent
    out = tmp_path / "diff.html"
    code, text, _ = run(capsys, str(old), str(new), "--html", str(out))
    assert code == 0 and text.splitlines()[-1] == f"wrote {out}"
    page = out.read_text()
    # the option graph: patrol changed, the removed option drawn dashed with its removed call
    assert re.search(r'<g id="option_0" class="node changed">\s*<title>o:patrol</title>', page)
    assert re.search(r'<g id="removed_option_\d+" class="node removed">\s*<title>o:rest</title>', page)
    assert re.search(r'<g id="removed_call_\d+" class="edge removed">\s*<title>o:patrol&#45;&gt;o:rest</title>', page)
    # patrol's state machine: the changed condition's edge (state 0, leaf 2: to_post_a -> wait)
    assert re.search(r'<g id="leaf_0_2" class="edge changed">\s*<title>s:to_post_a&#45;&gt;s:wait</title>', page)
    assert '<g id="state_3" class="node changed">' in page  # wait: its action changed
    assert "<script" not in page
