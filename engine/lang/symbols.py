"""The one global symbol table of a program (§1.4) and the declaration passes that fill it.

As in the original compiler, names are global strings (namespaces are not scopes) and a symbol
is keyed by (name, symbol class): the same string may name an enumeration *and* an input symbol.
Only option parameters are scoped (per option); states are checked per option by the checker.

Passes over all files of the include closure, in the original's order:

1. enumerations (so any file may use an enum declared in a file it does not include);
2. symbols, constants, basic behaviors, option headers with their parameters.

The trees (decisions, actions) are built afterwards by :mod:`xabsl_studio.engine.lang.check`.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

from xabsl_studio.engine import ir
from xabsl_studio.engine.lang import ast
from xabsl_studio.engine.lang.diagnostics import Diagnostics
from xabsl_studio.engine.lang.tokens import is_identifier
from xabsl_studio.engine.types import Kind, Span

#: Symbol classes an identifier in an expression may name, in the original's search order.
EXPRESSION_CLASSES = ("constant", "option-parameter", "input", "output")
#: Fine classes that form a symbol-table key (the original's Decimal/Boolean/Enum split).
_KIND_CLASS = {Kind.DECIMAL: "decimal", Kind.BOOLEAN: "boolean", Kind.ENUM: "enum"}


@dataclass
class OptionHeader:
    """What other files need of an option before its trees are built: name and parameters."""

    decl: ast.OptionDecl
    file: ast.SourceFile
    params: dict[str, ir.Parameter] = field(default_factory=dict)  # "@x" -> Parameter("o.x")


@dataclass
class SymbolTable:
    """The global symbol table: every declaration of the include closure, by name."""

    enums: dict[str, ir.Enumeration] = field(default_factory=dict)
    #: qualified element name -> enumeration name
    elements: dict[str, str] = field(default_factory=dict)
    inputs: dict[str, ir.InputSymbol] = field(default_factory=dict)
    outputs: dict[str, ir.OutputSymbol] = field(default_factory=dict)
    constants: dict[str, ir.ConstantDecl] = field(default_factory=dict)
    behaviors: dict[str, ir.BasicBehavior] = field(default_factory=dict)
    options: dict[str, OptionHeader] = field(default_factory=dict)
    agents: list[ast.AgentDecl] = field(default_factory=list)
    #: every declaration's span by (name, class), for "defined here" notes and lint
    declared_at: dict[tuple[str, str], Span] = field(default_factory=dict)
    #: fine-class keys (name, class, kind) for duplicate detection as the original does it
    _keys: dict[tuple[str, str, str], Span] = field(default_factory=dict)

    def element(self, enum: str, name: str) -> str | None:
        """The qualified element for ``name`` (short or qualified) of enumeration ``enum``."""
        qualified = f"{enum}.{name}"
        if self.elements.get(qualified) == enum:
            return qualified
        if self.elements.get(name) == enum:
            return name
        return None


def _kind(type_: ast.TypeRef) -> Kind:
    return Kind(type_.kind)


class Declarations:
    """Runs the declaration passes over all files into one :class:`SymbolTable`."""

    def __init__(self, files: list[ast.SourceFile], diagnostics: Diagnostics) -> None:
        self.files = files
        self.diagnostics = diagnostics
        self.table = SymbolTable()

    def run(self) -> SymbolTable:
        """Run both declaration passes over all files; returns the filled table."""
        for source in self.files:
            if source.namespace:
                for item in source.namespace.items:
                    if isinstance(item, ast.EnumDecl):
                        self.declare_enum(item, source.namespace.name.text)
        for source in self.files:
            if source.namespace:
                self.declare_namespace(source)
            if source.option:
                self.declare_option(source)
            self.table.agents.extend(source.agents)
        return self.table

    # ------------------------------------------------------------------ helpers

    def key(self, name: ast.Name, klass: str, kind: str = "") -> bool:
        """Register a declaration; report and return False for a duplicate."""
        key = (name.text, klass, kind)
        if key in self.table._keys:
            first = self.table._keys[key]
            self.diagnostics.add(
                "duplicate-definition",
                f"'{name.text}' is defined more than once",
                name.span,
                related=(("first defined here", first),),
            )
            return False
        self.table._keys[key] = name.span
        self.table.declared_at.setdefault((name.text, klass), name.span)
        return True

    def check_enum_type(self, type_: ast.TypeRef) -> str | None:
        """The enumeration an enum type names (reported if unknown); None for other types."""
        if type_.kind != "enum":
            return None
        assert type_.enum is not None
        if type_.enum.text not in self.table.enums:
            self.diagnostics.add("unknown-enum", f"no enumeration named '{type_.enum.text}'", type_.enum.span)
        return type_.enum.text

    def check_range_unit(self, kind: Kind, what: str, range_span: Span | None, unit_span: Span | None) -> None:
        """Warn about a range or unit on a boolean or enum symbol or parameter (ignored)."""
        # The original prints X2537 for these but does not count it (§1.7): a warning here.
        if kind is Kind.DECIMAL:
            return
        for label, span in (("range", range_span), ("unit", unit_span)):
            if span is not None:
                self.diagnostics.add(
                    "range-on-non-decimal",
                    f"a {kind.value} {what} cannot have a {label}; it is ignored",
                    span,
                )

    def parameters(self, owner: str, decls: list[ast.ParamDecl], what: str) -> tuple[ir.Parameter, ...]:
        """The qualified parameters of ``owner``: ``owner`` + ``.`` + the declared name in full."""
        params: list[ir.Parameter] = []
        seen: dict[str, Span] = {}
        for decl in decls:
            kind = _kind(decl.type)
            enum = self.check_enum_type(decl.type)
            short = decl.name.text
            if short in seen:
                self.diagnostics.add(
                    "duplicate-definition",
                    f"parameter '{short}' is defined more than once",
                    decl.name.span,
                    related=(("first defined here", seen[short]),),
                )
                continue
            seen[short] = decl.name.span
            self.check_range_unit(kind, f"{what} parameter", decl.range_span, decl.unit_span)
            bare = short[1:] if short.startswith("@") else short
            params.append(
                ir.Parameter(
                    f"{owner}.{bare}",
                    kind,
                    enum,
                    decl.range if kind is Kind.DECIMAL else None,
                    decl.unit if kind is Kind.DECIMAL else None,
                    decl.doc,
                    decl.name.span,
                    owner,
                )
            )
        return tuple(params)

    # ------------------------------------------------------------------ pass 1

    def declare_enum(self, decl: ast.EnumDecl, namespace: str) -> None:
        """Pass 1: declare an enumeration and its qualified elements."""
        if not self.key(decl.name, "enum"):
            return
        elements = []
        for element in decl.elements:
            qualified = f"{decl.name.text}.{element.text}"
            if qualified in self.table.elements:
                self.diagnostics.add(
                    "duplicate-definition", f"enum element '{element.text}' is defined more than once", element.span
                )
                continue
            self.table.elements[qualified] = decl.name.text
            elements.append(qualified)
        self.table.enums[decl.name.text] = ir.Enumeration(
            decl.name.text, tuple(elements), decl.internal, decl.doc, decl.name.span
        )

    # ------------------------------------------------------------------ pass 2

    def declare_namespace(self, source: ast.SourceFile) -> None:
        """Pass 2: declare a namespace's symbols, constants or basic behaviors."""
        namespace = source.namespace
        assert namespace is not None
        name = namespace.name.text
        stem = os.path.splitext(os.path.basename(source.path))[0]
        # a file name that is no identifier (basic-behaviors.xabsl) asks for nothing: a namespace
        # named so would be a syntax error
        if name != stem and is_identifier(stem):
            self.diagnostics.add(
                "naming", f"namespace '{name}' should be named like its file '{stem}'", namespace.name.span
            )
        if not namespace.items:
            self.diagnostics.add("empty-namespace", f"namespace '{name}' declares nothing", namespace.name.span)
        has_behaviors = any(isinstance(i, ast.BehaviorDecl) for i in namespace.items)
        has_symbols = any(not isinstance(i, ast.BehaviorDecl) for i in namespace.items)
        if has_behaviors and has_symbols:
            self.diagnostics.add(
                "namespace-separation",
                f"namespace '{name}' mixes basic behaviors with symbols; put them in separate namespaces",
                namespace.name.span,
            )
        for item in namespace.items:
            if isinstance(item, ast.SymbolDecl):
                self.declare_symbol(item, name)
            elif isinstance(item, ast.ConstDecl):
                if self.key(item.name, "constant"):
                    text = ("-" if item.negative else "") + item.text
                    self.table.constants[item.name.text] = ir.ConstantDecl(
                        item.name.text, float(text), text, item.unit, item.doc, name, item.name.span
                    )
            elif isinstance(item, ast.BehaviorDecl) and self.key(item.name, "behavior"):
                params = self.parameters(item.name.text, item.params, "basic behavior")
                self.table.behaviors[item.name.text] = ir.BasicBehavior(
                    item.name.text, params, item.doc, name, len(self.table.behaviors), item.name.span
                )

    def declare_symbol(self, decl: ast.SymbolDecl, namespace: str) -> None:
        """Pass 2: declare an input, output or internal symbol."""
        kind = _kind(decl.type)
        enum = self.check_enum_type(decl.type)
        klass = "input" if decl.io == "input" else "output"
        if decl.params is not None and klass != "input":
            self.diagnostics.add(
                "parameters-on-non-input",
                f"only input symbols can have parameters ('{decl.name.text}')",
                decl.name.span,
            )
        self.check_range_unit(kind, "symbol", decl.range_span, decl.unit_span)
        if not self.key(decl.name, klass, _KIND_CLASS[kind]):
            return
        range_ = decl.range if kind is Kind.DECIMAL else None
        unit = decl.unit if kind is Kind.DECIMAL else None
        if klass == "input":
            params = self.parameters(decl.name.text, decl.params or [], "input symbol")
            self.table.inputs[decl.name.text] = ir.InputSymbol(
                decl.name.text,
                kind,
                enum,
                params,
                range_,
                unit,
                decl.doc,
                namespace,
                len(self.table.inputs),
                decl.name.span,
            )
        else:
            self.table.outputs[decl.name.text] = ir.OutputSymbol(
                decl.name.text,
                kind,
                enum,
                decl.io == "internal",
                range_,
                unit,
                decl.doc,
                namespace,
                len(self.table.outputs),
                decl.name.span,
            )

    def declare_option(self, source: ast.SourceFile) -> None:
        """Pass 2: declare an option's name and parameters, for calls from other files."""
        decl = source.option
        assert decl is not None
        stem = os.path.splitext(os.path.basename(source.path))[0]
        if decl.name.text != stem and is_identifier(stem):  # as for namespaces
            self.diagnostics.add(
                "naming", f"option '{decl.name.text}' should be named like its file '{stem}'", decl.name.span
            )
        if not self.key(decl.name, "option"):
            return
        header = OptionHeader(decl, source)
        for param_decl in decl.params:
            if not param_decl.name.text.startswith("@"):
                self.diagnostics.add(
                    "no-matching-symbol",
                    f"option parameters are declared with '@' (write '@{param_decl.name.text}')",
                    param_decl.name.span,
                )
        params = self.parameters(decl.name.text, decl.params, "option")
        header.params = {"@" + p.short_name: p for p in params}
        self.table.options[decl.name.text] = header
