"""The language server's model of one behavior set: parsed files kept in memory, rechecked incrementally.

A :class:`Project` owns the include closure of one agents file. Editor buffers overlay the files
on disk. :meth:`Project.analyze` brings the model up to date and returns an :class:`Analysis`:
the compiler's diagnostics per file and an index of every name occurrence (declarations and
resolved references) built from the compiler's own data — the AST's name spans, the symbol
table of :mod:`xabsl_studio.engine.lang.symbols` and the resolutions the checker of
:mod:`xabsl_studio.engine.lang.check` makes (a subclass records them as it resolves), never by re-parsing text.

Incremental, in three layers:

* a file is tokenized and parsed again only when its text changed (disk files: when their size
  or modification time changed);
* the declaration passes always run again (they are cheap tables over the ASTs);
* an option is checked again only when its own AST changed or when anything it could depend on
  changed: the "interface" of the program (namespaces, the agents, every option's name and
  parameters, which files are broken). Typing inside one option's states rechecks one option.

The pipeline is the one of :func:`xabsl_studio.engine.lang.compile_file` (the same passes, in the same order,
with the same rule that options of files with syntax errors are not checked), so the diagnostics
are the compiler's; ``tests/lsp`` compares them.

Every file is read through a :class:`~xabsl_studio.lsp.access.FileAccess` (the allowed roots, regular
``.xabsl`` files, a size bound): an ``include`` that leaves the roots is a diagnostic, not a read.

This module does not import pygls: :mod:`xabsl_studio.lsp.server` adapts it to the protocol.
"""

from __future__ import annotations

import os
import time
from bisect import bisect_right
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import TypeAlias

from xabsl_studio.engine import ir
from xabsl_studio.engine.lang import assemble_program, ast, deep_recursion
from xabsl_studio.engine.lang.check import OptionChecker
from xabsl_studio.engine.lang.diagnostics import Diagnostic, Diagnostics
from xabsl_studio.engine.lang.loader import display_path
from xabsl_studio.engine.lang.parser import parse_file
from xabsl_studio.engine.lang.symbols import Declarations, OptionHeader, SymbolTable
from xabsl_studio.engine.lang.tokens import Token, decode_source, tokenize
from xabsl_studio.engine.types import Span
from xabsl_studio.lsp.access import FileAccess, OutsideRoots

#: What a name occurrence stands for: ("option", name), ("behavior", name), ("input", name),
#: ("output", name), ("constant", name), ("enum", name), ("element", qualified element),
#: ("param", owner class, owner, short name), ("state", option, state), ("agent", name).
Key: TypeAlias = tuple[str, ...]


def _width(char: str, encoding: str) -> int:
    """How many units of ``encoding`` (LSP's "utf-8", "utf-16" or "utf-32") one character takes."""
    code = ord(char)
    if encoding == "utf-16":
        return 2 if code > 0xFFFF else 1
    if encoding == "utf-8":
        return 1 if code < 0x80 else 2 if code < 0x800 else 3 if code < 0x10000 else 4
    return 1


class LineIndex:
    """Offsets in a file's text <-> (0-based line, column in the units of a position encoding)."""

    __slots__ = ("ascii", "starts", "text")

    def __init__(self, text: str) -> None:
        self.text = text
        self.ascii = text.isascii()
        starts = [0]
        find = text.find
        at = find("\n")
        while at >= 0:
            starts.append(at + 1)
            at = find("\n", at + 1)
        self.starts = starts

    def position(self, offset: int, encoding: str = "utf-16") -> tuple[int, int]:
        """The (line, character) of a text offset, characters counted in ``encoding``."""
        offset = max(0, min(offset, len(self.text)))
        line = bisect_right(self.starts, offset) - 1
        start = self.starts[line]
        if self.ascii or encoding == "utf-32":
            return line, offset - start
        return line, sum(_width(c, encoding) for c in self.text[start:offset])

    def offset(self, line: int, character: int, encoding: str = "utf-16") -> int:
        """The text offset of a (line, character) position, characters counted in ``encoding``."""
        if line < 0:
            return 0
        if line >= len(self.starts):
            return len(self.text)
        start = self.starts[line]
        end = self.starts[line + 1] - 1 if line + 1 < len(self.starts) else len(self.text)
        if self.ascii or encoding == "utf-32":
            return min(start + max(character, 0), end)
        units = 0
        at = start
        while at < end and units < character:
            units += _width(self.text[at], encoding)
            at += 1
        return at


@dataclass
class SourceState:
    """One file as last parsed: its text, AST and the diagnostics of reading and parsing it."""

    real: str
    shown: str
    text: str
    tree: ast.SourceFile
    parse_diagnostics: list[Diagnostic]
    lines: LineIndex
    stamp: tuple[int, int] | None = None  # (size, mtime_ns) of the disk file read
    #: unique per parse, so caches can tell a reparsed file from the one they saw
    serial: int = 0
    _tokens: list[Token] | None = None

    @property
    def tokens(self) -> list[Token]:
        """The file's tokens (computed on demand: semantic tokens and completion need them)."""
        if self._tokens is None:
            self._tokens = tokenize(self.text, self.shown, Diagnostics())
        return self._tokens


@dataclass(slots=True)
class Occurrence:
    """A name in a file: where it is, what it stands for, and whether it declares it."""

    start: int
    end: int
    key: Key
    declaration: bool
    text: str


@dataclass
class _OptionResult:
    """What checking one option produced (cached while its inputs stay the same)."""

    option: ir.Option | None
    diagnostics: list[Diagnostic]
    usage: set[tuple[str, str]]
    references: dict[int, tuple[Span, Key]]
    #: unique per check, so the name index can tell a new result from the one it indexed
    serial: int = 0


@dataclass
class Analysis:
    """The checked state of the behavior set: diagnostics and the name index, by real path."""

    files: list[SourceState]
    by_real: dict[str, SourceState]
    by_shown: dict[str, SourceState]
    table: SymbolTable
    program: ir.Program
    diagnostics: dict[str, list[Diagnostic]]
    #: file-less diagnostics (a missing agents file)
    loose: list[Diagnostic]
    occurrences: dict[str, list[Occurrence]]
    declarations: dict[Key, tuple[str, Occurrence]]
    timings: dict[str, float] = field(default_factory=dict)
    rechecked: int = 0

    @property
    def ok(self) -> bool:
        """Whether the analysis found no error in any file."""
        return not any(d.is_error for ds in self.diagnostics.values() for d in ds) and not any(
            d.is_error for d in self.loose
        )

    def all_diagnostics(self) -> list[Diagnostic]:
        """Every diagnostic of the analysis, per file first, then those without a file."""
        return [d for ds in self.diagnostics.values() for d in ds] + self.loose

    def occurrence_at(self, real: str, offset: int) -> Occurrence | None:
        """The name occurrence covering ``offset`` (or ending right at it) in file ``real``."""
        items = self.occurrences.get(real, [])
        starts = [o.start for o in items]
        index = bisect_right(starts, offset) - 1
        for candidate in (index, index - 1):
            if 0 <= candidate < len(items):
                occurrence = items[candidate]
                if occurrence.start <= offset <= occurrence.end:
                    return occurrence
        return None

    def references(self, key: Key) -> list[tuple[str, Occurrence]]:
        """Every occurrence of ``key`` (declaration included), by file in include order."""
        return [(f.real, o) for f in self.files for o in self.occurrences.get(f.real, []) if o.key == key]

    def option_at(self, real: str) -> ast.OptionDecl | None:
        """The option declared in file ``real``, if it declares one."""
        state = self.by_real.get(real)
        return state.tree.option if state else None


class _Recorder(OptionChecker):
    """The compiler's option checker, noting what every name it resolves stands for."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self.references: dict[int, tuple[Span, Key]] = {}

    def note(self, span: Span, key: Key) -> None:
        self.references[span.start] = (span, key)

    def identifier(self, name: str, span: Span, enum: str | None) -> ir.Expression | None:
        result = super().identifier(name, span, enum)
        match result:
            case ir.EnumLiteral(element=element):
                self.note(span, ("element", element))
            case ir.ParameterRef(param=param):
                short = param[len(self.name) + 1 :]
                self.note(span, ("param", "option", self.name, short))
            case ir.Constant():
                self.note(span, ("constant", name))
            case ir.InputRef():
                self.note(span, ("input", name))
            case ir.OutputRef():
                self.note(span, ("output", name))
        return result

    def input_call(self, node: ast.Call) -> ir.Expression | None:
        if node.name.text in self.table.inputs:
            self.note(node.name.span, ("input", node.name.text))
        return super().input_call(node)

    def arguments(
        self,
        callee: str,
        params: tuple[ir.Parameter, ...],
        args: list[ast.CallArg],
        call_span: Span,
        what: str,
    ) -> tuple[ir.Argument, ...] | None:
        klass = {"option": "option", "basic behavior": "behavior"}.get(what, "input")
        shorts = {p.short_name for p in params}
        for arg in args:
            short = arg.name.text[1:] if arg.name.text.startswith("@") else arg.name.text
            if short in shorts:
                self.note(arg.name.span, ("param", klass, callee, short))
        return super().arguments(callee, params, args, call_span, what)

    def call(self, node: ast.CallAction) -> ir.Action | None:
        name = node.name.text
        option = name in self.table.options and node.explicit in (None, "option")
        behavior = name in self.table.behaviors and node.explicit in (None, "behavior")
        if option != behavior:
            self.note(node.name.span, ("option" if option else "behavior", name))
        return super().call(node)

    def assignment(self, node: ast.Assign) -> ir.Action | None:
        if node.target.text in self.table.outputs:
            self.note(node.target.span, ("output", node.target.text))
        return super().assignment(node)

    def tree(self, node: ast.DTree) -> ir.DecisionTree:
        if isinstance(node, ast.Goto) and node.target.text in self.state_names:
            self.note(node.target.span, ("state", self.name, node.target.text))
        return super().tree(node)


def _bare(name: str) -> str:
    return name[1:] if name.startswith("@") else name


def _declared(tree: ast.SourceFile) -> Iterable[tuple[Span, Key, bool]]:
    """The declarations of one file (and the names in declarations that refer elsewhere)."""

    def params(klass: str, owner: str, decls: list[ast.ParamDecl]) -> Iterable[tuple[Span, Key, bool]]:
        for p in decls:
            if p.type.enum is not None:
                yield p.type.enum.span, ("enum", p.type.enum.text), False
            yield p.name.span, ("param", klass, owner, _bare(p.name.text)), True

    if tree.namespace is not None:
        yield tree.namespace.name.span, ("namespace", tree.namespace.name.text), True
        for item in tree.namespace.items:
            if isinstance(item, ast.EnumDecl):
                yield item.name.span, ("enum", item.name.text), True
                for element in item.elements:
                    yield element.span, ("element", f"{item.name.text}.{element.text}"), True
            elif isinstance(item, ast.SymbolDecl):
                if item.type.enum is not None:
                    yield item.type.enum.span, ("enum", item.type.enum.text), False
                klass = "input" if item.io == "input" else "output"
                yield item.name.span, (klass, item.name.text), True
                yield from params("input", item.name.text, item.params or [])
            elif isinstance(item, ast.ConstDecl):
                yield item.name.span, ("constant", item.name.text), True
            else:
                yield item.name.span, ("behavior", item.name.text), True
                yield from params("behavior", item.name.text, item.params)
    if tree.option is not None:
        decl = tree.option
        yield decl.name.span, ("option", decl.name.text), True
        yield from params("option", decl.name.text, decl.params)
        for state in decl.states:
            yield state.name.span, ("state", decl.name.text, state.name.text), True
    for agent in tree.agents:
        yield agent.name.span, ("agent", agent.name.text), True
        yield agent.root.span, ("option", agent.root.text), False


def _header_signature(decl: ast.OptionDecl) -> tuple[object, ...]:
    """What other options see of an option: its name and parameters (with their positions)."""
    return (
        decl.name.text,
        decl.name.span,
        tuple(
            (p.name.text, p.name.span, p.type.kind, p.type.enum.text if p.type.enum else None, p.range, p.unit, p.doc)
            for p in decl.params
        ),
        decl.doc,
    )


class Project:
    """One agents file's include closure, with unsaved editor texts laid over the files on disk.

    Args:
        agents: the agents file (or a lone file compiled on its own).
        base: the folder display names are relative to (default: the agents file's).
        access: which files may be read (default: the agents file's folder and below).
    """

    def __init__(self, agents: str, base: str | None = None, access: FileAccess | None = None) -> None:
        self.agents = os.path.realpath(agents)
        self.base = os.path.realpath(base or os.path.dirname(self.agents))
        self.access = access or FileAccess([os.path.dirname(self.agents)])
        self.overlays: dict[str, str] = {}
        self.sources: dict[str, SourceState] = {}
        self._interface: tuple[object, ...] | None = None
        self._checked: dict[str, tuple[int, _OptionResult]] = {}
        self._serial = 0
        #: per file: (its serial and its option results' serials, its occurrences, its declarations)
        self._indexed: dict[str, tuple[tuple[int, ...], list[Occurrence], list[tuple[Key, Occurrence]]]] = {}
        #: when the files on disk were last looked at (overlay edits in between do not stat them)
        self._disk_seen = -1.0
        self._disk_dirty = True
        self._look_at_disk = True
        self._resolved: dict[tuple[str, str], str] = {}
        #: the last tree of each file that parsed without errors (completion while typing)
        self.good: dict[str, ast.SourceFile] = {}
        self._analysis: Analysis | None = None
        self._dirty = True

    # ------------------------------------------------------------------ buffers

    def set_text(self, path: str, text: str) -> None:
        """An editor buffer's text for ``path`` (used instead of the file on disk)."""
        real = os.path.realpath(path)
        if self.overlays.get(real) != text:
            self.overlays[real] = text
            self._dirty = True

    def close(self, path: str) -> None:
        """The editor closed ``path``: the file on disk counts again."""
        if self.overlays.pop(os.path.realpath(path), None) is not None:
            self._dirty = True

    def disk_changed(self) -> None:
        """Files on disk may have changed (the client said so): look again on the next analysis."""
        self._dirty = True
        self._disk_dirty = True

    def contains(self, path: str) -> bool:
        """Whether ``path`` is in the include closure as last analyzed."""
        return os.path.realpath(path) in self.analyze().by_real

    # ------------------------------------------------------------------ loading

    def _source(self, real: str, diagnostics: Diagnostics) -> SourceState | None:
        cached = self.sources.get(real)
        # the base folder never changes, so a cached file's display name stays right
        shown = cached.shown if cached is not None else display_path(real, self.base)
        if real in self.overlays:
            text = self.overlays[real]
            if cached is not None and cached.text == text:
                return cached
            stamp = None
        elif cached is not None and cached.stamp is not None and not self._look_at_disk:
            return cached  # a keystroke elsewhere: the disk was looked at a moment ago
        else:
            try:
                stat = os.stat(self.access.check(real))
            except OSError as error:
                diagnostics.add("unreadable-file", f"unable to read file: {error.strerror}", None, shown)
                self.sources.pop(real, None)
                return None
            stamp = (stat.st_size, stat.st_mtime_ns)
            if cached is not None and cached.stamp == stamp:
                return cached
            try:
                text = decode_source(self.access.read(real))
            except OSError as error:
                diagnostics.add("unreadable-file", f"unable to read file: {error.strerror}", None, shown)
                self.sources.pop(real, None)
                return None
        own = Diagnostics()
        tree = parse_file(shown, text, own)
        self._serial += 1
        if not own.errors:
            self.good[real] = tree
        state = SourceState(real, shown, text, tree, list(own.items), LineIndex(text), stamp, self._serial)
        self.sources[real] = state
        return state

    def _resolve(self, real: str, include: str) -> str:
        """The real path an include names (cached while the disk is trusted: symlinks may change)."""
        key = (real, include)
        target = self._resolved.get(key)
        if target is None:
            target = os.path.realpath(os.path.join(os.path.dirname(real), include))
            self._resolved[key] = target
        return target

    def _unopenable(self, include: str, target: str) -> str:
        """Why an included file is not read: outside the roots, not a regular file, or missing."""
        try:
            self.access.check(target)
        except OutsideRoots as error:
            return f"unable to open file '{include}': {error.strerror}"
        if os.path.exists(target):
            return f"unable to open file '{include}': not a regular file"
        return f"unable to open file '{include}'"

    def _load(self, diagnostics: Diagnostics) -> tuple[ast.SourceFile | None, list[SourceState]]:
        """The include closure as :func:`xabsl_studio.engine.lang.loader.load` reads it, from the cache."""
        files: list[SourceState] = []
        seen: set[str] = set()

        def visit(real: str) -> SourceState | None:
            seen.add(real)
            state = self._source(real, diagnostics)
            if state is None:
                return None
            diagnostics.items.extend(state.parse_diagnostics)
            included_here: set[str] = set()
            for include in state.tree.includes:
                if "\0" in include.path:
                    diagnostics.add(
                        "missing-include-file", "unable to open file: the name contains a NUL byte", include.span
                    )
                    continue
                target = self._resolve(real, include.path)
                if target in included_here:
                    diagnostics.add("include-twice", f"'{include.path}' is included twice from this file", include.span)
                    continue
                included_here.add(target)
                if target in seen:
                    continue
                known = target in self.overlays or (not self._look_at_disk and target in self.sources)
                if not known and not self.access.is_file(target):
                    diagnostics.add("missing-include-file", self._unopenable(include.path, target), include.span)
                    continue
                visit(target)
            files.append(state)
            return state

        root = visit(self.agents)
        return (root.tree if root else None), files

    # ------------------------------------------------------------------ checking

    def analyze(self) -> Analysis:
        """The up-to-date analysis (recomputed only when a buffer or the disk changed)."""
        if self._analysis is not None and not self._dirty:
            return self._analysis
        with deep_recursion():
            self._analysis = self._analyze()
        self._dirty = False
        return self._analysis

    #: how long files on disk are trusted without a look while the editor only changes buffers
    DISK_TRUST_SECONDS = 2.0

    def _analyze(self) -> Analysis:
        started = time.perf_counter()
        self._look_at_disk = self._disk_dirty or started - self._disk_seen > self.DISK_TRUST_SECONDS
        if self._look_at_disk:
            self._resolved.clear()
            self._disk_seen = started
            self._disk_dirty = False
        diagnostics = Diagnostics()
        root, files = self._load(diagnostics)
        loaded = time.perf_counter()
        broken = {d.file for d in diagnostics if d.is_error}
        trees = [f.tree for f in files]
        table = Declarations(trees, diagnostics).run()
        declared = time.perf_counter()

        interface = (
            tuple(
                (f.real, f.serial) if f.tree.option is None else (f.real, _header_signature(f.tree.option))
                for f in files
            ),
            tuple(sorted(broken)),
        )
        if interface != self._interface:
            self._interface = interface
            self._checked.clear()

        usage: set[tuple[str, str]] = set()
        ordered = sorted(
            (h for h in table.options.values()),
            key=lambda h: (h.decl.name.text.lower(), h.decl.name.text),
        )
        options: dict[str, ir.Option] = {}
        results: dict[str, list[_OptionResult]] = {}
        rechecked = 0
        live: set[str] = set()
        index = 0
        by_tree = {id(f.tree): f for f in files}
        for header in ordered:
            source = by_tree[id(header.file)]
            real = source.real
            is_broken = header.file.path in broken
            cache_key = f"{real}\0{header.decl.name.text}"
            live.add(cache_key)
            cached = self._checked.get(cache_key)
            if cached is not None and cached[0] == source.serial:
                result = cached[1]
            else:
                result = self._check(table, header, -1 if is_broken else index)
                self._serial += 1
                result.serial = self._serial
                self._checked[cache_key] = (source.serial, result)
                rechecked += 1
            results.setdefault(real, []).append(result)
            if is_broken:
                continue  # checked for navigation only: the compiler reports nothing for it
            index += 1
            diagnostics.items.extend(result.diagnostics)
            usage |= result.usage
            if result.option is not None:
                options[header.decl.name.text] = result.option
        for stale in set(self._checked) - live:
            del self._checked[stale]

        program = assemble_program(
            table,
            options,
            usage,
            root.title_comment if root else None,
            tuple(f.shown for f in files),
            diagnostics,
        )
        checked = time.perf_counter()

        by_shown = {f.shown: f for f in files}
        per_file: dict[str, list[Diagnostic]] = {f.real: [] for f in files}
        loose: list[Diagnostic] = []
        for d in diagnostics.sorted():
            state = by_shown.get(d.span.file if d.span else d.file)
            if state is None:
                loose.append(d)
            else:
                per_file[state.real].append(d)

        occurrences, declarations = self._index(files, results)
        indexed = time.perf_counter()
        return Analysis(
            files=files,
            by_real={f.real: f for f in files},
            by_shown=by_shown,
            table=table,
            program=program,
            diagnostics=per_file,
            loose=loose,
            occurrences=occurrences,
            declarations=declarations,
            timings={
                "load": loaded - started,
                "declare": declared - loaded,
                "check": checked - declared,
                "index": indexed - checked,
            },
            rechecked=rechecked,
        )

    @staticmethod
    def _check(table: SymbolTable, header: OptionHeader, index: int) -> _OptionResult:
        own = Diagnostics()
        usage: set[tuple[str, str]] = set()
        recorder = _Recorder(table, header, own, usage)
        option: ir.Option | None
        try:
            option = recorder.build(max(index, 0))
        except RecursionError:
            option = None
            own.add(
                "nesting-too-deep",
                f"option '{header.decl.name.text}' nests expressions or decisions too deeply to check",
                header.decl.name.span,
            )
        return _OptionResult(option, list(own.items), usage, recorder.references)

    def _index(
        self, files: list[SourceState], results: dict[str, list[_OptionResult]]
    ) -> tuple[dict[str, list[Occurrence]], dict[Key, tuple[str, Occurrence]]]:
        """The name index; a file whose tree and option results are unchanged keeps its entries."""
        occurrences: dict[str, list[Occurrence]] = {}
        declarations: dict[Key, tuple[str, Occurrence]] = {}
        indexed: dict[str, tuple[tuple[int, ...], list[Occurrence], list[tuple[Key, Occurrence]]]] = {}
        for f in files:
            own = results.get(f.real, [])
            signature = (f.serial, *(r.serial for r in own))
            cached = self._indexed.get(f.real)
            if cached is None or cached[0] != signature:
                cached = (signature, *self._index_file(f, own))
            indexed[f.real] = cached
            occurrences[f.real] = cached[1]
            for key, occurrence in cached[2]:
                declarations.setdefault(key, (f.real, occurrence))
        self._indexed = indexed
        return occurrences, declarations

    @staticmethod
    def _index_file(
        f: SourceState, results: list[_OptionResult]
    ) -> tuple[list[Occurrence], list[tuple[Key, Occurrence]]]:
        found: dict[int, Occurrence] = {}
        declared: list[tuple[Key, Occurrence]] = []
        for span, key, is_declaration in _declared(f.tree):
            occurrence = Occurrence(span.start, span.end, key, is_declaration, f.text[span.start : span.end])
            found[span.start] = occurrence
            if is_declaration:
                declared.append((key, occurrence))
        for result in results:
            for span, key in result.references.values():
                found.setdefault(
                    span.start, Occurrence(span.start, span.end, key, False, f.text[span.start : span.end])
                )
        return sorted(found.values(), key=lambda o: o.start), declared
