"""What the pages say: decision trees as XABSL text, escaping, cross references, the command line."""

from __future__ import annotations

import re
from collections.abc import Callable
from html import unescape
from pathlib import Path

import pytest

from tests.docs.sitecheck import broken_links, read_site
from tests.kit import KIT
from xabsl_studio.engine.cli import main
from xabsl_studio.engine.docs import GraphLayoutError, build, write
from xabsl_studio.engine.docs.graphs import render_all
from xabsl_studio.engine.docs.xref import cross_references
from xabsl_studio.engine.ir.ic_reader import read_ic_file
from xabsl_studio.engine.lang import Compilation

SOURCES = {
    "agents.xabsl": '/*** Title: Tiny <set> & co */\ninclude "s.xabsl"; include "b.xabsl"; include "o.xabsl";\n'
    '/** The one agent. */\nagent main("Main", top);\n',
    "s.xabsl": """namespace s("S") {
  /** how far <away> the ball is */
  float input ball.distance [0..9000] "mm";
  bool input seen;
  enum mode { walk, stand };
  /** the mode chosen */
  enum mode output chosen;
  float output count;
  float internal memo;
  /** kick harder than this */
  const strong = 300 "N";
}
""",
    "b.xabsl": """namespace b("B") {
  /** Walks & kicks. */
  behavior kick { float strength [0..1] "1"; }
}
""",
    "o.xabsl": """/** Goes <b>for</b> the ball. */
option top {
  /** the distance to stop at */
  float @stop [0..1000] "mm";
  common decision {
    /** lost it */
    if (!seen) goto look;
  }
  initial state look {
    decision {
      else
      /** near */
      if (ball.distance < @stop && seen) {
        if (state_time > 100) goto hit;
        else stay;
      }
      else if (ball.distance > strong) goto look;
      else stay;
    }
    action { chosen = walk; memo = ball.distance; }
  }
  target state hit {
    action { kick(strength = 1); count = count + 1; chosen = stand; }
  }
}
""",
}


@pytest.fixture
def site(compile_sources: Callable[..., Compilation]) -> dict[str, str]:
    compilation = compile_sources(SOURCES, "agents.xabsl")
    assert compilation.program is not None, [d.format() for d in compilation.errors]
    return {path: data.decode("utf-8") for path, data in build(compilation.program).items()}


def text_of(html: str, pattern: str) -> str:
    """The plain text of the first match of ``pattern`` (tags dropped, entities decoded)."""
    found = re.search(pattern, html, flags=re.S)
    assert found, pattern
    return unescape(re.sub(r"<[^>]+>", "", found.group(1)))


def test_decision_trees_read_as_xabsl_source(site: dict[str, str]) -> None:
    page = site["options/top.html"]
    assert text_of(page, r'<div id="common-decision">(.*?)</div>') == "/** lost it */\nif (!seen) goto look;"
    look = text_of(page, r'<section id="state-look">.*?<pre class="tree">(.*?)</pre>')
    assert look == (
        "/** near */\n"
        "else if (ball.distance < @stop && seen) {\n"
        "  if (state_time > 100) goto hit;\n"
        "  else stay;\n"
        "}\n"
        # ``goto look`` inside look is the IR's stay (the same transition, §3.3 ``t self``)
        "else if (ball.distance > strong) stay;\n"
        "else stay;"
    )
    actions = text_of(page, r'<section id="state-look">.*?<pre class="actions">(.*?)</pre>')
    assert actions == "chosen = walk;\nmemo = ball.distance;"
    hit = text_of(page, r'<section id="state-hit">(.*?)</section>')
    assert "no decision of its own: the common decision tree, else stay" in hit
    assert "kick(strength = 1);" in hit and "target" in hit
    # leaves are anchors the state machine's edges link to; goto links to the state's section
    assert '<span class="leaf" id="leaf-0-1"><span class="keyword">goto</span> <a href="#state-hit">hit</a>;' in page
    assert 'xlink:href="#leaf-0-1"' in page and 'xlink:href="#common-decision"' in page


def test_doc_comments_and_names_are_escaped(site: dict[str, str]) -> None:
    assert "Goes &lt;b&gt;for&lt;/b&gt; the ball." in site["options/top.html"]
    assert "<b>for</b>" not in site["options/top.html"]
    assert "<title>index · Tiny &lt;set&gt; &amp; co</title>" in site["index.html"]
    assert "how far &lt;away&gt; the ball is" in site["symbols.html"]
    assert "Walks &amp; kicks." in site["behaviors.html"]
    index = site["search-index.js"]
    assert "</" not in index  # a summary cannot end the script element


def test_parameters_show_type_range_unit_and_doc(site: dict[str, str]) -> None:
    row = text_of(site["options/top.html"], r'<tr id="param-stop">(.*?)</tr>')
    assert row == "@stopdecimal0..1000mmthe distance to stop at"
    kick = text_of(site["behaviors.html"], r'<h3 id="b-kick">.*?<table>(.*?)</table>')
    assert "strengthdecimal0..11" in kick


def test_cross_references_count_readers_writers_callers(compile_sources: Callable[..., Compilation]) -> None:
    program = compile_sources(SOURCES, "agents.xabsl").program
    assert program is not None
    refs = cross_references(program)
    assert refs.readers["seen"] == [("top", None), ("top", "look")]
    assert refs.readers["ball.distance"] == [("top", "look")]
    assert refs.readers["count"] == [("top", "hit")]
    assert refs.writers["chosen"] == [("top", "look"), ("top", "hit")]
    assert refs.writers["memo"] == [("top", "look")]
    assert refs.behavior_callers["kick"] == [("top", "hit")]
    assert refs.constant_users["strong"] == [("top", "look")]
    assert refs.enum_users["mode"] == [("top", "look"), ("top", "hit")]
    assert "top" not in refs.option_callers


def test_symbol_entries_say_who_reads_and_writes(site: dict[str, str]) -> None:
    chosen = text_of(site["symbols.html"], r'<h3 id="s-chosen">(.*?)</section>')
    assert "type enum mode" in chosen and "the mode chosen" in chosen
    assert "read byno option reads it" in chosen and "written bytop: look, hit" in chosen
    distance = text_of(site["symbols.html"], r'<h3 id="s-ball.distance">(.*?)</section>')
    assert "range 0..9000 · unit mm" in distance and "read bytop: look" in distance
    assert "value 300 · unit N" in text_of(site["constants.html"], r'<h3 id="c-strong">(.*?)</section>')


def test_cli_writes_the_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    agents = tmp_path / "set" / "agents.xabsl"
    agents.parent.mkdir()
    for name, text in SOURCES.items():
        (agents.parent / name).write_text(text)
    out = tmp_path / "out"
    assert main(["docs", str(agents), "-o", str(out)]) == 0
    assert capsys.readouterr().out.startswith("ok: 7 pages (1 options) in ")
    assert broken_links(out, read_site(out)) == []
    (agents.parent / "o.xabsl").write_text("option top { initial state s { action { nothing = 1; } } }\n")
    assert main(["docs", str(agents), "-o", str(tmp_path / "bad")]) == 1
    assert not (tmp_path / "bad").exists()
    assert "error" in capsys.readouterr().out
    assert main(["docs", str(tmp_path / "missing.xabsl"), "-o", str(out)]) == 2
    (tmp_path / "file").write_text("")
    assert main(["docs", str(agents), "-o", str(tmp_path / "file")]) == 2


def test_a_second_run_removes_the_pages_of_options_gone(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    agents = tmp_path / "set" / "agents.xabsl"
    agents.parent.mkdir()
    for name, text in SOURCES.items():
        (agents.parent / name).write_text(text)
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    assert main(["docs", str(agents), "-o", str(out)]) == 0
    assert (out / "options" / "top.html").is_file()
    (agents.parent / "o.xabsl").write_text(SOURCES["o.xabsl"].replace("option top", "option start"))
    (agents.parent / "agents.xabsl").write_text(SOURCES["agents.xabsl"].replace(", top)", ", start)"))
    assert main(["docs", str(agents), "-o", str(out)]) == 0
    assert not (out / "options" / "top.html").exists() and (out / "options" / "start.html").is_file()
    assert (out / "notes.txt").read_text() == "mine"
    assert broken_links(out, read_site(out)) == []


def test_programs_read_from_intermediate_code_are_documented(tmp_path: Path) -> None:
    """No spans, no source text: conditions in the canonical rendering, every link still valid."""
    program = read_ic_file(KIT / "decisions" / "expected.ic")
    files = build(program)
    write(files, tmp_path)
    pages = read_site(tmp_path)
    assert broken_links(tmp_path, pages) == []
    assert {p.heading for p in pages.values() if p.heading.startswith("option ")} == {
        f"option {name}" for name in program.options
    }
    assert '<pre class="tree">' in files[next(p for p in files if p.startswith("options/"))].decode()


def test_without_graphviz_the_command_says_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))  # no dot on it
    assert main(["docs", str(KIT / "decisions" / "agents.xabsl"), "-o", str(tmp_path / "out")]) == 2
    assert "Graphviz 'dot' is not installed" in capsys.readouterr().err


def test_a_graph_graphviz_refuses_is_named() -> None:
    good = "digraph a { x -> y }\n"
    bad = 'digraph "option broken" { x -> }\n'
    with pytest.raises(GraphLayoutError, match=r'could not lay out digraph "option broken": .*syntax error'):
        render_all([good, bad, good], jobs=1)
    svgs = render_all([good, good, good], jobs=2)
    assert len(svgs) == 3 and all(s.startswith("<?xml") and "<svg" in s for s in svgs)
