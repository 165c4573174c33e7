"""The documentation's static files: the style sheet and the search box's script.

The search index is a script (``search-index.js`` sets ``window.XABSL_DOCS_INDEX``), not a
JSON file fetched at run time, because browsers refuse ``fetch`` on ``file://`` pages: the
documentation has to work opened straight from disk.
"""

from __future__ import annotations

STYLE = """\
:root { --fg: #1d2330; --muted: #5b6475; --line: #d9dee8; --accent: #2457a6; --bg: #ffffff; --soft: #f4f6fa; }
* { box-sizing: border-box; }
body { margin: 0; font: 15px/1.5 system-ui, -apple-system, "Segoe UI", Helvetica, Arial, sans-serif;
  color: var(--fg); background: var(--bg); }
header { position: sticky; top: 0; z-index: 2; display: flex; flex-wrap: wrap; gap: .4em 1.2em;
  align-items: center; padding: .5em 1.2em; background: var(--soft); border-bottom: 1px solid var(--line); }
header .title { font-weight: 600; color: var(--fg); }
header nav a { margin-right: .9em; }
main { max-width: 72em; margin: 0 auto; padding: 1em 1.2em 4em; }
a { color: var(--accent); text-decoration: none; }
a:hover { text-decoration: underline; }
h1 { font-size: 1.6em; margin: .4em 0 .2em; }
h2 { font-size: 1.25em; margin: 1.6em 0 .4em; border-bottom: 1px solid var(--line); padding-bottom: .15em; }
h3 { font-size: 1.05em; margin: 1.3em 0 .3em; }
.kind { color: var(--muted); font-weight: normal; font-size: .8em; margin-right: .4em; }
.doc { white-space: pre-line; }
.muted, .where { color: var(--muted); font-size: .9em; }
.badge { display: inline-block; font-size: .75em; padding: 0 .5em; margin-left: .4em; border-radius: 1em;
  background: #e6edf8; color: var(--accent); vertical-align: middle; }
table { border-collapse: collapse; margin: .4em 0 1em; }
th, td { text-align: left; padding: .25em .8em .25em 0; border-bottom: 1px solid var(--line); vertical-align: top; }
th { font-weight: 600; font-size: .9em; }
code, pre { font-family: ui-monospace, "SFMono-Regular", Menlo, Consolas, monospace; font-size: .9em; }
pre.tree, pre.actions { background: var(--soft); padding: .6em .8em; border-radius: 4px; overflow-x: auto;
  margin: .3em 0 .8em; white-space: pre-wrap; }
[id] { scroll-margin-top: 3.5em; }
pre .comment { color: #6a7a55; }
pre .keyword { color: #8a3b9c; }
.leaf:target, section:target > h3, h3:target, tr:target { background: #fff3b0; }
.graph { overflow: auto; border: 1px solid var(--line); border-radius: 4px; padding: .5em; margin: .5em 0 1em;
  max-height: 80vh; }
.graph svg { max-width: 100%; height: auto; }
.graph.wide svg { max-width: none; }
.graph a:hover text { text-decoration: underline; }
ul.places { margin: .2em 0 .8em; padding-left: 1.2em; }
ul.columns { columns: 18em; padding-left: 1.2em; }
.search { position: relative; margin-left: auto; }
.search input { width: 18em; padding: .25em .5em; border: 1px solid var(--line); border-radius: 4px; font: inherit; }
.search ol { position: absolute; right: 0; top: 2.1em; width: 28em; max-height: 70vh; overflow-y: auto;
  margin: 0; padding: .3em 0; list-style: none; background: var(--bg); border: 1px solid var(--line);
  border-radius: 4px; box-shadow: 0 4px 14px rgba(0, 0, 0, .12); }
.search ol:empty { display: none; }
.search li a { display: block; padding: .2em .8em; }
.search li a.active, .search li a:hover { background: var(--soft); text-decoration: none; }
.search li .kind { float: right; }
"""

SEARCH = """\
// The search box: matches names in window.XABSL_DOCS_INDEX ([name, kind, url, summary] rows).
(function () {
  "use strict";
  var index = window.XABSL_DOCS_INDEX || [];
  var base = document.body.getAttribute("data-base") || "";
  var input = document.getElementById("search");
  var list = document.getElementById("search-results");
  if (!input || !list) { return; }
  var active = 0;
  function rank(name, query) {
    var lower = name.toLowerCase();
    if (lower === query) { return 0; }
    if (lower.indexOf(query) === 0) { return 1; }
    var at = lower.indexOf(query);
    if (at > 0 && /[._]/.test(lower.charAt(at - 1))) { return 2; }
    return at >= 0 ? 3 : -1;
  }
  function show() {
    var query = input.value.trim().toLowerCase();
    list.textContent = "";
    active = 0;
    if (!query) { return; }
    var found = [];
    for (var i = 0; i < index.length; i++) {
      var r = rank(index[i][0], query);
      if (r < 0 && index[i][3] && index[i][3].toLowerCase().indexOf(query) >= 0) { r = 4; }
      if (r >= 0) { found.push([r, index[i]]); }
    }
    found.sort(function (a, b) { return a[0] - b[0] || a[1][0].localeCompare(b[1][0]); });
    found.slice(0, 30).forEach(function (hit, n) {
      var row = hit[1];
      var item = document.createElement("li");
      var link = document.createElement("a");
      link.href = base + row[2];
      link.title = row[3] || row[0];
      var kind = document.createElement("span");
      kind.className = "kind";
      kind.textContent = row[1];
      link.appendChild(kind);
      link.appendChild(document.createTextNode(row[0]));
      if (n === 0) { link.className = "active"; }
      item.appendChild(link);
      list.appendChild(item);
    });
  }
  function move(step) {
    var links = list.querySelectorAll("a");
    if (!links.length) { return; }
    links[active].className = "";
    active = (active + step + links.length) % links.length;
    links[active].className = "active";
    links[active].scrollIntoView({ block: "nearest" });
  }
  input.addEventListener("input", show);
  input.addEventListener("keydown", function (event) {
    if (event.key === "ArrowDown") { move(1); event.preventDefault(); }
    else if (event.key === "ArrowUp") { move(-1); event.preventDefault(); }
    else if (event.key === "Enter") {
      var links = list.querySelectorAll("a");
      if (links.length) { window.location.href = links[active].href; }
    } else if (event.key === "Escape") { input.value = ""; show(); }
  });
  document.addEventListener("keydown", function (event) {
    if (event.key === "/" && document.activeElement !== input) { input.focus(); event.preventDefault(); }
  });
})();
"""
