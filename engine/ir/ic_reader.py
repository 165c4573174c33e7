"""Read XABSL intermediate code (§3) into an :class:`xabsl_studio.engine.ir.model.Program`.

The intermediate code (IC) is what the original compiler hands to the C++ engine: a flat stream of
whitespace-separated tokens (§3.1; CRLF or LF, ``//`` comments to the end of the line) laid out as
in §3.2. Reading it lets the engine run the original compiler's output and lets the tests run the
conformance kit's ``expected.ic`` without the source compiler.

The IC does not declare external things, so they are inferred from use:

* **input and output symbols**: ``i name`` reads an input symbol, ``o name`` reads an output
  symbol, ``d``/``b``/``e name`` actions assign an output symbol. The kind comes from the
  expression context (``dexp``/``bexp``/``eexp``) or the assignment's type letter.
* **enumerations**: ``e enumName name`` arguments and parameters name the enumeration, ``v E.e``
  literals name the element. Enum-valued symbols, parameters and expressions that meet in an
  assignment, a comparison (``c``) or a conditional (``q``) share one enumeration (unification).
  External enum elements are listed in **order of first appearance in the IC**; the IC cannot
  tell the declaration order, nor elements that are never mentioned. Names may contain dots
  (``v play.kind.kick.left`` is element ``kick.left`` of ``play.kind``), so, like the engine,
  which reads an element in the enumeration its context expects, a literal belongs to the
  enumeration its context names; only a literal whose context names none (an external enum
  output assigned nothing but literals) is taken to belong to the longest enumeration named
  elsewhere in the IC that prefixes it, else to its name up to the last dot.
* **parameters** of input symbols and basic behaviors: the IC lists only the arguments a call
  assigns, so parameters are listed in order of first appearance.
* **basic behaviors**: from ``a`` actions.

Spans and doc comments are ``None``: the IC has neither. A state's decision is the full tree of
the IC (common decision tree already inlined, §2.4); its leaves are numbered in pre-order from 0.
Only the state-kind form of generation B (``n``/``s N``/``c N`` after each state name) is read.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from xabsl_studio.engine.errors import ReadError
from xabsl_studio.engine.ir.model import (
    Action,
    ActionDone,
    Agent,
    Argument,
    Assignment,
    BasicBehavior,
    BehaviorCall,
    Binary,
    BooleanLiteral,
    Conditional,
    Conflict,
    Constant,
    DecisionTree,
    Enumeration,
    EnumLiteral,
    Expression,
    If,
    InputRef,
    InputSymbol,
    Logical,
    Number,
    Option,
    OptionCall,
    OptionTime,
    OutputRef,
    OutputSymbol,
    Parameter,
    ParameterRef,
    Program,
    State,
    StateTime,
    Transition,
    Unary,
)
from xabsl_studio.engine.types import Kind

__all__ = ["ICError", "read_ic", "read_ic_file"]

_KIND_LETTERS = {"d": Kind.DECIMAL, "b": Kind.BOOLEAN, "e": Kind.ENUM}
_DECIMAL_BINARY = {"+": "+", "-": "-", "*": "*", "d": "/", "%": "%"}
_COMPARISONS = {"=": "==", "n": "!=", "<": "<", "l": "<=", ">": ">", "g": ">="}
_TITLE = re.compile(r"//\s*Intermediate code for the agents of ?(.*)")


class ICError(ReadError):
    """Malformed intermediate code, with the position of the offending token."""

    def __init__(self, message: str, line: int, col: int, token: str | None) -> None:
        where = f"line {line}, column {col}"
        shown = "end of input" if token is None else repr(token)
        super().__init__(f"intermediate code, {where} at {shown}: {message}")
        self.line = line
        self.col = col
        self.token = token


@dataclass(slots=True)
class _Token:
    text: str
    line: int
    col: int


def _tokenize(text: str) -> tuple[list[_Token], str]:
    """Split into tokens with 1-based positions; returns the tokens and the title comment."""
    tokens: list[_Token] = []
    title = ""
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw
        cut = line.find("//")
        if cut >= 0:
            match = _TITLE.match(line[cut:].strip())
            if match and not tokens and not title:
                title = match.group(1).strip()
            line = line[:cut]
        for match in re.finditer(r"\S+", line):
            tokens.append(_Token(match.group(), number, match.start() + 1))
    return tokens, title


class _UnionFind:
    """Enum-typed things that must share one enumeration (keys like ``in:x``, ``enum:E``)."""

    def __init__(self) -> None:
        self.parent: dict[str, str] = {}

    def find(self, key: str) -> str:
        self.parent.setdefault(key, key)
        root = key
        while self.parent[root] != root:
            root = self.parent[root]
        while self.parent[key] != root:
            self.parent[key], key = root, self.parent[key]
        return root

    def union(self, a: str | None, b: str | None) -> None:
        if a is None or b is None:
            return
        ra, rb = self.find(a), self.find(b)
        if ra == rb:
            return
        # Keep an ``enum:`` key as the representative so that the class names its enumeration.
        if rb.startswith("enum:") and not ra.startswith("enum:"):
            ra, rb = rb, ra
        self.parent[rb] = ra


@dataclass
class _Facts:
    """What pass 1 learns about external declarations; pass 2 builds the IR from it."""

    internal_enums: dict[str, list[str]] = field(default_factory=dict)
    internal_symbols: dict[str, tuple[Kind, str | None]] = field(default_factory=dict)
    inputs: dict[str, Kind] = field(default_factory=dict)
    outputs: dict[str, Kind] = field(default_factory=dict)
    # owner -> {qualified parameter -> kind}, insertion order = first appearance
    input_params: dict[str, dict[str, Kind]] = field(default_factory=dict)
    behaviors: dict[str, dict[str, Kind]] = field(default_factory=dict)
    option_params: dict[str, dict[str, tuple[Kind, str | None]]] = field(default_factory=dict)
    elements: dict[str, list[str]] = field(default_factory=dict)
    unify: _UnionFind = field(default_factory=_UnionFind)
    #: pass 1: every enum element literal as (token index, element), in IC order
    literals: list[tuple[int, str]] = field(default_factory=list)
    #: after pass 1: the enumeration of the element literal at each token index
    literal_enums: dict[int, str] = field(default_factory=dict)

    def enum_of(self, key: str | None) -> str | None:
        if key is None:
            return None
        root = self.unify.find(key)
        return root[5:] if root.startswith("enum:") else None


class _Reader:
    """Recursive-descent reader over the token list (one instance per pass)."""

    def __init__(self, tokens: list[_Token], facts: _Facts, final: bool, declarations: Program | None = None) -> None:
        self.tokens = tokens
        self.declarations = declarations
        self.pos = 0
        self.facts = facts
        self.final = final
        self.option = ""
        #: option name -> token index of its first call (checked once all options are known)
        self.referenced_options: dict[str, int] = {}

    # -- token access -----------------------------------------------------------------------

    def error(self, message: str, at: int | None = None) -> ICError:
        index = self.pos if at is None else at
        if index < len(self.tokens):
            tok = self.tokens[index]
            return ICError(message, tok.line, tok.col, tok.text)
        last = self.tokens[-1] if self.tokens else _Token("", 1, 1)
        return ICError(message, last.line, last.col + len(last.text), None)

    def next(self) -> str:
        if self.pos >= len(self.tokens):
            raise self.error("unexpected end of intermediate code")
        text = self.tokens[self.pos].text
        self.pos += 1
        return text

    def count(self, what: str) -> int:
        text = self.next()
        try:
            value = int(text)
        except ValueError:
            raise self.error(f"expected the number of {what}", self.pos - 1) from None
        if value < 0:
            raise self.error(f"negative number of {what}", self.pos - 1)
        return value

    def number(self) -> tuple[float, str]:
        text = self.next()
        try:
            return float(text), text
        except ValueError:
            raise self.error("expected a number", self.pos - 1) from None

    def kind_letter(self, what: str) -> Kind:
        text = self.next()
        if text not in _KIND_LETTERS:
            raise self.error(f"expected a {what} type letter d, b or e", self.pos - 1)
        return _KIND_LETTERS[text]

    # -- whole file -------------------------------------------------------------------------

    def program(self, title: str) -> Program:
        facts = self.facts
        enums: dict[str, Enumeration] = {}
        for _ in range(self.count("internal enumerations")):
            name = self.next()
            elements = [self.next() for _ in range(self.count(f"elements of {name}"))]
            facts.internal_enums[name] = elements
            enums[name] = Enumeration(name, tuple(elements), internal=True)
            facts.unify.find(f"enum:{name}")
        for _ in range(self.count("internal symbols")):
            kind = self.kind_letter("symbol")
            enum = self.next() if kind is Kind.ENUM else None
            name = self.next()
            facts.internal_symbols[name] = (kind, enum)
            if enum is not None:
                facts.unify.union(f"enum:{enum}", f"out:{name}")
        headers: list[tuple[str, list[Parameter]]] = []
        for _ in range(self.count("options")):
            name = self.next()
            params: list[Parameter] = []
            declared = facts.option_params.setdefault(name, {})
            for _ in range(self.count(f"parameters of option {name}")):
                kind = self.kind_letter("parameter")
                enum = self.next() if kind is Kind.ENUM else None
                pname = self.next()
                params.append(Parameter(pname, kind, enum, owner=name))
                declared[pname] = (kind, enum)
                if enum is not None:
                    facts.unify.union(f"enum:{enum}", f"param:{pname}")
            headers.append((name, params))
        options: dict[str, Option] = {}
        for index, (name, params) in enumerate(headers):
            options[name] = self.option_body(name, index, tuple(params))
        agents: list[Agent] = []
        for _ in range(self.count("agents")):
            agent = self.next()
            at = self.pos
            root = self.next()
            if root not in options:
                raise self.error(f"agent {agent} names the unknown root option {root}", at)
            agents.append(Agent(agent, agent, root))
        if self.pos != len(self.tokens):
            raise self.error("unexpected token after the agent list")
        for name in self.referenced_options:
            if name not in options:
                raise self.error(f"unknown option {name}", self.referenced_options[name])
        if not self.final:
            return Program(title, {}, (), {}, {}, {}, {}, {})
        return self.build(title, options, tuple(agents), enums)

    def build(
        self, title: str, options: dict[str, Option], agents: tuple[Agent, ...], enums: dict[str, Enumeration]
    ) -> Program:
        facts = self.facts
        all_enums: dict[str, Enumeration] = {}
        for name, elements in facts.elements.items():
            if name not in facts.internal_enums:
                all_enums[name] = Enumeration(name, tuple(elements))
        all_enums.update(enums)
        inputs: dict[str, InputSymbol] = {}
        for index, (name, kind) in enumerate(facts.inputs.items()):
            params = tuple(
                Parameter(p, k, facts.enum_of(f"param:{p}") if k is Kind.ENUM else None, owner=name)
                for p, k in facts.input_params.get(name, {}).items()
            )
            inputs[name] = InputSymbol(name, kind, self.enum_for(kind, f"in:{name}"), params, index=index)
        outputs: dict[str, OutputSymbol] = {}
        index = 0
        for name, kind in facts.outputs.items():
            if name in facts.internal_symbols:
                continue
            outputs[name] = OutputSymbol(name, kind, self.enum_for(kind, f"out:{name}"), index=index)
            index += 1
        for name in sorted(facts.internal_symbols, key=str.lower):
            kind, enum = facts.internal_symbols[name]
            outputs[name] = OutputSymbol(name, kind, enum, internal=True, index=index)
            index += 1
        behaviors = {
            name: BasicBehavior(
                name,
                tuple(
                    Parameter(p, k, facts.enum_of(f"param:{p}") if k is Kind.ENUM else None, owner=name)
                    for p, k in params.items()
                ),
                index=i,
            )
            for i, (name, params) in enumerate(facts.behaviors.items())
        }
        declared = self.declarations
        if declared is not None:
            # The source declarations know what the IC cannot: every element of an external
            # enumeration in declaration order, every parameter of an input symbol or basic
            # behavior in declaration order, and the enumeration of every enum symbol.
            for name in list(all_enums):
                if name in declared.enums and not all_enums[name].internal:
                    all_enums[name] = declared.enums[name]
            for name in list(inputs):
                if name in declared.inputs:
                    inputs[name] = declared.inputs[name]
            for name in list(behaviors):
                if name in declared.behaviors:
                    behaviors[name] = declared.behaviors[name]
            for name, output in list(outputs.items()):
                if name in declared.outputs and not output.internal:
                    outputs[name] = declared.outputs[name]
            for symbol_enum in [s.enum for s in inputs.values()] + [s.enum for s in outputs.values()]:
                if symbol_enum is not None and symbol_enum not in all_enums and symbol_enum in declared.enums:
                    all_enums[symbol_enum] = declared.enums[symbol_enum]
        return Program(title, options, agents, all_enums, inputs, outputs, {}, behaviors)

    def enum_for(self, kind: Kind, key: str) -> str | None:
        # None when nothing in the IC ties the symbol to an enumeration (e.g. an enum output only
        # ever assigned from an enum input function); see ``declarations`` of :func:`read_ic`.
        return self.facts.enum_of(key) if kind is Kind.ENUM else None

    # -- options and states -----------------------------------------------------------------

    def option_body(self, name: str, index: int, params: tuple[Parameter, ...]) -> Option:
        self.option = name
        heads: list[tuple[str, str, int]] = []
        for _ in range(self.count(f"states of option {name}")):
            state = self.next()
            at = self.pos
            kind = self.next()
            if kind == "n":
                heads.append((state, "n", 0))
            elif kind in ("s", "c"):
                heads.append((state, kind, self.count("agents of a cooperative state")))
            else:
                raise self.error("expected a state kind n, s or c", at)
        names = {h[0] for h in heads}
        at = self.pos
        initial = self.next()
        if initial not in names:
            raise self.error(f"unknown initial state {initial} of option {name}", at)
        states: list[State] = []
        for state_index, (state, coop, coop_count) in enumerate(heads):
            at = self.pos
            flag = self.next()
            if flag not in ("0", "1"):
                raise self.error("expected the target-state flag 0 or 1", at)
            actions = tuple(self.action() for _ in range(self.count(f"actions of state {state}")))
            leaf_counter = [0]
            decision = self.statement(state, names, leaf_counter)
            states.append(
                State(
                    state,
                    state_index,
                    decision,
                    actions,
                    initial=state == initial,
                    target=flag == "1",
                    coop=coop,
                    coop_count=coop_count,
                )
            )
        return Option(name, index, params, tuple(states), initial)

    def statement(self, state: str, names: set[str], counter: list[int]) -> DecisionTree:
        at = self.pos
        code = self.next()
        if code == "t":
            at = self.pos
            target = self.next()
            if target not in names:
                raise self.error(f"transition to unknown state {target} of option {self.option}", at)
            leaf = counter[0]
            counter[0] += 1
            return Transition(target, stay=target == state, leaf=leaf)
        if code == "i":
            condition = self.bexp()
            then = self.statement(state, names, counter)
            otherwise = self.statement(state, names, counter)
            return If(condition, then, otherwise)
        raise self.error("expected a decision statement t or i", at)

    def action(self) -> Action:
        at = self.pos
        code = self.next()
        if code == "o":
            at = self.pos
            option = self.next()
            self.referenced_options.setdefault(option, at)
            return OptionCall(option, self.arguments(option, "option"))
        if code == "a":
            behavior = self.next()
            self.facts.behaviors.setdefault(behavior, {})
            return BehaviorCall(behavior, self.arguments(behavior, "behavior"))
        if code in _KIND_LETTERS:
            kind = _KIND_LETTERS[code]
            symbol = self.next()
            self.note_output(symbol, kind, self.pos - 1)
            if kind is Kind.DECIMAL:
                return Assignment(symbol, kind, None, self.dexp())
            if kind is Kind.BOOLEAN:
                return Assignment(symbol, kind, None, self.bexp())
            value, key = self.eexp()
            self.facts.unify.union(f"out:{symbol}", key)
            return Assignment(symbol, kind, self.facts.enum_of(f"out:{symbol}"), value)
        raise self.error("expected an action o, a, d, b or e", at)

    def arguments(self, owner: str, owner_kind: str) -> tuple[Argument, ...]:
        args: list[Argument] = []
        for _ in range(self.count(f"arguments of {owner}")):
            kind = self.kind_letter("argument")
            enum_name = self.next() if kind is Kind.ENUM else None
            at = self.pos
            param = self.next()
            if owner_kind == "option":
                declared = self.facts.option_params.get(owner)
                if declared is not None and param not in declared:
                    raise self.error(f"option {owner} has no parameter {param}", at)
            elif owner_kind == "behavior":
                self.facts.behaviors[owner].setdefault(param, kind)
            else:
                self.facts.input_params.setdefault(owner, {}).setdefault(param, kind)
            if kind is Kind.DECIMAL:
                value: Expression = self.dexp()
            elif kind is Kind.BOOLEAN:
                value = self.bexp()
            else:
                value, key = self.eexp()
                self.facts.unify.union(f"enum:{enum_name}", f"param:{param}")
                self.facts.unify.union(f"param:{param}", key)
            args.append(Argument(param, kind, enum_name, value))
        return tuple(args)

    # -- symbols ----------------------------------------------------------------------------

    def note_input(self, symbol: str, kind: Kind, at: int) -> None:
        known = self.facts.inputs.setdefault(symbol, kind)
        if known is not kind:
            raise self.error(f"input symbol {symbol} used as {kind.value} and as {known.value}", at)

    def note_output(self, symbol: str, kind: Kind, at: int) -> None:
        internal = self.facts.internal_symbols.get(symbol)
        if internal is not None and internal[0] is not kind:
            raise self.error(f"internal symbol {symbol} is {internal[0].value}, used as {kind.value}", at)
        known = self.facts.outputs.setdefault(symbol, kind)
        if known is not kind:
            raise self.error(f"output symbol {symbol} used as {kind.value} and as {known.value}", at)

    def param_ref(self, kind: Kind) -> ParameterRef:
        at = self.pos
        param = self.next()
        declared = self.facts.option_params.get(self.option, {})
        if param not in declared:
            raise self.error(f"option {self.option} has no parameter {param}", at)
        if declared[param][0] is not kind:
            raise self.error(f"parameter {param} is {declared[param][0].value}, used as {kind.value}", at)
        return ParameterRef(param, kind, declared[param][1])

    def input_ref(self, kind: Kind) -> tuple[InputRef, str]:
        at = self.pos
        symbol = self.next()
        self.note_input(symbol, kind, at)
        args = self.arguments(symbol, "input")
        key = f"in:{symbol}"
        enum = self.facts.enum_of(key) if kind is Kind.ENUM else None
        return InputRef(symbol, kind, enum, args), key

    def output_ref(self, kind: Kind) -> tuple[OutputRef, str]:
        at = self.pos
        symbol = self.next()
        self.note_output(symbol, kind, at)
        key = f"out:{symbol}"
        enum = self.facts.enum_of(key) if kind is Kind.ENUM else None
        return OutputRef(symbol, kind, enum), key

    # -- expressions ------------------------------------------------------------------------

    def dexp(self) -> Expression:
        at = self.pos
        code = self.next()
        if code == "v":
            return Number(self.number()[0])
        if code == "c":
            value, text = self.number()
            return Constant(text, value, text)
        if code == "i":
            return self.input_ref(Kind.DECIMAL)[0]
        if code == "o":
            return self.output_ref(Kind.DECIMAL)[0]
        if code == "p":
            return self.param_ref(Kind.DECIMAL)
        if code in _DECIMAL_BINARY:
            left = self.dexp()
            right = self.dexp()
            return Binary(_DECIMAL_BINARY[code], left, right, Kind.DECIMAL)
        if code == "s":
            return StateTime()
        if code == "t":
            return OptionTime()
        if code == "q":
            condition = self.bexp()
            then = self.dexp()
            otherwise = self.dexp()
            return Conditional(condition, then, otherwise, Kind.DECIMAL)
        raise self.error("expected a decimal expression", at)

    def bexp(self) -> Expression:
        at = self.pos
        code = self.next()
        if code == "v":
            text = self.next()
            if text not in ("true", "false"):
                raise self.error("expected true or false", self.pos - 1)
            return BooleanLiteral(text == "true")
        if code == "p":
            return self.param_ref(Kind.BOOLEAN)
        if code == "i":
            return self.input_ref(Kind.BOOLEAN)[0]
        if code == "o":
            return self.output_ref(Kind.BOOLEAN)[0]
        if code == "t":
            return ActionDone()
        if code == "x":
            return Conflict()
        if code == "c":
            left, lkey = self.eexp()
            right, rkey = self.eexp()
            self.facts.unify.union(lkey, rkey)
            return Binary("enum==", left, right, Kind.BOOLEAN)
        if code in ("&", "|"):
            n = self.count("operands")
            if n < 1:
                raise self.error("an n-ary && or || needs operands", at)
            operands = tuple(self.bexp() for _ in range(n))
            return Logical("&&" if code == "&" else "||", operands)
        if code == "!":
            return _not(self.bexp())
        if code in _COMPARISONS:
            left = self.dexp()
            right = self.dexp()
            return Binary(_COMPARISONS[code], left, right, Kind.BOOLEAN)
        raise self.error("expected a boolean expression", at)

    def eexp(self) -> tuple[Expression, str | None]:
        """Read an enum expression; return it with the unification key of its enumeration."""
        at = self.pos
        code = self.next()
        if code == "v":
            at = self.pos
            element = self.next()
            if not self.final:
                # Which enumeration it belongs to is known once pass 1 has unified everything.
                self.facts.literals.append((at, element))
                return EnumLiteral(element, ""), f"lit:{at}"
            element_enum = self.facts.literal_enums[at]
            return EnumLiteral(element, element_enum), f"enum:{element_enum}"
        if code == "p":
            ref = self.param_ref(Kind.ENUM)
            return ref, f"param:{ref.param}"
        if code == "i":
            return self.input_ref(Kind.ENUM)
        if code == "o":
            return self.output_ref(Kind.ENUM)
        if code == "q":
            condition = self.bexp()
            then, tkey = self.eexp()
            otherwise, okey = self.eexp()
            self.facts.unify.union(tkey, okey)
            enum = self.facts.enum_of(tkey)
            return Conditional(condition, then, otherwise, Kind.ENUM, enum), tkey
        raise self.error("expected an enumerated expression", at)


def _resolve_literals(tokens: list[_Token], facts: _Facts) -> None:
    """Give every element literal its enumeration and list the external enums' elements.

    The enumeration is the one the literal's context names (through unification); a literal
    in a context that names none gets the longest enumeration named anywhere in the IC that
    prefixes it, else its name up to the last dot (and its context then shares that one).
    """
    named = sorted((k[5:] for k in facts.unify.parent if k.startswith("enum:")), key=len, reverse=True)
    for at, element in facts.literals:
        key = f"lit:{at}"
        enum = facts.enum_of(key)
        if enum is None:
            enum = next((e for e in named if element.startswith(e + ".")), None)
            if enum is None:
                if "." not in element:
                    raise _token_error(tokens, at, "an enum element must be qualified (enum.element)")
                enum = element.rsplit(".", 1)[0]
            facts.unify.union(f"enum:{enum}", key)
        internal = facts.internal_enums.get(enum)
        if internal is not None:
            if element not in internal:
                raise _token_error(tokens, at, f"{element} is not an element of the internal enumeration {enum}")
        elif not element.startswith(enum + ".") or len(element) == len(enum) + 1:
            raise _token_error(tokens, at, f"{element} cannot be an element of enumeration {enum}")
        else:
            known = facts.elements.setdefault(enum, [])
            if element not in known:
                known.append(element)
        facts.literal_enums[at] = enum


def _token_error(tokens: list[_Token], at: int, message: str) -> ICError:
    tok = tokens[at]
    return ICError(message, tok.line, tok.col, tok.text)


def _not(operand: Expression) -> Expression:
    return Unary("!", operand, Kind.BOOLEAN)


def read_ic(text: str, declarations: Program | None = None) -> Program:
    """Read intermediate code text into a Program.

    Args:
        text: the IC, with CRLF or LF line ends.
        declarations: optionally a program (e.g. compiled from the sources) whose external
            enumerations, input and output symbols and basic behaviors replace the inferred ones
            of the same name: the IC alone cannot tell external enum elements that are never
            mentioned, their declaration order, or the parameter order of input symbols.

    Returns:
        The program; external symbols, enumerations and basic behaviors are inferred from use.

    Raises:
        ICError: the text is not well-formed intermediate code (message names line and column).
    """
    tokens, title = _tokenize(text)
    facts = _Facts()
    _Reader(tokens, facts, final=False).program(title)
    _resolve_literals(tokens, facts)
    # Pass 2 sees the complete unification classes, so every expression gets its enumeration.
    facts2 = _Facts(unify=facts.unify, elements=facts.elements, literal_enums=facts.literal_enums)
    facts2.input_params = facts.input_params
    facts2.behaviors = facts.behaviors
    return _Reader(tokens, facts2, final=True, declarations=declarations).program(title)


def read_ic_file(path: str | Path, declarations: Program | None = None) -> Program:
    """Read an intermediate-code file (``.ic``/``.dat``); see :func:`read_ic`."""
    return read_ic(Path(path).read_text(encoding="latin-1"), declarations)
