"""The XABSL 2 front end: source files -> tokens -> AST -> checked program (IR) + diagnostics.

The one entry point is :func:`compile_file`::

    compilation = compile_file("examples/demo/agents.xabsl")
    for diagnostic in compilation.diagnostics:
        print(diagnostic.format())
    if compilation.ok:
        program = compilation.program   # xabsl_studio.engine.ir.Program

Stages, one module each: :mod:`.tokens`, :mod:`.parser` (with :mod:`.ast`), :mod:`.loader`
(the include closure), :mod:`.symbols` (the global symbol table), :mod:`.check` (names, types,
IR), :mod:`.lint` (whole-program checks). User mistakes never raise: they are diagnostics.
"""

from __future__ import annotations

import gc
import time
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field

from xabsl_studio.engine import ir
from xabsl_studio.engine.lang import lint
from xabsl_studio.engine.lang.check import OptionChecker, title_fields
from xabsl_studio.engine.lang.diagnostics import Diagnostic, Diagnostics, Severity
from xabsl_studio.engine.lang.loader import load
from xabsl_studio.engine.lang.symbols import Declarations, SymbolTable
from xabsl_studio.engine.recursion import deep_recursion as deep_recursion
from xabsl_studio.engine.types import Span

__all__ = ["Compilation", "Diagnostic", "Severity", "assemble_program", "compile_file"]


@dataclass
class Compilation:
    """The result of compiling one agents file."""

    program: ir.Program | None
    diagnostics: list[Diagnostic]
    files: list[str] = field(default_factory=list)
    #: seconds spent per stage: "parse", "check"
    timings: dict[str, float] = field(default_factory=dict)
    #: source text of every file, by display name
    sources: dict[str, str] = field(default_factory=dict)
    #: names of all options declared, also when the program has errors
    option_names: list[str] = field(default_factory=list)
    #: what checked when there are errors: the options of the files without syntax errors that
    #: built, every declared symbol and agent (for a studio that shows a broken behavior); never run it
    partial: ir.Program | None = None

    def source_text(self, span: Span) -> str:
        """The source text of a span, whitespace runs collapsed to one blank."""
        text = self.sources.get(span.file, "")
        return " ".join(text[span.start : span.end].split())

    @property
    def errors(self) -> list[Diagnostic]:
        """The error diagnostics, in report order."""
        return [d for d in self.diagnostics if d.is_error]

    @property
    def warnings(self) -> list[Diagnostic]:
        """The warnings (and lint findings), in report order."""
        return [d for d in self.diagnostics if not d.is_error]

    @property
    def ok(self) -> bool:
        """True when there is a program (no errors)."""
        return self.program is not None


def compile_file(
    path: str,
    base: str | None = None,
    overrides: Mapping[str, str] | None = None,
) -> Compilation:
    """Compile the agents file ``path`` and its include closure into a checked program.

    Args:
        path: the file to compile (normally ``agents.xabsl``).
        base: folder that diagnostic file names are relative to (default: working directory).
        overrides: unsaved texts by file path, used instead of the files on disk.

    Returns:
        a :class:`Compilation`; ``program`` is None when there is any error.
    """
    with deep_recursion(), no_cycle_collection():
        return _compile(path, base, overrides)


@contextmanager
def no_cycle_collection() -> Iterator[None]:
    """Pause the cyclic garbage collector while compiling (or building anything else that large).

    A compile allocates hundreds of thousands of tokens, spans and nodes that all stay alive
    until it ends, so every collection the allocations trigger traverses them all for nothing:
    that was 40% of the compile time of a 200-file set. Nothing is lost: reference counting
    still frees everything that dies, and the collector runs again as usual afterwards.
    """
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def assemble_program(
    table: SymbolTable,
    options: dict[str, ir.Option],
    usage: set[tuple[str, str]],
    title_comment: str | None,
    files: tuple[str, ...],
    diagnostics: Diagnostics,
) -> ir.Program:
    """The last stage of a compile: the program of the checked ``options``, its agents and lints.

    Checks the agents (unique names, existing root options), builds the :class:`~xabsl_studio.engine.ir.Program`
    and runs the option-graph and usage lints (cycles, reachability, unused declarations) into
    ``diagnostics``. Shared by :func:`compile_file` and the language server, which checks options
    one by one and keeps them between keystrokes.
    """
    agents: list[ir.Agent] = []
    agent_names: set[str] = set()
    for decl in table.agents:
        if decl.name.text in agent_names:
            diagnostics.add(
                "duplicate-definition", f"agent '{decl.name.text}' is defined more than once", decl.name.span
            )
        agent_names.add(decl.name.text)
        if decl.root.text not in table.options:
            diagnostics.add(
                "unknown-option", f"agent '{decl.name.text}': no option named '{decl.root.text}'", decl.root.span
            )
        agents.append(ir.Agent(decl.name.text, decl.title, decl.root.text, decl.doc, decl.name.span))

    fields = title_fields(title_comment)
    program = ir.Program(
        title=fields["title"],
        options=options,
        agents=tuple(agents),
        enums=table.enums,
        inputs=table.inputs,
        outputs=table.outputs,
        constants=table.constants,
        behaviors=table.behaviors,
        platform=fields["platform"],
        software_environment=fields["software_environment"],
        files=files,
    )
    lint.check_cycles(options, diagnostics)
    lint.check_reachability(program, diagnostics)
    lint.check_unused(program, usage, diagnostics)
    return program


def _compile(path: str, base: str | None, overrides: Mapping[str, str] | None) -> Compilation:
    diagnostics = Diagnostics()
    started = time.perf_counter()
    loaded = load(path, diagnostics, base, overrides)
    parsed = time.perf_counter()

    # A file with lexical or syntax errors is incomplete: its option's trees are not checked,
    # so a lost state does not come back as "missing initial state" or "unknown state".
    broken = {d.file for d in diagnostics if d.is_error}
    table = Declarations(loaded.files, diagnostics).run()
    usage: set[tuple[str, str]] = set()
    ordered = sorted(
        (h for h in table.options.values() if h.file.path not in broken),
        # ties (names differing only in case) by exact name, so include order cannot matter
        key=lambda h: (h.decl.name.text.lower(), h.decl.name.text),
    )
    options: dict[str, ir.Option] = {}
    for index, header in enumerate(ordered):
        try:
            options[header.decl.name.text] = OptionChecker(table, header, diagnostics, usage).build(index)
        except RecursionError:
            diagnostics.add(
                "nesting-too-deep",
                f"option '{header.decl.name.text}' nests expressions or decisions too deeply to check",
                header.decl.name.span,
            )

    program = assemble_program(
        table,
        options,
        usage,
        loaded.root.title_comment if loaded.root else None,
        tuple(f.path for f in loaded.files),
        diagnostics,
    )
    checked = time.perf_counter()

    return Compilation(
        program=None if diagnostics.errors else program,
        diagnostics=diagnostics.sorted(),
        files=[f.path for f in loaded.files],
        timings={"parse": parsed - started, "check": checked - parsed},
        sources={f.path: f.text for f in loaded.files},
        option_names=sorted(table.options, key=str.lower),
        partial=program if diagnostics.errors else None,
    )
