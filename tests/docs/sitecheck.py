"""Reading a generated documentation folder back: links, anchors, inline SVGs, the search index.

Everything is parsed from the files (``html.parser`` for pages, ``xml.etree`` for SVG), never
taken from the generator, so a test that uses it checks what a browser would get.
"""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

SVG = "{http://www.w3.org/2000/svg}"
XLINK = "{http://www.w3.org/1999/xlink}"


class _Page(HTMLParser):
    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.ids: list[str] = []
        self.links: list[str] = []
        self.sections: list[str] = []
        self.heading = ""
        self._in_h1 = False

    def handle_endtag(self, tag: str) -> None:
        if tag == "h1":
            self._in_h1 = False

    def handle_data(self, data: str) -> None:
        if self._in_h1:
            self.heading += data

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        values = dict(attrs)
        if tag == "h1":
            self._in_h1 = True
        if values.get("id"):
            self.ids.append(values["id"] or "")
            if tag == "section":
                self.sections.append(values["id"] or "")
        for name in ("href", "src", "xlink:href", "data"):
            value = values.get(name)
            if value is not None:
                self.links.append(value)


@dataclass
class Page:
    """One parsed page: its element ids, the links it makes, the SVGs it inlines."""

    path: str
    ids: list[str]
    links: list[str]
    sections: list[str]
    #: the text of the ``<h1>``: "option walk", "agent soccer", "Symbols"
    heading: str
    svgs: list[ET.Element] = field(default_factory=list)


def read_page(root: Path, path: str) -> Page:
    """Parse ``root/path``: ids and links with html.parser, every inline ``<svg>`` as XML."""
    text = (root / path).read_text(encoding="utf-8")
    parser = _Page()
    parser.feed(text)
    parser.close()
    svgs = [ET.fromstring(chunk) for chunk in re.findall(r"<svg\b.*?</svg>", text, flags=re.S)]
    return Page(path, parser.ids, parser.links, parser.sections, parser.heading, svgs)


def read_site(root: Path) -> dict[str, Page]:
    """Every HTML page below ``root``, by path relative to it (``/`` separators)."""
    return {
        p.relative_to(root).as_posix(): read_page(root, p.relative_to(root).as_posix()) for p in root.rglob("*.html")
    }


def broken_links(root: Path, pages: dict[str, Page]) -> list[str]:
    """``page: link`` for every link that leaves the folder or misses its file or anchor."""
    broken = []
    for path, page in pages.items():
        folder = Path(path).parent
        for link in page.links:
            parts = urlsplit(link)
            if parts.scheme or parts.netloc:
                broken.append(f"{path}: {link} (not local)")
                continue
            target = (folder / unquote(parts.path)).as_posix() if parts.path else path
            resolved = (root / target).resolve()
            if not resolved.is_relative_to(root.resolve()) or not resolved.is_file():
                broken.append(f"{path}: {link} (no file)")
                continue
            if parts.fragment:
                key = resolved.relative_to(root.resolve()).as_posix()
                if key not in pages or unquote(parts.fragment) not in pages[key].ids:
                    broken.append(f"{path}: {link} (no anchor)")
    return broken


def svg_nodes(svg: ET.Element) -> list[ET.Element]:
    """The Graphviz nodes of an SVG (``<g class="node">``)."""
    return [g for g in svg.iter(SVG + "g") if g.get("class") == "node"]


def search_index(root: Path) -> list[list[str]]:
    """The rows of ``search-index.js``: ``[name, kind, href, summary]``."""
    text = (root / "search-index.js").read_text(encoding="utf-8").strip()
    prefix = "window.XABSL_DOCS_INDEX = "
    assert text.startswith(prefix) and text.endswith(";")
    rows: list[list[str]] = json.loads(text[len(prefix) : -1])
    return rows
