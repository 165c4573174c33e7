"""The documentation's HTML pages, rendered from the IR (every text escaped here, nowhere else).

Layout of a documentation folder (paths relative to it)::

    index.html                 the behavior set: agents, options, declarations, counts
    agents/<agent>.html        an agent's option graph and the options it reaches
    options/<option>.html      an option: doc, parameters, state machine, common decision tree,
                               each state's decision tree and actions, callers
    symbols.html               input, output and internal symbols (#s-<name>)
    enumerations.html          enumerations (#e-<name>)
    constants.html             constants (#c-<name>)
    behaviors.html             basic behaviors (#b-<name>)
    style.css, search.js, search-index.js

Inside an option page a state is ``#state-<name>``, a parameter ``#param-<name>``, a decision
leaf ``#leaf-<state index>-<leaf id>``, the common decision tree ``#common-decision``.
Decision trees are written the way XABSL source writes them (``if (...) goto x; else stay;``)
with the conditions' source text the IR keeps (a canonical rendering for IC programs).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from html import escape
from urllib.parse import quote as url_quote

from xabsl_studio.engine import ir
from xabsl_studio.engine.docs.xref import CrossReferences, Place, own_actions, own_decision
from xabsl_studio.engine.emit.json import render_expression
from xabsl_studio.engine.types import Kind, Span


def _e(text: str) -> str:
    return escape(text, quote=True)


def fragment(text: str) -> str:
    """A name as the fragment of a URL (``#state-<fragment>``)."""
    return url_quote(text, safe="._-~")


def _slug(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name) or "_"


def summary(doc: str | None) -> str:
    """The first sentence (or line) of a doc comment, for lists and the search index."""
    if not doc:
        return ""
    first = doc.strip().split("\n", 1)[0].strip()
    end = first.find(". ")
    return first[: end + 1] if end >= 0 else first


class Site:
    """Where each page and entry lives; hrefs are relative to the page being rendered.

    Args:
        program: the program documented.
    """

    def __init__(self, program: ir.Program) -> None:
        self.program = program
        self.option_paths = self._paths("options", program.options)
        self.agent_paths = self._paths("agents", [a.name for a in program.agents])

    @staticmethod
    def _paths(folder: str, names: Iterable[str]) -> dict[str, str]:
        """File names per name, unique also on case-insensitive file systems."""
        paths: dict[str, str] = {}
        taken: set[str] = set()
        for name in names:
            slug = _slug(name)
            candidate, n = slug, 1
            while candidate.lower() in taken:
                n += 1
                candidate = f"{slug}-{n}"
            taken.add(candidate.lower())
            paths[name] = f"{folder}/{candidate}.html"
        return paths

    # hrefs from the documentation's root folder (``base`` is "" or "../" for pages in a subfolder)

    def option(self, name: str, state: str | None = None) -> str:
        """The page of option ``name`` (the section of ``state``)."""
        path = self.option_paths[name]
        return path + (f"#state-{fragment(state)}" if state else "")

    def agent(self, name: str) -> str:
        """The page of agent ``name``."""
        return self.agent_paths[name]

    @staticmethod
    def symbol(name: str) -> str:
        """The entry of an input, output or internal symbol."""
        return f"symbols.html#s-{fragment(name)}"

    @staticmethod
    def enum(name: str) -> str:
        """The entry of an enumeration."""
        return f"enumerations.html#e-{fragment(name)}"

    @staticmethod
    def constant(name: str) -> str:
        """The entry of a constant."""
        return f"constants.html#c-{fragment(name)}"

    @staticmethod
    def behavior(name: str) -> str:
        """The entry of a basic behavior."""
        return f"behaviors.html#b-{fragment(name)}"


_NAV = (
    ("index.html", "Index"),
    ("index.html#agents", "Agents"),
    ("index.html#options", "Options"),
    ("symbols.html", "Symbols"),
    ("enumerations.html", "Enumerations"),
    ("constants.html", "Constants"),
    ("behaviors.html", "Basic behaviors"),
)


class Renderer:
    """Renders every page of one program.

    Args:
        program: the program documented.
        refs: its cross references.
        site: where the pages live.
        agents_of: per option, the agents whose root reaches it.
    """

    def __init__(self, program: ir.Program, refs: CrossReferences, site: Site, agents_of: dict[str, list[str]]) -> None:
        self.program = program
        self.refs = refs
        self.site = site
        self.agents_of = agents_of
        self.title = program.title or "XABSL behavior"
        self.base = ""

    # -- page frame ------------------------------------------------------------------------------

    def page(self, path: str, title: str, body: str) -> str:
        """A whole HTML page at ``path`` (relative to the root) around ``body``."""
        self.base = "../" * path.count("/")
        base = self.base
        nav = "".join(f'<a href="{base}{href}">{label}</a>' for href, label in _NAV)
        return (
            "<!doctype html>\n"
            f'<html lang="en"><head><meta charset="utf-8"><title>{_e(title)} · {_e(self.title)}</title>\n'
            '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
            f'<link rel="stylesheet" href="{base}style.css"></head>\n'
            f'<body data-base="{base}">\n<header><a class="title" href="{base}index.html">{_e(self.title)}</a>'
            f"<nav>{nav}</nav>"
            '<div class="search"><input id="search" type="search" placeholder="Search options, symbols… (/)" '
            'autocomplete="off" aria-label="Search the documentation"><ol id="search-results"></ol></div>'
            f"</header>\n<main>\n{body}\n</main>\n"
            f'<script src="{base}search-index.js"></script><script src="{base}search.js"></script>\n'
            "</body></html>\n"
        )

    def link(self, href: str, text: str, css: str = "") -> str:
        """An ``<a>`` to ``href`` (relative to the root) from the current page."""
        cls = f' class="{css}"' if css else ""
        return f'<a href="{self.base}{_e(href)}"{cls}>{_e(text)}</a>'

    def local(self, fragment: str, text: str) -> str:
        """An ``<a>`` to an anchor of the current page."""
        return f'<a href="#{_e(fragment)}">{_e(text)}</a>'

    @staticmethod
    def where(span: Span | None) -> str:
        """``file:line`` of a declaration, when the program was compiled from source."""
        return f'<span class="where">{_e(span.file)}:{span.line}</span>' if span is not None else ""

    @staticmethod
    def doc(text: str | None) -> str:
        """A doc comment as a paragraph (line breaks kept)."""
        return f'<p class="doc">{_e(text.strip())}</p>' if text and text.strip() else ""

    def symbol_link(self, name: str) -> str:
        """A link to a symbol, enumeration-aware for parameters' types."""
        return self.link(self.site.symbol(name), name)

    def kind(self, kind: Kind, enum: str | None) -> str:
        """A value type; an enumeration links to its entry."""
        if kind is Kind.ENUM and enum:
            return "enum " + self.link(self.site.enum(enum), enum)
        return _e(kind.value)

    def places(self, places: Sequence[Place] | None, empty: str = "nowhere") -> str:
        """Places grouped by option: ``option: state, state, common``, each a link."""
        if not places:
            return f'<p class="muted">{_e(empty)}</p>'
        grouped: dict[str, list[str | None]] = {}
        for option, state in places:
            grouped.setdefault(option, []).append(state)
        items = []
        for option, states in grouped.items():
            parts = [
                self.link(self.site.option(option, state), state)
                if state is not None
                else self.link(self.site.option(option) + "#common", "common")
                for state in states
            ]
            items.append(f"<li>{self.link(self.site.option(option), option)}: {', '.join(parts)}</li>")
        return f'<ul class="places">{"".join(items)}</ul>'

    def parameters(self, params: Sequence[ir.Parameter], option: bool = False) -> str:
        """A parameter table: name, type, range, unit, description.

        Option parameters are written ``@name`` (as the option's body reads them) and anchored.
        """
        if not params:
            return '<p class="muted">no parameters</p>'
        rows = []
        for p in params:
            anchor = f' id="param-{_e(p.short_name)}"' if option else ""
            name = ("@" if option else "") + p.short_name
            rows.append(
                f"<tr{anchor}><td><code>{_e(name)}</code></td><td>{self.kind(p.kind, p.enum)}</td>"
                f"<td>{_e(p.range or '')}</td><td>{_e(p.unit or '')}</td><td>{_e((p.doc or '').strip())}</td></tr>"
            )
        return (
            "<table><tr><th>parameter</th><th>type</th><th>range</th><th>unit</th><th>description</th></tr>"
            + "".join(rows)
            + "</table>"
        )

    # -- decision trees and actions --------------------------------------------------------------------

    @staticmethod
    def _condition(node: ir.If | ir.CommonBranch) -> str:
        return _e(node.text or render_expression(node.condition))

    @staticmethod
    def _comment(text: str, pad: str) -> str:
        return f'{pad}<span class="comment">/** {_e(" ".join(text.split()))} */</span>'

    def _leaf(self, leaf: ir.Transition, state_index: int | None) -> str:
        if leaf.stay or leaf.target is None:
            text = '<span class="keyword">stay</span>;'
        else:
            text = f'<span class="keyword">goto</span> {self.local("state-" + fragment(leaf.target), leaf.target)};'
        if state_index is None:
            return text
        return f'<span class="leaf" id="leaf-{state_index}-{leaf.leaf}">{text}</span>'

    def _tree(self, tree: ir.DecisionTree, depth: int, out: list[str], state_index: int | None) -> None:
        """Append the lines of ``tree``; an else-if chain is one loop, not recursion."""
        pad = "  " * depth
        if isinstance(tree, ir.Transition):
            out.append(pad + self._leaf(tree, state_index))
            return
        prefix = ""
        node: ir.DecisionTree = tree
        while isinstance(node, ir.If):
            if node.doc:
                out.append(self._comment(node.doc, pad))
            head = f'{pad}{prefix}<span class="keyword">if</span> ({self._condition(node)})'
            self._branch(head, node.then, depth, out, state_index)
            if node.else_doc:
                out.append(self._comment(node.else_doc, pad))
            prefix = '<span class="keyword">else</span> '
            if not isinstance(node.otherwise, ir.If):
                self._branch(f'{pad}<span class="keyword">else</span>', node.otherwise, depth, out, state_index)
            node = node.otherwise

    def _branch(self, head: str, body: ir.DecisionTree, depth: int, out: list[str], state_index: int | None) -> None:
        if isinstance(body, ir.Transition):
            out.append(f"{head} {self._leaf(body, state_index)}")
        else:
            out.append(head + " {")
            self._tree(body, depth + 1, out, state_index)
            out.append("  " * depth + "}")

    def decision(self, tree: ir.DecisionTree, state_index: int, after_common: bool) -> str:
        """A state's own decision tree as XABSL text."""
        lines: list[str] = []
        self._tree(tree, 0, lines, state_index)
        if after_common:  # the leading ``else`` of XABSL source, after the doc comments
            first = next(i for i, line in enumerate(lines) if not line.startswith('<span class="comment">'))
            lines[first] = '<span class="keyword">else</span> ' + lines[first]
        return '<pre class="tree">' + "\n".join(lines) + "</pre>"

    def common_decision(self, option: ir.Option) -> str:
        """The option's common decision tree (``if`` / ``else if`` branches, no final ``else``)."""
        lines: list[str] = []
        for n, branch in enumerate(option.common_decision):
            if branch.doc:
                lines.append(self._comment(branch.doc, ""))
            head = ('<span class="keyword">else</span> ' if n else "") + (
                f'<span class="keyword">if</span> ({self._condition(branch)})'
            )
            self._branch(head, branch.tree, 0, lines, None)
        return '<pre class="tree">' + "\n".join(lines) + "</pre>"

    def _args(self, args: Sequence[ir.Argument]) -> str:
        return ", ".join(f"{_e(a.param.rsplit('.', 1)[-1])} = {_e(render_expression(a.value))}" for a in args)

    def actions(self, actions: Sequence[ir.Action]) -> str:
        """Action items as XABSL text: options and basic behaviors linked, assignments' symbols too."""
        if not actions:
            return '<p class="muted">no action items</p>'
        lines = []
        for action in actions:
            if isinstance(action, ir.OptionCall):
                lines.append(f"{self.link(self.site.option(action.option), action.option)}({self._args(action.args)});")
            elif isinstance(action, ir.BehaviorCall):
                lines.append(
                    f"{self.link(self.site.behavior(action.behavior), action.behavior)}({self._args(action.args)});"
                )
            else:
                lines.append(f"{self.symbol_link(action.symbol)} = {_e(render_expression(action.value))};")
        return '<pre class="actions">' + "\n".join(lines) + "</pre>"

    # -- pages ------------------------------------------------------------------------------------------

    def option_page(self, option: ir.Option, svg: str) -> str:
        """The page of one option."""
        path = self.site.option_paths[option.name]
        self.base = "../"
        refs = self.refs
        parts = [f'<h1><span class="kind">option</span> {_e(option.name)}</h1>']
        where = self.where(option.span)
        agents = self.agents_of.get(option.name, [])
        meta = [where] if where else []
        if agents:
            meta.append("reached by agent " + ", ".join(self.link(self.site.agent(a), a) for a in agents))
        if meta:
            parts.append(f'<p class="muted">{" · ".join(meta)}</p>')
        parts.append(self.doc(option.doc))
        parts.append("<h2>Parameters</h2>" + self.parameters(option.params, option=True))
        parts.append('<h2>State machine</h2><div class="graph">' + svg + "</div>")
        parts.append("<h2>Called from</h2>" + self.places(refs.option_callers.get(option.name), "no option calls it"))
        callees: list[str] = []
        for state in option.states:
            for action in state.actions:
                if isinstance(action, ir.OptionCall):
                    item = self.link(self.site.option(action.option), action.option)
                elif isinstance(action, ir.BehaviorCall):
                    item = self.link(self.site.behavior(action.behavior), action.behavior) + " (basic behavior)"
                else:
                    continue
                if item not in callees:
                    callees.append(item)
        parts.append(
            "<h2>Calls</h2>"
            + (f'<ul class="places">{"".join(f"<li>{c}</li>" for c in callees)}</ul>' if callees else "")
            + ("" if callees else '<p class="muted">nothing: a leaf of the option graph</p>')
        )
        if option.common_decision or option.common_action:
            parts.append('<h2 id="common">Common decision tree and action</h2>')
            parts.append('<p class="muted">Evaluated before the decision of every state.</p>')
            if option.common_decision:
                parts.append(f'<div id="common-decision">{self.common_decision(option)}</div>')
            if option.common_action:
                parts.append("<h3>Common action</h3>" + self.actions(option.common_action))
            reads = refs.reads.get((option.name, None))
            if reads:
                parts.append("<p>reads " + ", ".join(self.symbol_link(s) for s in reads) + "</p>")
        parts.append("<h2>States</h2>")
        incoming: dict[str, list[str]] = {}
        for state in option.states:
            for leaf in ir.leaves(state.decision):
                if leaf.target and leaf.target != state.name and state.name not in incoming.get(leaf.target, []):
                    incoming.setdefault(leaf.target, []).append(state.name)
        for state in option.states:
            parts.append(self.state_section(option, state, incoming.get(state.name, [])))
        return self.page(path, f"option {option.name}", "\n".join(p for p in parts if p))

    def state_section(self, option: ir.Option, state: ir.State, incoming: list[str]) -> str:
        """One state: flags, its decision tree, its actions, what it reads, where it comes from."""
        badges = []
        if state.initial or state.name == option.initial_state:
            badges.append("initial")
        if state.target:
            badges.append("target")
        if state.coop == "c":
            badges.append(f"capacity {state.coop_count}")
        elif state.coop == "s":
            badges.append(f"synchronized {state.coop_count}" if state.coop_count else "synchronized")
        flags = "".join(f'<span class="badge">{b}</span>' for b in badges)
        parts = [
            f'<section id="state-{_e(state.name)}"><h3><span class="kind">state</span> {_e(state.name)}{flags}</h3>'
        ]
        parts.append(self.doc(state.doc))
        after_common = bool(option.common_decision)
        if state.has_decision:
            parts.append(self.decision(own_decision(option, state), state.index, after_common))
        else:
            common = "the common decision tree, else " if after_common else ""
            parts.append(f'<p class="muted">no decision of its own: {common}stay</p>')
        parts.append(self.actions(own_actions(option, state)))
        reads = self.refs.reads.get((option.name, state.name))
        if reads:
            parts.append("<p>reads " + ", ".join(self.symbol_link(s) for s in reads) + "</p>")
        if incoming:
            parts.append(
                "<p>entered from " + ", ".join(self.local("state-" + fragment(s), s) for s in incoming) + "</p>"
            )
        parts.append("</section>")
        return "\n".join(p for p in parts if p)

    def agent_page(self, agent: ir.Agent, svg: str, options: Sequence[str]) -> str:
        """An agent: its root option, its option graph and the options it reaches."""
        self.base = "../"
        parts = [f'<h1><span class="kind">agent</span> {_e(agent.name)}</h1>']
        meta = [f"“{_e(agent.title)}”"] if agent.title else []
        meta.append("root option " + self.link(self.site.option(agent.root), agent.root))
        where = self.where(agent.span)
        if where:
            meta.append(where)
        parts.append(f'<p class="muted">{" · ".join(meta)}</p>')
        parts.append(self.doc(agent.doc))
        # natural size in a scroll box: fitted to the page, a large option graph's names get unreadable
        parts.append('<h2>Option graph</h2><div class="graph wide">' + svg + "</div>")
        parts.append(f"<h2>Options ({len(options)})</h2>" + self.option_list(options))
        return self.page(self.site.agent(agent.name), f"agent {agent.name}", "\n".join(p for p in parts if p))

    def option_list(self, names: Iterable[str]) -> str:
        """A list of options, each linked, with its doc comment's first sentence."""
        items = []
        for name in names:
            text = summary(self.program.options[name].doc)
            items.append(
                f"<li>{self.link(self.site.option(name), name)}"
                + (f' <span class="muted">— {_e(text)}</span>' if text else "")
                + "</li>"
            )
        return f'<ul class="columns">{"".join(items)}</ul>'

    def index_page(self) -> str:
        """The index: the set's title, agents, every option, the declarations, counts."""
        self.base = ""
        program = self.program
        parts = [f"<h1>{_e(self.title)}</h1>"]
        meta = []
        if program.platform:
            meta.append("platform " + _e(program.platform))
        if program.software_environment:
            meta.append("software environment " + _e(program.software_environment))
        meta.append(
            f"{len(program.agents)} agents, {len(program.options)} options, "
            f"{sum(len(o.states) for o in program.options.values())} states, "
            f"{len(program.inputs)} input and {len(program.outputs)} output symbols, "
            f"{len(program.enums)} enumerations, {len(program.constants)} constants, "
            f"{len(program.behaviors)} basic behaviors"
        )
        parts.append(f'<p class="muted">{" · ".join(meta)}</p>')
        agents = []
        for agent in program.agents:
            title = f' <span class="muted">“{_e(agent.title)}”</span>' if agent.title else ""
            agents.append(
                f"<li>{self.link(self.site.agent(agent.name), agent.name)}{title}: root option "
                f"{self.link(self.site.option(agent.root), agent.root)}</li>"
            )
        parts.append('<h2 id="agents">Agents</h2>' + (f"<ul>{''.join(agents)}</ul>" if agents else "<p>none</p>"))
        names = sorted(program.options, key=str.lower)
        parts.append(f'<h2 id="options">Options ({len(names)})</h2>' + self.option_list(names))
        sections = (
            ("symbols.html", "Symbols", [*program.inputs, *program.outputs]),
            ("enumerations.html", "Enumerations", list(program.enums)),
            ("constants.html", "Constants", list(program.constants)),
            ("behaviors.html", "Basic behaviors", list(program.behaviors)),
        )
        parts.append("<h2>Declarations</h2><ul>")
        for href, label, items in sections:
            parts.append(f"<li>{self.link(href, label)} ({len(items)})</li>")
        parts.append("</ul>")
        return self.page("index.html", "index", "\n".join(parts))

    def _entry(self, anchor: str, kind: str, name: str, lines: Sequence[str]) -> str:
        head = f'<h3 id="{_e(anchor)}"><span class="kind">{_e(kind)}</span> {_e(name)}</h3>'
        return "<section>" + head + "\n".join(line for line in lines if line) + "</section>"

    def _facts(self, facts: Sequence[tuple[str, str]]) -> str:
        shown = [f"{label} {value}" for label, value in facts if value]
        return f"<p>{' · '.join(shown)}</p>" if shown else ""

    def symbols_page(self) -> str:
        """Input, output and internal symbols: type, range, unit, doc, readers and writers."""
        self.base = ""
        program, refs = self.program, self.refs
        parts = ["<h1>Symbols</h1>"]
        groups = (
            ("Input symbols", "input symbol", list(program.inputs.values())),
            ("Output symbols", "output symbol", [s for s in program.outputs.values() if not s.internal]),
            ("Internal symbols", "internal symbol", [s for s in program.outputs.values() if s.internal]),
        )
        for title, kind, symbols in groups:
            parts.append(f"<h2>{title} ({len(symbols)})</h2>")
            if not symbols:
                parts.append('<p class="muted">none</p>')
            for symbol in symbols:
                lines = [
                    self._facts(
                        (
                            ("type", self.kind(symbol.kind, symbol.enum)),
                            ("range", _e(symbol.range or "")),
                            ("unit", _e(symbol.unit or "")),
                            ("namespace", _e(symbol.namespace or "")),
                        )
                    ),
                    self.where(symbol.span),
                    self.doc(symbol.doc),
                ]
                if isinstance(symbol, ir.InputSymbol) and symbol.params:
                    lines.append(self.parameters(symbol.params))
                lines.append("<p>read by</p>" + self.places(refs.readers.get(symbol.name), "no option reads it"))
                if isinstance(symbol, ir.OutputSymbol):
                    lines.append(
                        "<p>written by</p>" + self.places(refs.writers.get(symbol.name), "no option writes it")
                    )
                parts.append(self._entry("s-" + symbol.name, kind, symbol.name, lines))
        return self.page("symbols.html", "symbols", "\n".join(parts))

    def enumerations_page(self) -> str:
        """Enumerations: elements, doc, the symbols and parameters of the type, the options using it."""
        self.base = ""
        program = self.program
        parts = [f"<h1>Enumerations ({len(program.enums)})</h1>"]
        typed: dict[str, list[str]] = {}
        symbols: list[ir.InputSymbol | ir.OutputSymbol] = [*program.inputs.values(), *program.outputs.values()]
        for symbol in symbols:
            if symbol.enum:
                typed.setdefault(symbol.enum, []).append(self.symbol_link(symbol.name))
        for behavior in program.behaviors.values():
            for p in behavior.params:
                if p.enum:
                    typed.setdefault(p.enum, []).append(
                        self.link(self.site.behavior(behavior.name), behavior.name) + f" @{_e(p.short_name)}"
                    )
        for option in program.options.values():
            for p in option.params:
                if p.enum:
                    href = self.site.option(option.name) + f"#param-{fragment(p.short_name)}"
                    typed.setdefault(p.enum, []).append(self.link(href, f"{option.name} @{p.short_name}"))
        for enum in program.enums.values():
            elements = ", ".join(f"<code>{_e(e.removeprefix(enum.name + '.'))}</code>" for e in enum.elements)
            lines = [
                self._facts((("elements", elements), ("internal", "yes" if enum.internal else ""))),
                self.where(enum.span),
                self.doc(enum.doc),
                "<p>type of " + (", ".join(typed[enum.name]) if enum.name in typed else "nothing declared") + "</p>",
                "<p>elements used by</p>" + self.places(self.refs.enum_users.get(enum.name), "no option"),
            ]
            parts.append(self._entry("e-" + enum.name, "enum", enum.name, lines))
        return self.page("enumerations.html", "enumerations", "\n".join(parts))

    def constants_page(self) -> str:
        """Constants: value, unit, doc, the options using them."""
        self.base = ""
        program = self.program
        parts = [f"<h1>Constants ({len(program.constants)})</h1>"]
        for constant in program.constants.values():
            lines = [
                self._facts(
                    (
                        ("value", f"<code>{_e(constant.text)}</code>"),
                        ("unit", _e(constant.unit or "")),
                        ("namespace", _e(constant.namespace or "")),
                    )
                ),
                self.where(constant.span),
                self.doc(constant.doc),
                "<p>used by</p>" + self.places(self.refs.constant_users.get(constant.name), "no option uses it"),
            ]
            parts.append(self._entry("c-" + constant.name, "const", constant.name, lines))
        return self.page("constants.html", "constants", "\n".join(parts))

    def behaviors_page(self) -> str:
        """Basic behaviors: parameters, doc, the states that run them."""
        self.base = ""
        program = self.program
        parts = [f"<h1>Basic behaviors ({len(program.behaviors)})</h1>"]
        for behavior in program.behaviors.values():
            lines = [
                self._facts((("namespace", _e(behavior.namespace or "")),)),
                self.where(behavior.span),
                self.doc(behavior.doc),
                self.parameters(behavior.params),
                "<p>run by</p>" + self.places(self.refs.behavior_callers.get(behavior.name), "no option runs it"),
            ]
            parts.append(self._entry("b-" + behavior.name, "basic behavior", behavior.name, lines))
        return self.page("behaviors.html", "basic behaviors", "\n".join(parts))

    def search_index(self) -> list[tuple[str, str, str, str]]:
        """``(name, kind, href from the root, summary)`` of everything the search box finds."""
        program, site = self.program, self.site
        rows: list[tuple[str, str, str, str]] = []
        rows += [(a.name, "agent", site.agent(a.name), a.title) for a in program.agents]
        rows += [(o.name, "option", site.option(o.name), summary(o.doc)) for o in program.options.values()]
        for option in program.options.values():
            rows += [(f"{option.name}.{s.name}", "state", site.option(option.name, s.name), "") for s in option.states]
        rows += [(s.name, "input symbol", site.symbol(s.name), summary(s.doc)) for s in program.inputs.values()]
        rows += [
            (s.name, "internal symbol" if s.internal else "output symbol", site.symbol(s.name), summary(s.doc))
            for s in program.outputs.values()
        ]
        rows += [(e.name, "enum", site.enum(e.name), summary(e.doc)) for e in program.enums.values()]
        rows += [(c.name, "const", site.constant(c.name), summary(c.doc)) for c in program.constants.values()]
        rows += [(b.name, "basic behavior", site.behavior(b.name), summary(b.doc)) for b in program.behaviors.values()]
        return rows
