"""The XABSL language server: the Language Server Protocol (pygls 2, lsprotocol) over :mod:`xabsl_studio.lsp.project`.

Every answer comes from the compiler's data held by a :class:`~xabsl_studio.lsp.project.Project`: its
diagnostics (with "did you mean" hints offered as quick fixes), its symbol table (completion,
hover), its tokens (completion context, semantic tokens) and the name index built from the AST
and the checker's resolutions (definition, references, rename, symbols).

A document belongs to the behavior set of the nearest ``agents.xabsl`` above it that includes
it (or the agents file given with ``--agents`` / the ``agents`` initialization option); a file
outside every such set is compiled on its own.

The server reads only what :mod:`xabsl_studio.lsp.access` allows (the allowed roots, regular ``.xabsl``
files, a size bound) and the texts the client sent; a request about a document that is neither
is refused with "invalid params". :mod:`xabsl_studio.lsp.rpc` answers every request, malformed or not,
without a traceback.
"""

from __future__ import annotations

import os
import re
import sys
from bisect import bisect_left
from collections import Counter
from collections.abc import Iterable
from typing import BinaryIO
from urllib.parse import unquote

from lsprotocol import types as lsp
from pygls.exceptions import JsonRpcException, JsonRpcInvalidParams, JsonRpcInvalidRequest
from pygls.io_ import StdoutWriter
from pygls.lsp.server import LanguageServer
from pygls.uris import from_fs_path, to_fs_path

from xabsl_studio.engine import ir
from xabsl_studio.engine.lang import ast, deep_recursion
from xabsl_studio.engine.lang.diagnostics import Diagnostic, Diagnostics, Severity
from xabsl_studio.engine.lang.tokens import KEYWORDS, Token, TokenType, decode_source, tokenize
from xabsl_studio.engine.types import Kind, Span
from xabsl_studio.lsp.access import FileAccess
from xabsl_studio.lsp.project import Analysis, Key, Occurrence, Project, SourceState
from xabsl_studio.lsp.rpc import XabslProtocol, handle_text
from xabsl_studio.server.protocol.limits import MAX_LSP_MESSAGE_BYTES

AGENTS_FILE = "agents.xabsl"
VALUE_KEYWORDS = ("true", "false", "state_time", "option_time", "action_done", "conflict")
_IDENTIFIER = re.compile(r"@?[A-Za-z_][A-Za-z0-9_.]*")
_HINTS = (re.compile(r"\(did you mean '([^']+)'\?\)"), re.compile(r"\(write '([^']+)'\)"))

TOKEN_TYPES = [
    "keyword",
    "number",
    "string",
    "comment",
    "operator",
    "enum",
    "enumMember",
    "variable",
    "parameter",
    "function",
    "class",
    "event",
    "namespace",
]
TOKEN_MODIFIERS = ["declaration", "readonly"]
_KEY_TOKEN = {
    "enum": "enum",
    "element": "enumMember",
    "input": "variable",
    "output": "variable",
    "constant": "variable",
    "param": "parameter",
    "behavior": "function",
    "option": "class",
    "state": "event",
    "agent": "namespace",
    "namespace": "namespace",
}
_WHAT = {
    "enum": "enumeration",
    "element": "enum element",
    "input": "input symbol",
    "output": "output symbol",
    "constant": "constant",
    "param": "parameter",
    "behavior": "basic behavior",
    "option": "option",
    "state": "state",
    "agent": "agent",
    "namespace": "namespace",
}


def _agents_files(folder: str, access: FileAccess) -> list[str]:
    """The agents files of ``folder``: ``agents.xabsl`` first, then other files declaring agents.

    Only a folder inside the allowed roots is looked through, and only regular files there are read.
    """
    found: list[str] = []
    names = access.names(folder)
    if AGENTS_FILE in names and access.is_file(os.path.join(folder, AGENTS_FILE)):
        found.append(os.path.realpath(os.path.join(folder, AGENTS_FILE)))
    for name in names:
        if not name.endswith(".xabsl") or name == AGENTS_FILE:
            continue
        path = os.path.join(folder, name)
        try:
            text = decode_source(access.read(path))
        except OSError:
            continue
        if "agent" in text and any(t.is_kw("agent") for t in tokenize(text, name, Diagnostics())):
            found.append(os.path.realpath(path))
    return found


def type_text(kind: Kind, enum: str | None) -> str:
    """How XABSL writes a type: ``float``, ``bool``, ``enum name``."""
    return {Kind.DECIMAL: "float", Kind.BOOLEAN: "bool"}.get(kind, f"enum {enum}")


def _facts(range_: str | None, unit: str | None) -> str:
    """A range and a unit as XABSL writes them: ``[0..10] "mm"``."""
    return " ".join(x for x in (f"[{range_}]" if range_ else "", f'"{unit}"' if unit else "") if x)


def _param_line(p: ir.Parameter) -> str:
    facts = _facts(p.range, p.unit)
    doc = f" — {p.doc}" if p.doc else ""
    return f"- `{type_text(p.kind, p.enum)} {p.short_name}`{' ' + facts if facts else ''}{doc}"


def document_path(uri: object) -> str:
    """The real path a document URI names (percent-decoded, links resolved).

    Raises:
        JsonRpcInvalidParams: not a ``file:`` URI, or one with a NUL byte.
    """
    path = to_fs_path(uri) if isinstance(uri, str) else None
    if path is None:
        raise JsonRpcInvalidParams(f"{_short(uri)} is no file: URI")
    path = unquote(path)
    if "\0" in path:
        raise JsonRpcInvalidParams("a document URI with a NUL byte")
    return os.path.realpath(path)


def _short(text: object) -> str:
    """A client's value for an error message, cut to a readable length."""
    shown = repr(text) if not isinstance(text, str) else text
    return shown if len(shown) <= 200 else shown[:200] + "..."


class XabslLanguageServer(LanguageServer):
    """pygls' language server holding the behavior sets (projects) the editor has open."""

    protocol: XabslProtocol

    def __init__(self, agents: str | None = None, root: str | None = None, access: FileAccess | None = None) -> None:
        super().__init__(
            "xabsl-lsp",
            "0.1.0",
            text_document_sync_kind=lsp.TextDocumentSyncKind.Incremental,
            protocol_cls=XabslProtocol,
        )
        self.fixed_agents = os.path.realpath(agents) if agents else None
        #: the behavior folder a browser client builds its document URIs on (``xabsl/root``)
        self.root = os.path.realpath(root) if root else None
        #: what the server may read (lsp/access.py)
        self.access = access or FileAccess(
            [os.path.dirname(self.fixed_agents)] if self.fixed_agents else [], client_roots=True
        )
        #: the real paths of the documents the client has open (their text is the client's)
        self.opened: set[str] = set()
        self.projects: dict[str, Project] = {}
        #: files compiled on their own (no agents file includes them), asked again on each change
        self.standalone: set[str] = set()
        self.published: dict[str, list[lsp.Diagnostic]] = {}
        #: the compiler's diagnostics last published per uri (converting all files per keystroke is costly)
        self.raw: dict[str, tuple[int, list[Diagnostic]]] = {}

    # ------------------------------------------------------------------ projects

    @property
    def encoding(self) -> str:
        """The negotiated position encoding: "utf-16" (LSP's default), "utf-8" or "utf-32"."""
        chosen = self.workspace.position_encoding
        # an lsprotocol enum member; its str() is its name, its value the protocol's spelling
        value = getattr(chosen, "value", chosen) or "utf-16"
        return str(value)

    def agents_for(self, path: str) -> str:
        """The agents file whose behavior set ``path`` belongs to.

        The first behavior set already open that includes it; else the nearest agents file
        above it that includes it (``agents.xabsl``, or another file there that declares
        agents); else the file alone.
        """
        real = os.path.realpath(path)
        if self.fixed_agents:
            return self.fixed_agents
        for agents, project in self.projects.items():
            if agents not in self.standalone and (real == agents or real in project.analyze().by_real):
                return agents
        folder = os.path.dirname(real)
        while True:
            for candidate in _agents_files(folder, self.access):
                if candidate == real or real in self.project(candidate).analyze().by_real:
                    return candidate
            parent = os.path.dirname(folder)
            if parent == folder:
                self.standalone.add(real)
                return real
            folder = parent

    def project(self, agents: str) -> Project:
        """The project of an agents file, made on first use."""
        if agents not in self.projects:
            self.projects[agents] = Project(agents, access=self.access)
        return self.projects[agents]

    def project_of(self, uri: str, opening: bool = False) -> tuple[Project, str]:
        """The project a document belongs to, and the document's real path.

        Raises:
            JsonRpcInvalidParams: no file URI, or a document that is neither open (``opening``:
                being opened) nor one the server may read.
        """
        real = document_path(uri)
        if not (opening or real in self.opened or self.access.allows(real)):
            raise JsonRpcInvalidParams(f"{_short(uri)} is not open and outside the behavior folders served here")
        return self.project(self.agents_for(real)), real

    def client_folders(self) -> None:
        """Take the client's workspace folders and ``rootUri`` as allowed roots (``xabsl lsp`` only)."""
        uris = [f.uri for f in self.workspace.folders.values()]
        if self.workspace.root_uri:
            uris.append(self.workspace.root_uri)
        paths = []
        for u in uris:
            path = to_fs_path(u)
            if path is not None:
                paths.append(unquote(path))
        self.access.grant(paths)

    # ------------------------------------------------------------------ conversions

    def range_of(self, state: SourceState, start: int, end: int) -> lsp.Range:
        """An LSP range for the offsets ``start``..``end`` of a source."""
        a = state.lines.position(start, self.encoding)
        b = state.lines.position(end, self.encoding)
        return lsp.Range(lsp.Position(*a), lsp.Position(*b))

    def location(self, analysis: Analysis, real: str, start: int, end: int) -> lsp.Location:
        """An LSP location for the offsets ``start``..``end`` of file ``real``."""
        return lsp.Location(from_fs_path(real) or real, self.range_of(analysis.by_real[real], start, end))

    def offset_of(self, state: SourceState, position: lsp.Position) -> int:
        """The text offset of an LSP position in a source."""
        return state.lines.offset(position.line, position.character, self.encoding)

    def diagnostic(self, analysis: Analysis, state: SourceState, d: Diagnostic) -> lsp.Diagnostic:
        """A compiler diagnostic as an LSP diagnostic, with its related places."""
        span = d.span
        start, end = (span.start, span.end) if span else (0, 0)
        related = []
        for message, where in d.related:
            other = analysis.by_shown.get(where.file)
            if other is not None:
                related.append(
                    lsp.DiagnosticRelatedInformation(
                        self.location(analysis, other.real, where.start, where.end), message
                    )
                )
        fix = next((m.group(1) for pattern in _HINTS if (m := pattern.search(d.message))), None)
        data: dict[str, str] = {"original_code": d.original_code} if d.original_code else {}
        if fix is not None:
            data["replacement"] = fix
        return lsp.Diagnostic(
            range=self.range_of(state, start, end),
            message=d.message,
            severity=lsp.DiagnosticSeverity.Error if d.severity is Severity.ERROR else lsp.DiagnosticSeverity.Warning,
            code=d.code,
            source="xabsl",
            related_information=related or None,
            tags=[lsp.DiagnosticTag.Unnecessary] if d.code.startswith(("unused-", "unreachable-")) else None,
            data=data or None,
        )

    def publish(self, project: Project, edited: str | None = None) -> Analysis:
        """Analyze ``project`` and publish what changed (a file that is fixed gets an empty list).

        The ``edited`` file (a real path) always gets its diagnostics, changed or not: the
        editor learns that its latest text was checked.
        """
        analysis = project.analyze()
        for state in analysis.files:
            uri = from_fs_path(state.real) or state.real
            raw = analysis.diagnostics.get(state.real, [])
            if state.real != edited and self.raw.get(uri) == (state.serial, raw):
                continue
            self.raw[uri] = (state.serial, raw)
            items = [self.diagnostic(analysis, state, d) for d in raw]
            if self.published.get(uri) != items or state.real == edited:
                self.published[uri] = items
                self.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(uri=uri, diagnostics=items))
        for uri in [u for u in self.published if (to_fs_path(u) or u) not in analysis.by_real]:
            if not any(os.path.realpath(to_fs_path(uri) or uri) in p.analyze().by_real for p in self.projects.values()):
                del self.published[uri]
                self.raw.pop(uri, None)
                self.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(uri=uri, diagnostics=[]))
        return analysis

    # ------------------------------------------------------------------ describing names

    def describe(self, analysis: Analysis, key: Key) -> str:
        """Markdown for a hover or a completion item's documentation."""
        table = analysis.table
        kind, name = key[0], key[1]
        lines: list[str] = []
        if kind == "input" and name in table.inputs:
            s = table.inputs[name]
            lines.append(f"**input symbol** `{type_text(s.kind, s.enum)} {name}` {_facts(s.range, s.unit)}".rstrip())
            lines += [_param_line(p) for p in s.params]
            doc = s.doc
        elif kind == "output" and name in table.outputs:
            o = table.outputs[name]
            what = "internal symbol" if o.internal else "output symbol"
            lines.append(f"**{what}** `{type_text(o.kind, o.enum)} {name}` {_facts(o.range, o.unit)}".rstrip())
            doc = o.doc
        elif kind == "constant" and name in table.constants:
            c = table.constants[name]
            lines.append(f"**constant** `{name} = {c.text}` {c.unit or ''}".rstrip())
            doc = c.doc
        elif kind == "enum" and name in table.enums:
            e = table.enums[name]
            lines.append(f"**enumeration** `{name}`{' (internal)' if e.internal else ''}: " + ", ".join(e.elements))
            doc = e.doc
        elif kind == "element":
            enum = table.elements.get(name, "")
            lines.append(f"**enum element** `{name}` of enumeration `{enum}`")
            doc = table.enums[enum].doc if enum in table.enums else None
        elif kind == "behavior" and name in table.behaviors:
            b = table.behaviors[name]
            lines.append(f"**basic behavior** `{name}`")
            lines += [_param_line(p) for p in b.params]
            doc = b.doc
        elif kind == "option" and name in table.options:
            header = table.options[name]
            lines.append(f"**option** `{name}`")
            lines += [_param_line(p) for p in header.params.values()]
            states = [
                s.name.text + (" (initial)" if s.initial else "") + (" (target)" if s.target else "")
                for s in header.decl.states
            ]
            lines.append("states: " + ", ".join(states))
            doc = header.decl.doc
        elif kind == "param":
            param = self.parameter(analysis, key)
            if param is None:
                return f"**parameter** `{key[3]}`"
            lines.append(
                f"**parameter** of {_WHAT[key[1]]} `{key[2]}`: "
                f"`{type_text(param.kind, param.enum)} {param.short_name}` "
                f"{_facts(param.range, param.unit)}".rstrip()
            )
            doc = param.doc
        elif kind == "state":
            owner = table.options.get(name)
            decl = next((s for s in owner.decl.states if s.name.text == key[2]), None) if owner else None
            flags = [f for f, on in (("initial", decl and decl.initial), ("target", decl and decl.target)) if on]
            lines.append(f"**state** `{key[2]}` of option `{name}`" + (f" ({', '.join(flags)})" if flags else ""))
            doc = None
        elif kind == "agent":
            agent = next((a for a in table.agents if a.name.text == name), None)
            lines.append(f"**agent** `{name}`" + (f' "{agent.title}" → option `{agent.root.text}`' if agent else ""))
            doc = agent.doc if agent else None
        else:
            lines.append(f"**{_WHAT.get(kind, kind)}** `{name}`")
            doc = None
        if doc:
            lines += ["", doc]
        return "\n".join(lines)

    @staticmethod
    def parameter(analysis: Analysis, key: Key) -> ir.Parameter | None:
        """The IR parameter a name key stands for (of an option, input symbol or basic behavior)."""
        table = analysis.table
        _, klass, owner, short = key
        params: Iterable[ir.Parameter] = ()
        if klass == "option" and owner in table.options:
            params = table.options[owner].params.values()
        elif klass == "behavior" and owner in table.behaviors:
            params = table.behaviors[owner].params
        elif klass == "input" and owner in table.inputs:
            params = table.inputs[owner].params
        return next((p for p in params if p.short_name == short), None)


def create_server(
    agents: str | None = None, root: str | None = None, roots: Iterable[str] | None = None
) -> XabslLanguageServer:
    """A language server with every feature registered (one per connection).

    Args:
        agents: the agents file of every document (``--agents``); its folder is served.
        root: the folder ``xabsl/root`` answers (the studio's example folder).
        roots: the only folders served (the studio's behavior folders); None: the client's
            workspace folders are served too (``xabsl lsp``, the user's own editor).
    """
    if roots is None:
        access = FileAccess([os.path.dirname(os.path.realpath(agents))] if agents else [], client_roots=True)
    else:
        access = FileAccess(roots)
    server = XabslLanguageServer(agents, root, access)

    @server.feature("xabsl/root")
    def root_uri(ls: XabslLanguageServer, params: object) -> dict[str, str | None]:
        """The behavior folder's URI: a browser client knows its files by paths relative to it."""
        folder = ls.root or (to_fs_path(ls.workspace.root_uri) if ls.workspace.root_uri else None)
        return {"uri": from_fs_path(folder) if folder else None}

    @server.feature(lsp.INITIALIZE)
    def initialize(ls: XabslLanguageServer, params: lsp.InitializeParams) -> None:
        ls.client_folders()
        options = params.initialization_options
        if isinstance(options, dict) and options.get("agents") is not None:
            agents = options["agents"]
            if not isinstance(agents, str) or not agents or "\0" in agents:
                raise JsonRpcInvalidParams("initializationOptions.agents: the path of an agents file")
            real = os.path.realpath(agents)
            ls.access.add(os.path.dirname(real))  # xabsl lsp: the user's editor names its agents file
            if not ls.access.allows(real):
                raise JsonRpcInvalidParams(
                    f"initializationOptions.agents: {_short(agents)} is outside the behavior folders served here"
                )
            ls.fixed_agents = real

    @server.feature(lsp.WORKSPACE_DID_CHANGE_WORKSPACE_FOLDERS)
    def folders_changed(ls: XabslLanguageServer, params: lsp.DidChangeWorkspaceFoldersParams) -> None:
        ls.client_folders()

    def changed(ls: XabslLanguageServer, uri: str) -> None:
        # pygls keeps the documents the client opened; a change to another one has no text
        document = ls.workspace.text_documents.get(unquote(uri))
        if document is None:
            return
        project, real = ls.project_of(uri, opening=True)
        ls.opened.add(real)
        project.set_text(real, document.source)
        ls.publish(project, real)

    @server.feature(lsp.TEXT_DOCUMENT_DID_OPEN)
    def did_open(ls: XabslLanguageServer, params: lsp.DidOpenTextDocumentParams) -> None:
        changed(ls, params.text_document.uri)

    @server.feature(lsp.TEXT_DOCUMENT_DID_CHANGE)
    def did_change(ls: XabslLanguageServer, params: lsp.DidChangeTextDocumentParams) -> None:
        changed(ls, params.text_document.uri)

    @server.feature(lsp.TEXT_DOCUMENT_DID_SAVE)
    def did_save(ls: XabslLanguageServer, params: lsp.DidSaveTextDocumentParams) -> None:
        project, _ = ls.project_of(params.text_document.uri)
        project.disk_changed()
        ls.publish(project)

    @server.feature(lsp.TEXT_DOCUMENT_DID_CLOSE)
    def did_close(ls: XabslLanguageServer, params: lsp.DidCloseTextDocumentParams) -> None:
        real = document_path(params.text_document.uri)
        if real not in ls.opened:
            return
        project, _ = ls.project_of(params.text_document.uri)
        ls.opened.discard(real)
        project.close(real)
        ls.publish(project)

    @server.feature(lsp.WORKSPACE_DID_CHANGE_WATCHED_FILES)
    def watched(ls: XabslLanguageServer, params: lsp.DidChangeWatchedFilesParams) -> None:
        for project in ls.projects.values():
            project.disk_changed()
            ls.publish(project)

    def at(
        ls: XabslLanguageServer, doc: lsp.TextDocumentIdentifier, position: lsp.Position
    ) -> tuple[Analysis, SourceState, int] | None:
        project, real = ls.project_of(doc.uri)
        analysis = project.analyze()
        state = analysis.by_real.get(real)
        if state is None:
            return None
        return analysis, state, ls.offset_of(state, position)

    def name_at(
        ls: XabslLanguageServer, doc: lsp.TextDocumentIdentifier, position: lsp.Position
    ) -> tuple[Analysis, SourceState, Occurrence] | None:
        """The name occurrence under the cursor, with its analysis and source (None: no name there)."""
        found = at(ls, doc, position)
        if found is None:
            return None
        analysis, state, offset = found
        occurrence = analysis.occurrence_at(state.real, offset)
        return None if occurrence is None else (analysis, state, occurrence)

    @server.feature(lsp.TEXT_DOCUMENT_HOVER)
    def hover(ls: XabslLanguageServer, params: lsp.HoverParams) -> lsp.Hover | None:
        named = name_at(ls, params.text_document, params.position)
        if named is None:
            return None
        analysis, state, occurrence = named
        return lsp.Hover(
            contents=lsp.MarkupContent(lsp.MarkupKind.Markdown, ls.describe(analysis, occurrence.key)),
            range=ls.range_of(state, occurrence.start, occurrence.end),
        )

    @server.feature(lsp.TEXT_DOCUMENT_DEFINITION)
    def definition(ls: XabslLanguageServer, params: lsp.DefinitionParams) -> list[lsp.Location] | None:
        named = name_at(ls, params.text_document, params.position)
        if named is None:
            return None
        analysis, _state, occurrence = named
        if occurrence.key not in analysis.declarations:
            return None
        real, declared = analysis.declarations[occurrence.key]
        return [ls.location(analysis, real, declared.start, declared.end)]

    @server.feature(lsp.TEXT_DOCUMENT_REFERENCES)
    def references(ls: XabslLanguageServer, params: lsp.ReferenceParams) -> list[lsp.Location] | None:
        named = name_at(ls, params.text_document, params.position)
        if named is None:
            return None
        analysis, _state, occurrence = named
        return [
            ls.location(analysis, real, o.start, o.end)
            for real, o in analysis.references(occurrence.key)
            if params.context.include_declaration or not o.declaration
        ]

    @server.feature(lsp.TEXT_DOCUMENT_PREPARE_RENAME)
    def prepare_rename(ls: XabslLanguageServer, params: lsp.PrepareRenameParams) -> lsp.PrepareRenamePlaceholder | None:
        named = name_at(ls, params.text_document, params.position)
        if named is None:
            return None
        analysis, state, occurrence = named
        if occurrence.key[0] in ("namespace",) or occurrence.key not in analysis.declarations:
            return None
        return lsp.PrepareRenamePlaceholder(ls.range_of(state, occurrence.start, occurrence.end), occurrence.text)

    @server.feature(lsp.TEXT_DOCUMENT_RENAME)
    def rename(ls: XabslLanguageServer, params: lsp.RenameParams) -> lsp.WorkspaceEdit | None:
        named = name_at(ls, params.text_document, params.position)
        if named is None:
            return None
        analysis, _state, occurrence = named
        if occurrence.key not in analysis.declarations:
            return None
        new = params.new_name.strip()
        bare = new[1:] if new.startswith("@") else new
        if not _IDENTIFIER.fullmatch(new) or bare in KEYWORDS or (new.startswith("@") and occurrence.key[0] != "param"):
            raise JsonRpcInvalidParams(f"'{_short(params.new_name)}' is no valid XABSL name")
        key = occurrence.key
        enum = analysis.table.elements.get(key[1]) if key[0] == "element" else None
        edits = [(real, o, _renamed(key, o, bare, enum)) for real, o in analysis.references(key)]
        # names qualified by the renamed one: 'Enum.element', 'option.parameter'
        edits += list(_qualified_by(analysis, key, bare))
        project, _ = ls.project_of(params.text_document.uri)
        clash = _breaks(project, analysis, edits)
        if clash is not None:
            raise JsonRpcException(
                f"cannot rename '{occurrence.text}' to '{new}': {clash}", code=lsp.LSPErrorCodes.RequestFailed
            )
        changes: dict[str, list[lsp.TextEdit]] = {}
        for real, o, text in edits:
            uri = from_fs_path(real) or real
            changes.setdefault(uri, []).append(lsp.TextEdit(ls.range_of(analysis.by_real[real], o.start, o.end), text))
        if key[0] == "option" and _can_rename_files(ls):
            moved = _option_file_rename(ls, analysis, key[1], bare, changes)
            if moved is not None:
                return moved
        return lsp.WorkspaceEdit(changes=changes)

    @server.feature(lsp.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
    def document_symbols(ls: XabslLanguageServer, params: lsp.DocumentSymbolParams) -> list[lsp.DocumentSymbol]:
        project, real = ls.project_of(params.text_document.uri)
        analysis = project.analyze()
        state = analysis.by_real.get(real)
        return _outline(ls, state) if state else []

    @server.feature(lsp.WORKSPACE_SYMBOL)
    def workspace_symbols(ls: XabslLanguageServer, params: lsp.WorkspaceSymbolParams) -> list[lsp.SymbolInformation]:
        query = params.query.lower()
        out: list[lsp.SymbolInformation] = []
        seen: set[tuple[str, int]] = set()
        for project in ls.projects.values():
            analysis = project.analyze()
            for key, (real, o) in analysis.declarations.items():
                name = o.text if key[0] != "element" else key[1]
                if query not in name.lower() or (real, o.start) in seen:
                    continue
                seen.add((real, o.start))
                container = key[2] if key[0] in ("param", "state") else None
                out.append(
                    lsp.SymbolInformation(
                        name=name,
                        kind=_SYMBOL_KIND[key[0]],
                        location=ls.location(analysis, real, o.start, o.end),
                        container_name=container,
                    )
                )
        return out

    @server.feature(
        lsp.TEXT_DOCUMENT_SEMANTIC_TOKENS_FULL,
        lsp.SemanticTokensLegend(token_types=TOKEN_TYPES, token_modifiers=TOKEN_MODIFIERS),
    )
    def semantic_tokens(ls: XabslLanguageServer, params: lsp.SemanticTokensParams) -> lsp.SemanticTokens:
        project, real = ls.project_of(params.text_document.uri)
        analysis = project.analyze()
        state = analysis.by_real.get(real)
        return lsp.SemanticTokens(data=_semantic(ls, analysis, state) if state else [])

    @server.feature(lsp.TEXT_DOCUMENT_FOLDING_RANGE)
    def folding(ls: XabslLanguageServer, params: lsp.FoldingRangeParams) -> list[lsp.FoldingRange]:
        project, real = ls.project_of(params.text_document.uri)
        state = project.analyze().by_real.get(real)
        with deep_recursion():  # long 'else if' chains nest
            return _folds(state) if state else []

    @server.feature(
        lsp.TEXT_DOCUMENT_CODE_ACTION, lsp.CodeActionOptions(code_action_kinds=[lsp.CodeActionKind.QuickFix])
    )
    def code_actions(ls: XabslLanguageServer, params: lsp.CodeActionParams) -> list[lsp.CodeAction]:
        out = []
        for d in params.context.diagnostics:
            replacement = d.data.get("replacement") if isinstance(d.data, dict) else None
            if d.source != "xabsl" or not isinstance(replacement, str):
                continue
            out.append(
                lsp.CodeAction(
                    title=f"Change to '{replacement}'",
                    kind=lsp.CodeActionKind.QuickFix,
                    diagnostics=[d],
                    is_preferred=True,
                    edit=lsp.WorkspaceEdit(changes={params.text_document.uri: [lsp.TextEdit(d.range, replacement)]}),
                )
            )
        return out

    @server.feature(
        lsp.TEXT_DOCUMENT_COMPLETION,
        lsp.CompletionOptions(trigger_characters=["@", ".", "(", ",", " ", "="], resolve_provider=True),
    )
    def completion(ls: XabslLanguageServer, params: lsp.CompletionParams) -> lsp.CompletionList | None:
        found = at(ls, params.text_document, params.position)
        if found is None:
            return None
        analysis, state, offset = found
        project, _ = ls.project_of(params.text_document.uri)
        items = _complete(ls, project, analysis, state, offset)
        uri = params.text_document.uri
        for i in items:
            if i.data is not None:
                key = tuple(i.data)
                i.data = {"uri": uri, "key": i.data}
                if len(items) <= EAGER_DOCUMENTATION:
                    i.documentation = lsp.MarkupContent(lsp.MarkupKind.Markdown, ls.describe(analysis, key))
        return lsp.CompletionList(is_incomplete=False, items=items)

    @server.feature(lsp.COMPLETION_ITEM_RESOLVE)
    def resolve(ls: XabslLanguageServer, item: lsp.CompletionItem) -> lsp.CompletionItem:
        data = item.data
        if isinstance(data, dict) and isinstance(data.get("uri"), str) and isinstance(data.get("key"), list):
            try:
                project, _ = ls.project_of(data["uri"])
            except JsonRpcInvalidParams:
                return item  # an item of a document not served here: nothing to add
            key = tuple(str(k) for k in data["key"])
            item.documentation = lsp.MarkupContent(lsp.MarkupKind.Markdown, ls.describe(project.analyze(), key))
        return item

    return server


_SYMBOL_KIND = {
    "enum": lsp.SymbolKind.Enum,
    "element": lsp.SymbolKind.EnumMember,
    "input": lsp.SymbolKind.Variable,
    "output": lsp.SymbolKind.Variable,
    "constant": lsp.SymbolKind.Constant,
    "param": lsp.SymbolKind.TypeParameter,
    "behavior": lsp.SymbolKind.Function,
    "option": lsp.SymbolKind.Class,
    "state": lsp.SymbolKind.Event,
    "agent": lsp.SymbolKind.Object,
    "namespace": lsp.SymbolKind.Namespace,
}


def _can_rename_files(ls: XabslLanguageServer) -> bool:
    workspace = ls.client_capabilities.workspace
    edit = workspace.workspace_edit if workspace else None
    operations = (edit.resource_operations or []) if edit else []
    return bool(edit and edit.document_changes and lsp.ResourceOperationKind.Rename in operations)


def _option_file_rename(
    ls: XabslLanguageServer, analysis: Analysis, old: str, new: str, changes: dict[str, list[lsp.TextEdit]]
) -> lsp.WorkspaceEdit | None:
    """The rename of an option whose file is named like it: the file follows, and the includes.

    An option named differently from its file draws a ``naming`` warning, so renaming the
    option alone would add one. None when the file is named otherwise or the new name is taken.
    """
    real = analysis.declarations[("option", old)][0]
    folder, name = os.path.split(real)
    stem, extension = os.path.splitext(name)
    target = os.path.join(folder, new + extension)
    if stem != old or os.path.exists(target):
        return None
    edits = {uri: list(e) for uri, e in changes.items()}
    for f in analysis.files:
        strings = [t for t in f.tokens if t.type is TokenType.STRING]
        for include in f.tree.includes:
            if os.path.realpath(os.path.join(os.path.dirname(f.real), include.path)) != real:
                continue
            if os.path.basename(include.path) != name:
                continue  # reached through a link of another name: leave it
            token = next((t for t in strings if include.span.start <= t.span.start < include.span.end), None)
            if token is None:
                continue
            renamed = include.path[: len(include.path) - len(name)] + new + extension
            uri = from_fs_path(f.real) or f.real
            edits.setdefault(uri, []).append(
                lsp.TextEdit(ls.range_of(f, token.span.start, token.span.end), f'"{renamed}"')
            )
    document_changes: list[lsp.TextDocumentEdit | lsp.CreateFile | lsp.RenameFile | lsp.DeleteFile] = [
        lsp.TextDocumentEdit(lsp.OptionalVersionedTextDocumentIdentifier(uri=uri, version=None), list(e))
        for uri, e in edits.items()
    ]
    document_changes.append(lsp.RenameFile(old_uri=from_fs_path(real) or real, new_uri=from_fs_path(target) or target))
    return lsp.WorkspaceEdit(document_changes=document_changes)


def _breaks(project: Project, analysis: Analysis, edits: list[tuple[str, Occurrence, str]]) -> str | None:
    """The first error a rename would add to the behavior set (a name already in use...), or None.

    The edited texts are checked as the compiler checks them, in a scratch project beside the
    open one: whatever the compiler calls a clash (two options, states or parameters of one
    name; an option named like a basic behavior...) refuses the rename.
    """
    texts: dict[str, str] = {}
    for real in dict.fromkeys(real for real, _, _ in edits):
        text = analysis.by_real[real].text
        for _, o, new in sorted((e for e in edits if e[0] == real), key=lambda e: e[1].start, reverse=True):
            text = text[: o.start] + new + text[o.end :]
        texts[real] = text
    scratch = Project(project.agents, project.base, project.access)
    for real, text in {**project.overlays, **texts}.items():
        scratch.set_text(real, text)
    after = scratch.analyze()
    new_errors = Counter(d.code for d in after.all_diagnostics() if d.is_error) - Counter(
        d.code for d in analysis.all_diagnostics() if d.is_error
    )
    added = [d for d in after.all_diagnostics() if d.is_error and new_errors[d.code]]
    # the clash itself ("defined more than once") says more than what follows from it
    added.sort(key=lambda d: d.code != "duplicate-definition")
    return added[0].format() if added else None


def _qualified_by(analysis: Analysis, key: Key, new: str) -> Iterable[tuple[str, Occurrence, str]]:
    """Occurrences written with the renamed enumeration or option as their qualifier, rewritten."""
    if key[0] not in ("enum", "option"):
        return
    old = key[1]
    for f in analysis.files:
        for o in analysis.occurrences.get(f.real, []):
            k = o.key
            if key[0] == "enum" and k[0] == "element" and analysis.table.elements.get(k[1]) == old:
                if o.text == k[1] and o.text.startswith(old + "."):
                    yield f.real, o, new + o.text[len(old) :]
            elif key[0] == "option" and k[:3] == ("param", "option", old) and o.text == f"{old}.{k[3]}":
                yield f.real, o, f"{new}.{k[3]}"


def _renamed(key: Key, occurrence: Occurrence, new: str, enum: str | None) -> str:
    """The replacement text of one occurrence, keeping the form it was written in."""
    text = occurrence.text
    if key[0] == "param":
        if text.startswith("@"):
            return "@" + new
        owner = key[2] + "."
        return owner + new if text.startswith(owner) and text != key[3] else new
    if key[0] == "element" and text == key[1] and enum:
        return f"{enum}.{new}"
    return new


# ---------------------------------------------------------------------- outline and folding


def _outline(ls: XabslLanguageServer, state: SourceState) -> list[lsp.DocumentSymbol]:
    def symbol(
        name: str,
        kind: lsp.SymbolKind,
        whole: Span,
        at: Span,
        detail: str | None = None,
        children: list[lsp.DocumentSymbol] | None = None,
    ) -> lsp.DocumentSymbol:
        return lsp.DocumentSymbol(
            name=name,
            kind=kind,
            range=ls.range_of(state, whole.start, max(whole.end, at.end)),
            selection_range=ls.range_of(state, at.start, at.end),
            detail=detail,
            children=children,
        )

    def params(decls: list[ast.ParamDecl]) -> list[lsp.DocumentSymbol]:
        return [symbol(p.name.text, lsp.SymbolKind.TypeParameter, p.span, p.name.span, _type_of(p.type)) for p in decls]

    tree = state.tree
    out: list[lsp.DocumentSymbol] = []
    if tree.namespace is not None:
        ns = tree.namespace
        items: list[lsp.DocumentSymbol] = []
        for item in ns.items:
            if isinstance(item, ast.EnumDecl):
                elements = [symbol(e.text, lsp.SymbolKind.EnumMember, e.span, e.span) for e in item.elements]
                items.append(symbol(item.name.text, lsp.SymbolKind.Enum, item.span, item.name.span, "enum", elements))
            elif isinstance(item, ast.SymbolDecl):
                items.append(
                    symbol(
                        item.name.text,
                        lsp.SymbolKind.Variable,
                        item.span,
                        item.name.span,
                        f"{item.io} {_type_of(item.type)}",
                        params(item.params or []) or None,
                    )
                )
            elif isinstance(item, ast.ConstDecl):
                items.append(symbol(item.name.text, lsp.SymbolKind.Constant, item.span, item.name.span, "const"))
            else:
                items.append(
                    symbol(
                        item.name.text,
                        lsp.SymbolKind.Function,
                        item.span,
                        item.name.span,
                        "behavior",
                        params(item.params) or None,
                    )
                )
        out.append(symbol(ns.name.text, lsp.SymbolKind.Namespace, ns.span, ns.name.span, ns.title, items))
    if tree.option is not None:
        o = tree.option
        states = [
            symbol(s.name.text, lsp.SymbolKind.Event, s.span, s.name.span, "initial state" if s.initial else "state")
            for s in o.states
        ]
        out.append(symbol(o.name.text, lsp.SymbolKind.Class, o.span, o.name.span, "option", params(o.params) + states))
    for a in tree.agents:
        out.append(symbol(a.name.text, lsp.SymbolKind.Object, a.span, a.name.span, f"agent → {a.root.text}"))
    return out


def _type_of(t: ast.TypeRef) -> str:
    if t.kind == "enum" and t.enum is not None:
        return f"enum {t.enum.text}"
    return {"boolean": "bool"}.get(t.kind, "float")


def _folds(state: SourceState) -> list[lsp.FoldingRange]:
    spans: list[tuple[Span, lsp.FoldingRangeKind | None]] = []
    tree = state.tree

    def decision(node: ast.DTree | None) -> None:
        if isinstance(node, ast.IfElse):
            spans.append((node.span, None))
            decision(node.then)
            decision(node.otherwise)

    if tree.namespace is not None:
        spans.append((tree.namespace.span, None))
        for item in tree.namespace.items:
            spans.append((item.span, None))
    if tree.option is not None:
        spans.append((tree.option.span, None))
        if tree.option.common_decision is not None:
            spans.append((tree.option.common_decision.span, None))
            for branch in tree.option.common_decision.branches:
                decision(branch)
        for s in tree.option.states:
            spans.append((s.span, None))
            if s.decision_span is not None:
                spans.append((s.decision_span, None))
            decision(s.decision)
    for agent in tree.agents:
        spans.append((agent.span, None))
    for token in state.tokens:
        if token.type in (TokenType.DOC_COMMENT, TokenType.INITIAL_COMMENT):
            spans.append((token.span, lsp.FoldingRangeKind.Comment))
    out: dict[int, lsp.FoldingRange] = {}
    for span, kind in spans:
        start = span.line - 1
        # keep the closing line (a '}') visible
        end = span.end_line - 1 if kind is not None else span.end_line - 2
        if end > start and start not in out:
            out[start] = lsp.FoldingRange(start_line=start, end_line=end, kind=kind)
    return sorted(out.values(), key=lambda f: f.start_line)


# ---------------------------------------------------------------------- semantic tokens


def _semantic(ls: XabslLanguageServer, analysis: Analysis, state: SourceState) -> list[int]:
    occurrences = {o.start: o for o in analysis.occurrences.get(state.real, [])}
    data: list[int] = []
    last_line = 0
    last_char = 0

    def emit(start: int, end: int, kind: str, modifiers: int = 0) -> None:
        nonlocal last_line, last_char
        text = state.text
        # one token per line: not every client accepts multi-line tokens
        while start < end:
            newline = text.find("\n", start, end)
            stop = end if newline < 0 else newline
            if stop > start:
                line, char = state.lines.position(start, ls.encoding)
                _, end_char = state.lines.position(stop, ls.encoding)
                delta_line = line - last_line
                delta_char = char - last_char if delta_line == 0 else char
                data.extend((delta_line, delta_char, end_char - char, TOKEN_TYPES.index(kind), modifiers))
                last_line, last_char = line, char
            start = stop + 1 if newline >= 0 else end

    for token in state.tokens:
        t = token.type
        start, end = token.span.start, token.span.end
        if t is TokenType.KEYWORD:
            emit(start, end, "keyword")
        elif t is TokenType.NUMBER:
            emit(start, end, "number")
        elif t in (TokenType.STRING, TokenType.RANGE):
            emit(start, end, "string")
        elif t in (TokenType.DOC_COMMENT, TokenType.INITIAL_COMMENT):
            emit(start, end, "comment")
        elif t is TokenType.OPERATOR:
            emit(start, end, "operator")
        elif t is TokenType.IDENTIFIER:
            o = occurrences.get(start)
            if o is not None:
                modifiers = (1 if o.declaration else 0) | (2 if o.key[0] in ("constant", "input") else 0)
                emit(start, end, _KEY_TOKEN[o.key[0]], modifiers)
    return data


# ---------------------------------------------------------------------- completion


def _in_comment(text: str, tokens: list[Token], offset: int) -> bool:
    """Whether ``offset`` lies inside a comment, string or range (no completion there)."""
    starts = [t.span.start for t in tokens]
    index = bisect_left(starts, offset) - 1
    previous_end = 0
    if index >= 0:
        token = tokens[index]
        if token.span.start < offset < token.span.end and token.type in (
            TokenType.STRING,
            TokenType.RANGE,
            TokenType.DOC_COMMENT,
            TokenType.INITIAL_COMMENT,
        ):
            return True
        previous_end = token.span.end
    gap = text[previous_end:offset]
    if "//" in gap.rsplit("\n", 1)[-1]:
        return True
    return gap.rfind("/*") > gap.rfind("*/")


def _item(
    label: str,
    kind: lsp.CompletionItemKind,
    detail: str,
    key: Key | None,
    replace: lsp.Range,
    insert: str | None = None,
    sort: str = "5",
) -> lsp.CompletionItem:
    return lsp.CompletionItem(
        label=label,
        kind=kind,
        detail=detail,
        text_edit=lsp.TextEdit(replace, insert if insert is not None else label),
        filter_text=label,
        sort_text=f"{sort}{label.lower()}",
        # the documentation: filled in right away for short lists, else by completionItem/resolve
        data=list(key) if key else None,
    )


#: a completion list up to this long carries its documentation; longer ones get it on resolve
EAGER_DOCUMENTATION = 60


def _complete(
    ls: XabslLanguageServer, project: Project, analysis: Analysis, state: SourceState, offset: int
) -> list[lsp.CompletionItem]:
    text = state.text
    tokens = [t for t in state.tokens if t.type is not TokenType.EOF]
    if _in_comment(text, tokens, offset):
        return []
    # the word being typed: an identifier or keyword token reaching the cursor, or a lone '@'
    before = [t for t in tokens if t.span.start < offset]
    prefix_start = offset
    if before and before[-1].span.end >= offset and before[-1].type in (TokenType.IDENTIFIER, TokenType.KEYWORD):
        prefix_start = before[-1].span.start
        before = before[:-1]
    elif offset > 0 and text[offset - 1] == "@":
        prefix_start = offset - 1
    prefix = text[prefix_start:offset]
    replace = ls.range_of(state, prefix_start, offset)
    table = analysis.table
    option = state.tree.option
    if option is None:  # a file with syntax errors may have lost its option: use the last good one
        header = next((h for h in table.options.values() if h.file is state.tree), None)
        option = header.decl if header else None
    option_name = option.name.text if option else None
    good = project.good.get(state.real)
    good_option = good.option if good is not None else None
    last = before[-1] if before else None

    def item(
        label: str,
        kind: lsp.CompletionItemKind,
        detail: str,
        key: Key | None,
        insert: str | None = None,
        sort: str = "5",
    ) -> lsp.CompletionItem:
        return _item(label, kind, detail, key, replace, insert, sort)

    def states() -> list[lsp.CompletionItem]:
        # the states as typed, and those an edit in progress hid from the parser
        names = {s.name.text: s for o in (good_option, option) if o is not None for s in o.states}
        if option_name is None:
            return []
        return [
            item(
                s.name.text,
                lsp.CompletionItemKind.EnumMember,
                "initial state" if s.initial else "state",
                ("state", option_name, s.name.text),
                sort="1",
            )
            for s in names.values()
        ]

    def own_params() -> list[lsp.CompletionItem]:
        if option_name is None or option_name not in table.options:
            return []
        return [
            item(
                "@" + p.short_name,
                lsp.CompletionItemKind.Variable,
                f"{type_text(p.kind, p.enum)} {_facts(p.range, p.unit)}".strip(),
                ("param", "option", option_name, p.short_name),
                sort="1",
            )
            for p in table.options[option_name].params.values()
        ]

    def elements(enum: str, sort: str = "0") -> list[lsp.CompletionItem]:
        e = table.enums.get(enum)
        if e is None:
            return []
        out = []
        for qualified in e.elements:
            short = qualified[len(enum) + 1 :] if qualified.startswith(enum + ".") else qualified
            label = qualified if "." in prefix and prefix.startswith(enum + ".") else short
            out.append(
                item(label, lsp.CompletionItemKind.EnumMember, f"enum {enum}", ("element", qualified), sort=sort)
            )
        return out

    def values() -> list[lsp.CompletionItem]:
        out = own_params()
        for s in table.inputs.values():
            detail = f"input {type_text(s.kind, s.enum)} {_facts(s.range, s.unit)}".strip()
            out.append(
                item(
                    s.name,
                    lsp.CompletionItemKind.Function if s.params else lsp.CompletionItemKind.Variable,
                    detail,
                    ("input", s.name),
                )
            )
        for o in table.outputs.values():
            what = "internal" if o.internal else "output"
            out.append(
                item(
                    o.name,
                    lsp.CompletionItemKind.Variable,
                    f"{what} {type_text(o.kind, o.enum)} {_facts(o.range, o.unit)}".strip(),
                    ("output", o.name),
                )
            )
        for c in table.constants.values():
            out.append(
                item(
                    c.name,
                    lsp.CompletionItemKind.Constant,
                    f"const = {c.text} {c.unit or ''}".strip(),
                    ("constant", c.name),
                )
            )
        for k in VALUE_KEYWORDS:
            out.append(item(k, lsp.CompletionItemKind.Keyword, "value", None, sort="7"))
        return out

    def callables() -> list[lsp.CompletionItem]:
        out = []
        for name, header in table.options.items():
            signature = ", ".join(p.short_name for p in header.params.values())
            out.append(item(name, lsp.CompletionItemKind.Class, f"option({signature})", ("option", name)))
        for b in table.behaviors.values():
            signature = ", ".join(p.short_name for p in b.params)
            out.append(
                item(b.name, lsp.CompletionItemKind.Function, f"basic behavior({signature})", ("behavior", b.name))
            )
        return out

    def enum_of(token: Token) -> str | None:
        name = token.text
        if option_name and option_name in table.options:
            for p in table.options[option_name].params.values():
                if name in ("@" + p.short_name, p.name):
                    return p.enum
        symbol = table.inputs.get(name) or table.outputs.get(name)
        return symbol.enum if symbol is not None else None

    # after 'goto': the option's states
    if last is not None and last.is_kw("goto"):
        return states()
    if prefix.startswith("@"):
        return own_params()
    if last is not None and last.is_kw("enum"):
        return [item(e, lsp.CompletionItemKind.Enum, "enumeration", ("enum", e)) for e in table.enums]
    # 'Enum.' : the elements of that enumeration, qualified
    if "." in prefix:
        head = prefix.rsplit(".", 1)[0]
        if head in table.enums:
            return elements(head) + [i for i in values() if i.label.startswith(prefix)]
    # inside a call's parentheses: parameter names, or a parameter's value
    depth = 0
    for j in range(len(before) - 1, -1, -1):
        t = before[j]
        if t.type is TokenType.OPERATOR and t.text in (";", "{", "}"):
            break
        if t.is_op(")"):
            depth += 1
        elif t.is_op("("):
            if depth:
                depth -= 1
                continue
            callee_at = j - 1
            if (
                callee_at >= 1
                and before[callee_at].type is TokenType.KEYWORD
                and before[callee_at].text in ("option", "behavior")
            ):
                callee_at -= 1
            if callee_at < 0 or before[callee_at].type is not TokenType.IDENTIFIER:
                break
            callee = before[callee_at].text
            params: tuple[ir.Parameter, ...] = ()
            klass = ""
            if callee in table.options:
                params, klass = tuple(table.options[callee].params.values()), "option"
            elif callee in table.behaviors:
                params, klass = table.behaviors[callee].params, "behavior"
            elif callee in table.inputs:
                params, klass = table.inputs[callee].params, "input"
            else:
                break
            inner = before[j + 1 :]
            if last is not None and (last.is_op("(") or last.is_op(",")):
                given = {_strip(inner[k].text) for k in range(len(inner) - 1) if inner[k + 1].is_op("=")}
                return [
                    item(
                        p.short_name,
                        lsp.CompletionItemKind.Property,
                        type_text(p.kind, p.enum) + (" " + _facts(p.range, p.unit) if _facts(p.range, p.unit) else ""),
                        ("param", klass, callee, p.short_name),
                        insert=f"{p.short_name} = ",
                        sort="0",
                    )
                    for p in params
                    if p.short_name not in given
                ]
            if last is not None and last.is_op("=") and len(before) >= 2:
                short = _strip(before[-2].text)
                param = next((p for p in params if p.short_name == short), None)
                if param is not None and param.enum:
                    return elements(param.enum) + values()
                return values()
            break
    if last is not None and len(before) >= 2 and before[-2].type is TokenType.IDENTIFIER:
        if last.is_op("==") or last.is_op("!="):
            enum = enum_of(before[-2])
            if enum:
                return elements(enum) + values()
            return values()
        if last.is_op("="):
            symbol = table.outputs.get(before[-2].text)
            if symbol is not None and symbol.enum:
                return elements(symbol.enum) + values()
            return values()
    keywords = [
        item(k, lsp.CompletionItemKind.Keyword, "keyword", None, sort="8")
        for k in sorted(KEYWORDS)
        if k not in VALUE_KEYWORDS
    ]
    return values() + callables() + keywords


def _strip(name: str) -> str:
    return name[1:] if name.startswith("@") else name


#: Longest header line of a stdio message (``Content-Length: N`` and ``Content-Type: ...``).
MAX_HEADER_LINE = 4096


def read_message(stream: BinaryIO, limit: int) -> bytes | int | None:
    """The body of the next ``Content-Length`` framed message on ``stream``; None at its end.

    A body over ``limit`` bytes is read away in pieces and only its length returned, so a
    runaway length neither fills the memory nor loses the framing.
    """
    while True:
        length: int | None = None
        while True:
            line = stream.readline(MAX_HEADER_LINE)
            if not line:
                return None
            if not line.strip():
                break
            name, _, value = line.decode("latin-1").partition(":")
            if name.strip().lower() == "content-length" and value.strip().isdigit():
                length = int(value.strip())
        if length is None:
            continue  # headers without a length: nothing to read, wait for the next message
        if length > limit:
            while length > 0:
                piece = stream.read(min(length, 1 << 20))
                if not piece:
                    return None
                length -= len(piece)
            return limit + 1
        body = stream.read(length)
        if len(body) < length:
            return None
        return body


def serve_stdio(agents: str | None = None, stdin: BinaryIO | None = None, stdout: BinaryIO | None = None) -> None:
    """Speak the protocol on stdin/stdout until the client says exit (or closes stdin)."""
    server = create_server(agents)
    server.protocol.set_writer(StdoutWriter(stdout or sys.stdout.buffer))
    reader = stdin or sys.stdin.buffer
    try:
        while (body := read_message(reader, MAX_LSP_MESSAGE_BYTES)) is not None:
            if isinstance(body, int):
                too_big = JsonRpcInvalidRequest(f"Invalid Request: a message over {MAX_LSP_MESSAGE_BYTES} bytes")
                server.protocol.reply_error(None, too_big)
                continue
            handle_text(server.protocol, body)
    except BrokenPipeError:
        pass  # the editor went away


__all__ = ["XabslLanguageServer", "create_server", "document_path", "read_message", "serve_stdio", "type_text"]
