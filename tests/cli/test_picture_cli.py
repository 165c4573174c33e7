"""``xabsl picture``: option graphs, subtrees, state machines, recorded activation paths as SVG, PNG, PDF.

Every file written is opened by a program that is not ours: SVG by ``xml.etree``, PNG by its
header and chunks, PDF by poppler's ``pdftoppm`` (rendered to a PNG of a size that follows).
"""

from __future__ import annotations

import shutil
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from tests.profile.conftest import record
from xabsl_studio.engine.cli import main

REPO = Path(__file__).resolve().parents[2]
SOCCER = REPO / "examples" / "soccer" / "behavior" / "agents.xabsl"
DEMO = REPO / "examples" / "demo"
SVG = "{http://www.w3.org/2000/svg}"


def picture(*argv: str) -> subprocess.CompletedProcess[str]:
    """Run ``xabsl picture`` as its own process (the command a user types)."""
    return subprocess.run(
        [sys.executable, "-m", "xabsl_studio.engine.cli", "picture", *argv],
        capture_output=True,
        text=True,
        timeout=120,
        env={"PYTHONPATH": str(REPO), "PATH": "/usr/bin:/bin:/usr/local/bin"},
        check=False,
    )


def svg_ids(path: Path) -> dict[str, ET.Element]:
    root = ET.parse(path).getroot()
    assert root.tag == f"{SVG}svg"
    return {e.get("id", ""): e for e in root.iter() if e.get("id")}


def png_size(data: bytes) -> tuple[int, int]:
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "PNG signature"
    length, kind = struct.unpack(">I4s", data[8:16])
    assert kind == b"IHDR" and length == 13
    width, height = struct.unpack(">II", data[16:24])
    assert data.endswith(b"IEND\xaeB`\x82"), "a whole PNG, up to its IEND chunk"
    return width, height


def pdf_pages_render(path: Path, tmp_path: Path) -> tuple[int, int]:
    """Render page 1 with poppler's pdftoppm; the size of the PNG it made."""
    pdftoppm = shutil.which("pdftoppm")
    assert pdftoppm is not None, "poppler-utils (make test-deps installs it)"
    out = tmp_path / "page"
    subprocess.run([pdftoppm, "-png", "-r", "72", "-f", "1", "-l", "1", str(path), str(out)], check=True, timeout=60)
    (page,) = tmp_path.glob("page*.png")
    return png_size(page.read_bytes())


@pytest.mark.parametrize("fmt", ["svg", "png", "pdf"])
def test_the_whole_option_graph_in_each_format(tmp_path: Path, fmt: str) -> None:
    out = tmp_path / f"graph.{fmt}"
    done = picture(str(SOCCER), "-o", str(out))
    assert done.returncode == 0, done.stdout + done.stderr
    assert f"as {fmt.upper()} in {out}" in done.stdout
    if fmt == "svg":
        ids = svg_ids(out)
        assert sum(1 for i in ids if i.startswith("option_")) >= 10, "the soccer set's options"
        assert any(i.startswith("call_") for i in ids)
    elif fmt == "png":
        width, height = png_size(out.read_bytes())
        assert width > 400 and height > 200
    else:
        assert out.read_bytes().startswith(b"%PDF-")
        width, height = pdf_pages_render(out, tmp_path)
        assert width > 200 and height > 100


def test_a_subtree_and_a_state_machine(tmp_path: Path) -> None:
    whole, below = tmp_path / "whole.svg", tmp_path / "below.svg"
    assert picture(str(DEMO), "-o", str(whole)).returncode == 0, "a folder with agents.xabsl"
    assert picture(str(DEMO), "--option", "approach_ball", "-o", str(below)).returncode == 0
    options = {i for i in svg_ids(whole) if i.startswith("option_")}
    sub = {i for i in svg_ids(below) if i.startswith("option_")}
    assert sub and sub < options, "below approach_ball: fewer options"
    machine = tmp_path / "machine.pdf"
    done = picture(str(DEMO), "--machine", "approach_ball", "--format", "pdf", "-o", str(machine))
    assert done.returncode == 0 and "the state machine of approach_ball" in done.stdout
    assert pdf_pages_render(machine, tmp_path)[0] > 100
    svg = tmp_path / "machine.svg"
    assert picture(str(DEMO), "--machine", "approach_ball", "-o", str(svg)).returncode == 0
    ids = svg_ids(svg)
    assert "initial" in ids and any(i.startswith("state_") for i in ids) and any(i.startswith("leaf_") for i in ids)
    texts = " ".join(t.text or "" for t in ET.parse(svg).getroot().iter(f"{SVG}text"))
    assert "option approach_ball" in texts, "the title"


def test_the_activation_path_at_a_tick_of_a_recording(tmp_path: Path) -> None:
    recording = record(tmp_path / "run.mcap")
    # tick 2: cycle in a (calling sub, in y); tick 4: cycle in b (calling stand)
    at2, at4, machine = tmp_path / "t2.svg", tmp_path / "t4.svg", tmp_path / "m.svg"
    for tick, out in ((2, at2), (4, at4)):
        done = picture("--recording", str(recording), "--tick", str(tick), "-o", str(out))
        assert done.returncode == 0, done.stdout + done.stderr
        assert f"activation path at tick {tick}" in done.stdout
    root = ET.parse(at2).getroot()
    texts = [t.text or "" for t in root.iter(f"{SVG}text")]
    assert "▸ a" in texts and "▸ y" in texts, "each option's active state under its name"
    assert any("robot1 at tick 2" in t for t in texts), "the title"
    filled = _filled(at2)
    assert filled["cycle"] and filled["sub"] and filled["stand"], filled
    later = _filled(at4)
    assert later["cycle"] and not later["sub"], "at tick 4 sub did not run"
    # the state machine of cycle at tick 4: state b is filled, the edge a -> b that fired is thick
    done = picture("--recording", str(recording), "--tick", "4", "--machine", "cycle", "-o", str(machine))
    assert done.returncode == 0, done.stdout + done.stderr
    ids = svg_ids(machine)
    states = {g.findtext(f"{SVG}title"): g for i, g in ids.items() if i.startswith("state_")}
    fill = _fill(states["s:b"])
    assert fill == "#ffe08a" and _fill(states["s:a"]) != fill
    fired = [g for i, g in ids.items() if i.startswith("leaf_")]
    widths = {g.findtext(f"{SVG}title"): [p.get("stroke-width") for p in g.iter(f"{SVG}path")] for g in fired}
    assert widths["s:a->s:b"] == ["2.6"] and widths["s:b->s:a"] != ["2.6"], widths


def _fill(group: ET.Element) -> str | None:
    for shape in group.iter():
        if shape.tag in (f"{SVG}polygon", f"{SVG}path", f"{SVG}ellipse") and shape.get("fill") not in (None, "none"):
            return shape.get("fill")
    return None


def _filled(path: Path) -> dict[str, bool]:
    """Option and behavior names -> drawn as having run."""
    found = {}
    for group in ET.parse(path).getroot().iter(f"{SVG}g"):
        title = group.findtext(f"{SVG}title") or ""
        if group.get("class") == "node" and title[:2] in ("o:", "b:"):
            found[title[2:]] = _fill(group) == "#ffe08a"
    return found


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--option", "nope"], "no option 'nope' in this behavior"),
        (["--machine", "nope"], "no option 'nope' in this behavior"),
        (["--agent", "nobody"], "no agent 'nobody' in this behavior"),
        (["--tick", "3"], "--recording and --tick go together"),
        (["--robot", "robot1"], "--robot names a robot of --recording"),
    ],
)
def test_bad_arguments_say_what_is_wrong_and_write_nothing(tmp_path: Path, argv: list[str], message: str) -> None:
    out = tmp_path / "x.png"
    done = picture(str(DEMO), *argv, "-o", str(out))
    assert done.returncode == 2 and message in done.stderr, done.stderr
    assert not out.exists()


def test_an_unknown_suffix_a_missing_tick_and_a_broken_behavior(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["picture", str(DEMO), "-o", str(tmp_path / "x.gif")]) == 2
    assert "say --format svg, png or pdf" in capsys.readouterr().err
    recording = record(tmp_path / "run.mcap", ticks=5)
    assert main(["picture", "--recording", str(recording), "--tick", "99", "-o", str(tmp_path / "x.svg")]) == 2
    assert "tick 99 is outside the recording (0..4)" in capsys.readouterr().err
    broken = tmp_path / "broken"
    broken.mkdir()
    (broken / "agents.xabsl").write_text('include "missing.xabsl";\nagent a("A", nothing);\n')
    assert main(["picture", str(broken), "-o", str(tmp_path / "b.svg")]) == 1
    assert "no picture written" in capsys.readouterr().out and not (tmp_path / "b.svg").exists()
