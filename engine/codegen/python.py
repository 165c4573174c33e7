"""Compile the IR to Python source, once per program and storage layout (architecture "Engine").

Per option ``o`` (index ``i``) the generated chunk, compiled with the filename ``<xabsl:o>``, holds:

* ``D{i}_{s}(...)``: the decision of state ``s`` (common decision tree inlined, §2.4).
  It returns a constant tuple ``(next_state, leaf_id, s)``: CPython keeps constant tuples
  prebuilt, so deciding allocates nothing, and the engine records the tuple as the tick's
  leaf (§2.12) with a single store.
* ``A{i}_{s}(...)``: the action list of state ``s`` (§2.2): output assignments written
  through at once, subsequent options and basic behaviors called in textual order with every
  parameter re-evaluated in the engine's order and unassigned ones reset (§2.5).
* ``O{i}(now, tick)``: one execution of the option (§2.2 ``ActionBehavior.execute`` +
  ``Option.execute``): activation bookkeeping with tick stamps instead of per-tick flag resets,
  unsigned millisecond times (§2.6), decision before actions, at most one transition.

What a tick does not need is not generated (the engine runs ~10 options per agent tick, so
every bytecode of the prologue counts):

* ``state_time`` / ``option_time`` are computed only in options that read them, and passed only
  to the functions that read them: a decision gets ``st``/``ot``/``tick`` and an action list
  ``st``/``ot``/``now``/``tick`` as far as its option's expressions use them;
* an option with a single state has no ``D``/``A`` functions: its decision and actions are
  written inline in ``O{i}`` (no dispatch and two calls less per execution); so has an option of
  up to :data:`INLINE_STATES` states, whose ``O{i}`` selects the active state's decision and the
  next state's actions with ``if s == 0: ... elif s == 1: ...`` (a comparison or two instead of
  two calls through the ``DEC``/``ACT`` tuples; ``benchmarks/engine_tick.py``: ~10 % per tick);
* an input symbol registered as an attribute of a host object is read as ``IA{k}.<attribute>``,
  one registered as an item of a host mapping as ``IA{k}['<key>']``, rather than called as
  ``I{k}()``;
* a basic-behavior call does its activation bookkeeping inline (``BB{k}``/``BE{k}`` are the
  instance and its bound ``execute``) instead of calling back into the engine.

Expressions are inlined as Python expressions (§2.8): short-circuit ``and``/``or``, exact float
comparisons, ``/`` with the 1e-7 rule inlined, ``%`` through :mod:`xabsl_studio.engine.codegen.support`.
Symbols and parameters are reached through module globals bound by the engine (see
:class:`xabsl_studio.engine.codegen.layout.Layout`): the flat lists of
:data:`xabsl_studio.engine.codegen.layout.STORAGE` (``LT``, ``S``, ``PP``...) indexed by constants, and host callables.
Every generated line remembers the option, state and IR span it came from (``origins``), which
is how faults and the debugger point back at XABSL source.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from types import CodeType

from xabsl_studio.engine.codegen.layout import Layout, OptionSlot, default_value, engine_order
from xabsl_studio.engine.codegen.support import to_int32
from xabsl_studio.engine.errors import LoadError
from xabsl_studio.engine.ir.model import (
    ActionDone,
    Argument,
    Assignment,
    BehaviorCall,
    Binary,
    BooleanLiteral,
    Conditional,
    Conflict,
    Constant,
    DecisionTree,
    EnumLiteral,
    Expression,
    If,
    InputRef,
    Logical,
    Number,
    Option,
    OptionCall,
    OptionTime,
    OutputRef,
    ParameterRef,
    Program,
    State,
    StateTime,
    Unary,
    walk,
)
from xabsl_studio.engine.types import Kind, Span

__all__ = ["CodegenError", "GeneratedOption", "GeneratedProgram", "Origin", "expression_source", "generate"]


class CodegenError(LoadError, ValueError):
    """A program the code generator cannot turn into Python (so the engine cannot load it)."""


_MASK = "0xFFFFFFFF"
_ADDITIVE = frozenset({"+", "-"})
_MULTIPLICATIVE = frozenset({"*"})
_COMPARE = {"<": "<", "<=": "<=", ">": ">", ">=": ">=", "==": "==", "!=": "!=", "enum==": "==", "enum!=": "!="}


@dataclass(frozen=True, slots=True)
class Origin:
    """Where a generated line comes from: option, state (None for the option prologue), span."""

    option: str
    state: str | None
    span: Span | None
    what: str


@dataclass
class GeneratedOption:
    """The generated source of one option, its code object and the line -> origin map."""

    name: str
    filename: str
    source: str
    code: CodeType
    origins: dict[int, Origin] = field(default_factory=dict)


@dataclass
class GeneratedProgram:
    """All generated options of a program; :meth:`bind` makes them runnable in a globals dict."""

    program: Program
    options: dict[str, GeneratedOption]

    def bind(self, namespace: dict[str, object]) -> None:
        """Define every option's functions in ``namespace`` (which holds the engine's storage)."""
        for generated in self.options.values():
            exec(generated.code, namespace)

    def origin(self, filename: str, line: int) -> Origin | None:
        """The origin of ``line`` of the chunk compiled as ``filename`` (None if unknown)."""
        for generated in self.options.values():
            if generated.filename == filename:
                return generated.origins.get(line)
        return None


def _number(value: float) -> str:
    if math.isnan(value):
        return "float('nan')"
    if math.isinf(value):
        return "_INF" if value > 0 else "(-_INF)"
    text = repr(float(value))
    return f"({text})" if text.startswith("-") else text


def _literal(value: float | bool | int) -> str:
    if isinstance(value, bool):
        return repr(value)
    if isinstance(value, float):
        return _number(value)
    return repr(value)


class _ExpressionWriter:
    """Turns one IR expression into one Python expression in the context of an option/state."""

    def __init__(self, layout: Layout, option: Option, state: State | None, reads: Program | None = None) -> None:
        self.layout = layout
        self.option = option
        self.slot: OptionSlot = layout.options[option.name]
        self.state = state
        self.temps = 0
        #: input functions whose arguments are being generated (outermost first)
        self.calling: list[str] = []
        #: the program whose ids name the reads a decision records (None: nothing is recorded)
        self.reads = reads

    def read(self, key: str, value: str) -> str:
        """``value``; when recording, also appended to the tick's reads as ``(key..., value)``.

        ``RA`` is the append of the engine's list of reads (C: about 40 ns); it returns None, so
        ``or`` yields the value the temporary holds, read once, exactly as without recording.
        """
        if self.reads is None:
            return value
        t = self.temp()
        return f"(RA(({key}, ({t} := {value}))) or {t})"

    def temp(self) -> str:
        self.temps += 1
        return f"_t{self.temps}"

    def __call__(self, e: Expression) -> str:
        match e:
            case Number(value=value):
                return _number(value)
            case Constant(value=value):
                return _number(value)
            case BooleanLiteral(value=value):
                return "True" if value else "False"
            case EnumLiteral(element=element):
                return repr(self.layout.enum_values[element])
            case ParameterRef(param=param):
                position = [p[0] for p in self.slot.params].index(param)
                declared = [p.name for p in self.option.params].index(param) if self.reads is not None else 0
                return self.read(f'"p", {declared}', f"PP[{self.slot.offset + position}]")
            case OutputRef(symbol=symbol):
                out = self.layout.outputs[symbol]
                code = -1 - self.reads.outputs[symbol].index if self.reads is not None else 0
                return self.read(str(code), f"OV[{out.index}]" if out.stored else f"OG{out.index}()")
            case InputRef():
                return self.input_call(e)
            case StateTime():
                return self.read('"st"', "st")
            case OptionTime():
                return self.read('"ot"', "ot")
            case ActionDone():
                return self.read('"done"', self.action_done())
            case Conflict():
                if self.state is None:
                    return "False"
                return self.read('"conflict"', f"CF({self.slot.index}, {self.state.index})")
            case Unary(op="-", operand=operand):
                # The compiler emits unary minus as ``0 - x`` (§3.3), so -(0.0) is +0.0.
                return f"(0.0 - {self(operand)})"
            case Unary(op="!", operand=operand):
                return f"(not {self(operand)})"
            case Binary(op="/", left=left, right=right):
                t = self.temp()
                return f"({self(left)} / ({t} if ({t} := {self(right)}) != 0 else 1e-07))"
            case Binary(op="%", left=left, right=Number(value=value) | Constant(value=value)) if to_int32(value):
                # a constant divisor is truncated once, here, not on every tick (support.modulo_by)
                return f"_modc({self(left)}, {abs(to_int32(value))})"
            case Binary(op="%", left=left, right=right):
                return f"_mod({self(left)}, {self(right)})"
            case Binary(op=op, left=left, right=right) if op in ("+", "-", "*"):
                # Python's + - * associate to the left like C++, so a left-deep chain (what the
                # parser builds for `a + b + c`) needs no inner parentheses; written flat, a long
                # sum stays under CPython's limit of 200 nested parentheses.
                group = _ADDITIVE if op in _ADDITIVE else _MULTIPLICATIVE
                terms = [f" {op} {self(right)}"]
                node = left
                while isinstance(node, Binary) and node.op in group:
                    terms.append(f" {node.op} {self(node.right)}")
                    node = node.left
                return "(" + self(node) + "".join(reversed(terms)) + ")"
            case Binary(op=op, left=left, right=right):
                return f"({self(left)} {_COMPARE[op]} {self(right)})"
            case Logical(op=op, operands=operands):
                word = " and " if op == "&&" else " or "
                return "(" + word.join(self(o) for o in operands) + ")"
            case Conditional(condition=c, then=t, otherwise=o):
                return f"({self(t)} if {self(c)} else {self(o)})"
        raise TypeError(f"cannot generate code for {e!r}")

    def action_done(self) -> str:
        if self.state is None:
            return "False"
        terms = []
        for name in self.state.subsequent_options:
            c = self.layout.options[name].index
            # wasActive of the child: executed in the previous tick (also when it already ran
            # earlier in this tick, which only B1 allows), and its active state is a target.
            was = f"(LT[{c}] == tick - 1 or (LT[{c}] == tick and PV[{c}] == tick - 1))"
            terms.append(f"({was} and TG{c}[S[{c}]])")
        if not terms:
            return "False"
        return "(" + " or ".join(terms) + ")"

    def input_call(self, ref: InputRef) -> str:
        slot = self.layout.inputs[ref.symbol]
        code = str(self.reads.inputs[ref.symbol].index) if self.reads is not None else ""
        if slot.attribute is not None:
            return self.read(code, f"IA{slot.index}.{slot.attribute}")
        if slot.key is not None:
            return self.read(code, f"IA{slot.index}[{slot.key!r}]")
        if not slot.params:
            return self.read(code, f"I{slot.index}()")
        assigned = {a.param: a for a in ref.args}
        inner = [node for a in ref.args for node in walk(a.value) if isinstance(node, InputRef)]
        nested = any(node.args for node in inner)
        same = any(node.symbol == ref.symbol for node in inner)
        in_order = engine_order(slot.params) == list(range(len(slot.params)))
        self.calling.append(ref.symbol)
        try:
            if not same and ref.symbol not in self.calling[:-1] and (not nested or in_order):
                # No call of the same symbol inside the arguments and no enclosing one: the
                # shared storage is unobservable, so the arguments go straight into the call
                # in registration order. Host functions inside the arguments (``abs(value =
                # angle_diff(...))``) are allowed when that order is also the engine's, so
                # they run in the same order either way.
                values = [self.arg_or_default(assigned.get(name), kind) for name, kind in slot.params]
                if self.reads is not None:
                    return self.recorded_call(ref, slot.index, code, values)
                return f"I{slot.index}({', '.join(values)})"
            # Set the shared parameter storage one parameter at a time in the engine's order,
            # so a nested call of the same symbol clobbers earlier arguments exactly as in the
            # original engine (§2.5).
            parts = [
                f"FS{slot.index}({i}, {self.arg_or_default(assigned.get(slot.params[i][0]), slot.params[i][1])})"
                for i in engine_order(slot.params)
            ]
        finally:
            self.calling.pop()
        if self.reads is not None:
            # The call leaves its arguments in the shared storage: record them from there.
            stored = [f"FP{slot.index}[{i}]" for i in range(len(slot.params))]
            result = self.temp()
            call = f"({result} := I{slot.index}(*FP{slot.index}))"
            parts.append(f"({call}, RA(({code}, {self.declared(ref, stored)}, {result})))[0]")
        else:
            parts.append(f"I{slot.index}(*FP{slot.index})")
        return f"({', '.join(parts)})[{len(parts) - 1}]"

    def recorded_call(self, ref: InputRef, index: int, code: str, values: list[str]) -> str:
        """``I{index}(values...)`` (arguments in registration order), recorded as ``(code, args..., result)``.

        The arguments are evaluated once, in the same order as without recording, into
        temporaries; the read lists them in the order the symbol declares its parameters (so a
        reader needs no host table), then the result.
        """
        temps = [self.temp() for _ in values]
        result = self.temp()
        args = ", ".join(f"({t} := {v})" for t, v in zip(temps, values, strict=True))
        return f"(({result} := I{index}({args})), RA(({code}, {self.declared(ref, temps)}, {result})))[0]"

    def declared(self, ref: InputRef, registered: list[str]) -> str:
        """``registered`` (one text per parameter in registration order) in the symbol's declaration order."""
        assert self.reads is not None
        slot = self.layout.inputs[ref.symbol]
        position = {name: i for i, (name, _) in enumerate(slot.params)}
        return ", ".join(registered[position[p.name]] for p in self.reads.inputs[ref.symbol].params)

    def arg_or_default(self, argument: Argument | None, kind: Kind) -> str:
        if argument is None:
            return _literal(default_value(kind))
        return self(argument.value)


def expression_source(layout: Layout, option: Option, state: State | None, expression: Expression) -> str:
    """The Python expression the generator inlines for ``expression`` (used by the debugger).

    Its free names are the engine globals plus ``st``, ``ot`` and ``tick``.
    """
    return _ExpressionWriter(layout, option, state)(expression)


def _reads(expressions: list[Expression], node_type: type) -> bool:
    return any(isinstance(node, node_type) for e in expressions for node in walk(e))


def _conditions(tree: DecisionTree) -> list[Expression]:
    found: list[Expression] = []
    while isinstance(tree, If):
        found.append(tree.condition)
        found.extend(_conditions(tree.then))
        tree = tree.otherwise
    return found


def _action_expressions(state: State) -> list[Expression]:
    found: list[Expression] = []
    for action in state.actions:
        if isinstance(action, Assignment):
            found.append(action.value)
        else:
            found.extend(a.value for a in action.args)
    return found


@dataclass(frozen=True, slots=True)
class _Uses:
    """What the code of one option needs from its prologue (see the module docstring)."""

    #: the decisions read ``state_time`` (also: the tick records it for the debugger)
    decision_st: bool
    #: the actions read ``state_time``
    action_st: bool
    #: some expression reads ``option_time``
    ot: bool
    #: parameter lists of the decision and action functions
    decision_params: str
    action_params: str

    @classmethod
    def of(cls, option: Option) -> _Uses:
        decisions = [c for state in option.states for c in _conditions(state.decision)]
        actions = [e for state in option.states for e in _action_expressions(state)]
        decision_st = _reads(decisions, StateTime)
        action_st = _reads(actions, StateTime)
        ot = _reads(decisions + actions, OptionTime)
        calls = any(not isinstance(a, Assignment) for state in option.states for a in state.actions)
        decision_params = [
            n
            for n, used in (
                ("st", decision_st),
                ("ot", _reads(decisions, OptionTime)),
                ("tick", _reads(decisions, ActionDone)),
            )
            if used
        ]
        action_params = [
            n
            for n, used in (
                ("st", action_st),
                ("ot", _reads(actions, OptionTime)),
                ("now", calls),
                ("tick", calls or _reads(actions, ActionDone)),
            )
            if used
        ]
        return cls(decision_st, action_st, ot, ", ".join(decision_params), ", ".join(action_params))


class _OptionWriter:
    """Writes the chunk of one option."""

    def __init__(self, program: Program, layout: Layout, option: Option, reads: bool = False) -> None:
        self.program = program
        self.layout = layout
        self.option = option
        self.slot = layout.options[option.name]
        self.uses = _Uses.of(option)
        self.lines: list[str] = []
        self.origins: dict[int, Origin] = {}
        #: decisions record what they read (see :func:`generate`); only options with conditions
        self.reads: Program | None = (
            program if reads and any(isinstance(s.decision, If) for s in option.states) else None
        )

    def emit(self, text: str, state: State | None = None, span: Span | None = None, what: str = "") -> None:
        self.lines.append(text)
        self.origins[len(self.lines)] = Origin(self.option.name, state.name if state else None, span, what)

    @property
    def single(self) -> bool:
        """One state: decision and actions are inlined into ``O{i}`` (nothing to dispatch)."""
        return len(self.option.states) == 1

    @property
    def inline(self) -> bool:
        """Decisions and action lists are written into ``O{i}``, selected by ``if s == k`` chains.

        True for options of up to :data:`INLINE_STATES` states (a comparison or two cost less
        than the two calls through ``DEC``/``ACT`` they replace) whose decision trees are not
        nested so deep that two more levels of indentation could reach CPython's limit.
        """
        states = self.option.states
        return len(states) <= INLINE_STATES and all(_depth(s.decision) <= INLINE_DEPTH for s in states)

    def write(self) -> str:
        i = self.slot.index
        if not self.single and not self.inline:
            for state in self.option.states:
                self.decide(state)
                self.act(state)
            self.emit(f"DEC{i} = ({', '.join(f'D{i}_{s.index}' for s in self.option.states)},)")
            self.emit(f"ACT{i} = ({', '.join(f'A{i}_{s.index}' for s in self.option.states)},)")
        self.emit(f"TG{i} = {tuple(self.slot.targets)!r}")
        if any(self.slot.coop):
            self.emit(f"CO{i} = {tuple(self.slot.coop)!r}")
        self.execute()
        return "\n".join(self.lines) + "\n"

    # -- decide -----------------------------------------------------------------------------

    def decide(self, state: State) -> None:
        i = self.slot.index
        self.emit(f"def D{i}_{state.index}({self.uses.decision_params}):", state, state.span, "decision")
        self.tree(state, state.decision, self.writer(state), "    ", "return ")
        self.emit("")

    def tree(
        self, state: State, node: DecisionTree, writer: _ExpressionWriter, indent: str, leaf: str, nxt: str = ""
    ) -> None:
        """The decision tree of ``state``; a leaf is ``{leaf}(next, leaf id, state)`` (then ``{nxt} = next``)."""
        keyword = "if"
        while isinstance(node, If):
            self.emit(f"{indent}{keyword} {writer(node.condition)}:", state, node.span, "condition")
            self.tree(state, node.then, writer, indent + "    ", leaf, nxt)
            node = node.otherwise
            # ``else if`` chains (the inlined common decision tree) become ``elif``: no
            # nesting, so long chains never reach Python's indentation limit.
            keyword = "elif"
        if keyword == "elif":
            self.emit(f"{indent}else:", state)
            indent += "    "
        target = self.option.state(node.target or state.name).index
        self.emit(f"{indent}{leaf}({target}, {node.leaf}, {state.index})", state, node.span, "transition")
        if nxt:
            self.emit(f"{indent}{nxt} = {target}", state)

    # -- act --------------------------------------------------------------------------------

    def act(self, state: State) -> None:
        i = self.slot.index
        self.emit(f"def A{i}_{state.index}({self.uses.action_params}):", state, state.span, "actions")
        self.actions(state, "    ")
        self.emit("")

    def actions(self, state: State, indent: str) -> None:
        """The action list of ``state`` as statements at ``indent`` (``pass`` if empty)."""
        writer = _ExpressionWriter(self.layout, self.option, state)
        body = len(self.lines)
        for position, action in enumerate(state.actions):
            if isinstance(action, Assignment):
                out = self.layout.outputs[action.symbol]
                site = self.layout.sites[(self.option.name, state.index, position)]
                self.emit(f"{indent}v = {writer(action.value)}", state, action.span, f"assignment {action.symbol}")
                self.emit(f"{indent}AV[{site}] = v", state, action.span)
                if out.stored:
                    self.emit(f"{indent}OV[{out.index}] = v", state, action.span)
                else:
                    self.emit(f"{indent}OS{out.index}(v)", state, action.span)
            elif isinstance(action, OptionCall):
                self.option_call(state, action, writer, indent)
            elif isinstance(action, BehaviorCall):
                self.behavior_call(state, action, writer, indent)
        if len(self.lines) == body:
            self.emit(f"{indent}pass", state)

    def option_call(self, state: State, call: OptionCall, writer: _ExpressionWriter, indent: str) -> None:
        callee = self.layout.options[call.option]
        assigned = {a.param: a for a in call.args}
        what = f"call of option {call.option}"
        for position in engine_order(callee.params):
            name, kind = callee.params[position]
            value = writer.arg_or_default(assigned.get(name), kind)
            self.emit(f"{indent}PP[{callee.offset + position}] = {value}", state, call.span, what)
        self.emit(f"{indent}O{callee.index}(now, tick)", state, call.span, what)

    def behavior_call(self, state: State, call: BehaviorCall, writer: _ExpressionWriter, indent: str) -> None:
        callee = self.layout.behaviors[call.behavior]
        assigned = {a.param: a for a in call.args}
        what = f"call of basic behavior {call.behavior}"

        def e(text: str) -> None:
            self.emit(indent + text, state, call.span, what)

        if callee.hook:
            e("changed = False")
        for position in engine_order(callee.params):
            name, kind = callee.params[position]
            value = writer.arg_or_default(assigned.get(name), kind)
            slot = callee.offset + position
            if callee.hook:
                e(f"v = {value}")
                e(f"if BP[{slot}] != v:")
                e(f"    BP[{slot}] = v")
                e("    changed = True")
            else:
                e(f"BP[{slot}] = {value}")
        # §2.2 ActionBehavior.execute, inline (the engine's ``run_behavior`` does the same for
        # root actions): tick stamps as for options, parametersChanged, activation time, execute.
        k = callee.index
        e(f"blt = BLT[{k}]")
        e("if blt != tick:")
        e(f"    BPV[{k}] = blt")
        e(f"    BLT[{k}] = tick")
        e("    bwas = blt == tick - 1")
        e("else:")
        e(f"    bwas = BPV[{k}] == tick - 1")
        if callee.hook:
            e("if changed:")
            e(f"    BB{k}.parameters_changed()")
        e("if not bwas:")
        e(f"    BTA[{k}] = now")
        e(f"BB{k}.time_of_execution = (now - BTA[{k}]) & {_MASK}")
        e(f"BE{k}()")

    # -- execute ----------------------------------------------------------------------------

    def execute(self) -> None:
        i = self.slot.index
        uses = self.uses
        single = self.single
        e = self.emit
        st_now = f"float((now - TS[{i}]) & {_MASK})"
        e(f"def O{i}(now, tick):", None, self.option.span, "option")
        e(f"    lt = LT[{i}]")
        e("    if lt != tick:")
        e(f"        PV[{i}] = lt")
        e(f"        LT[{i}] = tick")
        e("        was = lt == tick - 1")
        e("    else:")
        e(f"        was = DX({i}, tick)")
        continued = []
        if not single:
            continued.append(f"s = S[{i}]")
        if uses.ot:
            continued.append(f"ot = float((now - TA[{i}]) & {_MASK})")
        if uses.decision_st:
            continued.append(f"st = {st_now}")
        if continued:
            e("    if was:")
            for line in continued:
                e(f"        {line}")
            e("    else:")
        else:
            e("    if not was:")
        # (Re)activation: the initial state, state_time and option_time start at 0 (§2.2).
        e(f"        TA[{i}] = now")
        if not single:
            e(f"        s = {self.slot.initial}")
            e(f"        S[{i}] = s")
        e(f"        TS[{i}] = now")
        if uses.ot:
            e("        ot = 0.0")
        if uses.decision_st:
            e("        st = 0.0")
        if self.reads is not None:
            # The reads of this decision follow the option's id in the tick's list of reads.
            e(f"    RA({self.option.index})", None, self.option.span, "option")
        if single:
            # A single state can only stay: the decision only picks the leaf to record.
            state = self.option.states[0]
            self.tree(state, state.decision, self.writer(state), "    ", f"LF[{i}] = ")
            if uses.decision_st:
                e(f"    SD[{i}] = st")
            if uses.action_st and not uses.decision_st:
                e(f"    st = {st_now}")
            self.actions(state, "    ")
            return
        inline = self.inline
        if inline:
            # Each leaf records itself and sets the next state directly: no tuple to unpack.
            leaf = f"LF[{i}] = "
            pad = "        "
            self.dispatch("s", lambda state: self.tree(state, state.decision, self.writer(state), pad, leaf, "n"))
        else:
            e(f"    r = DEC{i}[s]({uses.decision_params})")
            e(f"    LF[{i}] = r")
            e("    n = r[0]")
        if uses.decision_st:
            # What ``state_time`` the decision saw, for the debugger's explanation (§2.12).
            e(f"    SD[{i}] = st")
        if any(self.slot.coop):
            e(f"    if n != s and CO{i}[n] and not CC({i}, n, s):")
            e("        n = s")
        e("    if n != s:")
        e(f"        S[{i}] = n")
        e(f"        TS[{i}] = now")
        if uses.action_st:
            e("        st = 0.0")
            if not uses.decision_st:
                e("    else:")
                e(f"        st = {st_now}")
        if inline:
            self.dispatch("n", lambda state: self.actions(state, "        "))
        else:
            e(f"    ACT{i}[n]({uses.action_params})")

    def writer(self, state: State) -> _ExpressionWriter:
        """A fresh expression writer for the decision of ``state`` (recording its reads if asked)."""
        return _ExpressionWriter(self.layout, self.option, state, self.reads)

    def dispatch(self, variable: str, body: Callable[[State], None]) -> None:
        """``if {variable} == 0: body(state 0) elif ... else: body(last state)`` at the prologue's level."""
        states = self.option.states
        for k, state in enumerate(states):
            if k == 0:
                self.emit(f"    if {variable} == {state.index}:", state, state.span)
            elif k < len(states) - 1:
                self.emit(f"    elif {variable} == {state.index}:", state, state.span)
            else:
                self.emit("    else:", state, state.span)
            body(state)


#: Options with at most this many states are inlined into ``O{i}`` (see ``_OptionWriter.inline``).
INLINE_STATES = 8
#: ... if no decision tree is nested deeper than this (CPython allows 100 indentation levels).
INLINE_DEPTH = 60


def _depth(tree: DecisionTree) -> int:
    """How deep ``if`` statements nest in ``tree`` (an ``else if`` chain counts once: it becomes ``elif``)."""
    depth = 0
    stack = [(tree, 0)]
    while stack:
        node, level = stack.pop()
        while isinstance(node, If):
            stack.append((node.then, level + 1))
            node = node.otherwise
        depth = max(depth, level)
    return depth


_CACHE: dict[tuple[int, tuple[object, ...], bool], GeneratedProgram] = {}
_CACHE_SIZE = 32


def generate(program: Program, layout: Layout, reads: bool = False) -> GeneratedProgram:
    """Generate and compile the Python code of ``program`` for ``layout``.

    Compiled once: engines that load the same program with equal layouts (a team of agents)
    share the code objects and only bind their own storage.

    With ``reads``, every decision records what it read into the engine's list of reads (the
    global ``RA`` is its ``append``), for the debugger's "why" (``Engine.record_reads``): the
    option's IR id before its decision, then per read a tuple ``(key..., value)`` -- an input
    symbol ``(input id, value)``, an input function ``(input id, args..., result)`` with the
    arguments in the order the symbol declares its parameters, an output or internal symbol
    ``(-1 - output id, value)``, a parameter of the option ``("p", declared position, value)``,
    ``("st", state_time)``, ``("ot", option_time)``, ``("done", action_done)``,
    ``("conflict", value)``. The behavior computes exactly what it computes without recording
    (the same reads and calls, in the same order); actions record nothing.
    """
    key = (id(program), layout.key(), reads)
    cached = _CACHE.get(key)
    if cached is not None and cached.program is program:
        return cached
    options: dict[str, GeneratedOption] = {}
    for option in program.options.values():
        writer = _OptionWriter(program, layout, option, reads)
        source = writer.write()
        filename = f"<xabsl:{option.name}>"
        try:
            code = compile(source, filename, "exec")
        except (SyntaxError, RecursionError, MemoryError) as error:
            # Only pathological sources get here: expressions nested deeper than CPython's
            # parser accepts (about 200 levels of parentheses the user wrote).
            raise CodegenError(
                f"option {option.name}: an expression is nested too deeply to compile to Python "
                f"({type(error).__name__}: {getattr(error, 'msg', error)})"
            ) from None
        options[option.name] = GeneratedOption(option.name, filename, source, code, writer.origins)
    generated = GeneratedProgram(program, options)
    if len(_CACHE) >= _CACHE_SIZE:
        _CACHE.pop(next(iter(_CACHE)))
    _CACHE[key] = generated
    return generated


#: Signature of a generated option function.
OptionFunction = Callable[[int, int], None]
