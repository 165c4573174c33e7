"""``xabsl profile``: JSON on stdout, rich tables, the HTML report (self-contained, well-formed), errors."""

from __future__ import annotations

import json
import re
from html.parser import HTMLParser
from pathlib import Path

import pytest

from xabsl_studio.engine.cli import main

VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta", "source", "track", "wbr"}


class _Balance(HTMLParser):
    """Checks that every element is closed in order (SVG's self-closed elements included)."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.stack: list[str] = []
        self.errors: list[str] = []
        self.ids: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.ids.extend(v for k, v in attrs if k == "id" and v)
        if tag not in VOID:
            self.stack.append(tag)

    def handle_startendtag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.ids.extend(v for k, v in attrs if k == "id" and v)

    def handle_endtag(self, tag: str) -> None:
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes {self.stack[-1] if self.stack else 'nothing'}")
        else:
            self.stack.pop()


def test_json(cycle_recording: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["profile", str(cycle_recording), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["format"] == "xabsl-profile/1"
    assert set(report) >= {"agents", "teams", "oscillations", "activity", "cpu", "cpu_note", "ticks", "tick_ms"}
    assert report["agents"]["robot1"]["options"]["cycle"]["states"]["a"]["activations"] == 10


def test_tables(cycle_recording: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["profile", str(cycle_recording), "--agent", "robot1", "--oscillation-ms", "60"]) == 0
    out = capsys.readouterr().out
    assert "team cycler" in out and "agent robot1" in out
    assert "coverage: options 2/3 (66.7 %)" in out
    assert "oscillations (re-entered within 60 ms): 18" in out
    assert "no CPU times" in out


def test_html_is_self_contained_and_well_formed(cycle_recording: Path, tmp_path: Path) -> None:
    out = tmp_path / "report.html"
    assert main(["profile", str(cycle_recording), "--json", "--html", str(out)]) == 0
    text = out.read_text()
    # no reference out of the file: XML namespace names are identifiers, not fetched
    without_namespaces = re.sub(r'xmlns(:\w+)?="[^"]*"', "", text)
    assert not re.search(r"https?://", without_namespaces)
    assert not re.search(r"<(script|link|img|iframe)[^>]*\s(src|href)=", text, re.IGNORECASE)
    checker = _Balance()
    checker.feed(text)
    checker.close()
    assert checker.errors == [] and checker.stack == []
    # the option graph and the state machines are inline SVG, coloured by coverage
    assert text.count("<svg") >= 1 + 3 + 1  # option graph, three state machines, one activity plot
    assert 'id="option_' in text and "never active" in text
    assert "leaf 0: 10" in text  # cycle a -> b, ten times, on its edge


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["profile", "/nonexistent.mcap"], "no such file"),
        (["profile", "{rec}", "--agent", "nobody"], "no agent 'nobody'"),
        (["profile", "{rec}", "--oscillation-ms", "nan"], "--oscillation-ms"),
        (["profile", "{rec}", "--oscillation-ms", "-1"], "--oscillation-ms"),
        (["profile", "{notrec}"], "not"),
    ],
)
def test_errors(
    argv: list[str], message: str, cycle_recording: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    notrec = tmp_path / "x.mcap"
    notrec.write_text("hello")
    argv = [a.format(rec=cycle_recording, notrec=notrec) for a in argv]
    assert main(argv) == 2
    assert message in capsys.readouterr().err
