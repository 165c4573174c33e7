"""The checker: resolves names, checks types and builds the IR of every option (§1.4, §2.4).

Runs after the declaration passes of :mod:`xabsl_studio.engine.lang.symbols`. For each option it lowers
expressions to typed IR expressions (folding unary minus on literals, flattening ``&&``/``||``
chains, §3.3), resolves enum literals only in enum context, resolves calls to options, basic
behaviors and parameterized input symbols, and builds each state's decision tree with the
common decision tree inlined in front (§2.4) and its leaves numbered.

A sub-expression with an error is "poisoned" (``None``): its parents report nothing more, so
one mistake gives one diagnostic.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Callable, Iterable

from xabsl_studio.engine import ir
from xabsl_studio.engine.lang import ast
from xabsl_studio.engine.lang.diagnostics import Diagnostics
from xabsl_studio.engine.lang.symbols import OptionHeader, SymbolTable
from xabsl_studio.engine.types import Kind, Span

_BUILTINS: dict[str, Callable[[Span | None], ir.Expression]] = {
    "state_time": ir.StateTime,
    "option_time": ir.OptionTime,
    "action_done": ir.ActionDone,
    "conflict": ir.Conflict,
}
_ARITHMETIC = frozenset(ir.ARITHMETIC_OPERATORS)
_ORDERING = frozenset({"<", "<=", ">", ">="})
_EQUALITY = frozenset({"==", "!="})


def _did_you_mean(name: str, candidates: Iterable[str]) -> str:
    """`` (did you mean 'x'?)`` for a close match, else ``""``."""
    matches = difflib.get_close_matches(name, list(candidates), n=1, cutoff=0.75)
    return f" (did you mean '{matches[0]}'?)" if matches else ""


def _describe(expr: ir.Expression) -> str:
    if expr.kind is Kind.ENUM:
        return f"enum '{expr.enum}'"
    return str(expr.kind.value)


class OptionChecker:
    """Builds the IR of one option; reports into the shared diagnostics."""

    def __init__(
        self, table: SymbolTable, header: OptionHeader, diagnostics: Diagnostics, usage: set[tuple[str, str]]
    ) -> None:
        self.table = table
        self.header = header
        self.name = header.decl.name.text
        self.text = header.file.text
        self.diagnostics = diagnostics
        #: (class, name) of every symbol this option uses, for the unused-symbol lint
        self.usage = usage
        self.state_names: set[str] = {s.name.text for s in header.decl.states}

    # ================================================================== expressions

    def expression(self, node: ast.Expr, enum: str | None = None) -> ir.Expression | None:
        """Lower one expression; ``enum`` is the enumeration an enum context expects."""
        match node:
            case ast.NumberLit(text=text, span=span):
                return ir.Number(float(text), span)
            case ast.BoolLit(value=value, span=span):
                return ir.BooleanLiteral(value, span)
            case ast.Builtin(name=name, span=span):
                return _BUILTINS[name](span)
            case ast.Paren(inner=inner):
                return self.expression(inner, enum)
            case ast.Ident(name=name, span=span):
                return self.identifier(name, span, enum)
            case ast.Call():
                return self.input_call(node)
            case ast.UnaryOp():
                return self.unary(node)
            case ast.BinaryOp():
                return self.binary(node)
            case ast.CondOp():
                return self.conditional(node, enum)
        raise AssertionError(f"unknown expression node {node!r}")

    def identifier(self, name: str, span: Span, enum: str | None) -> ir.Expression | None:
        """Resolve a name: an enum element in enum context, else a constant, parameter or symbol."""
        if enum is not None:
            element = self.table.element(enum, name)
            if element is not None:
                self.usage.add(("enum", enum))
                return ir.EnumLiteral(element, enum, span)
        matches: list[ir.Expression] = []
        if name in self.table.constants:
            constant = self.table.constants[name]
            matches.append(ir.Constant(name, constant.value, constant.text, span))
        param = self.option_parameter(name)
        if param is not None:
            matches.append(ir.ParameterRef(param.name, param.kind, param.enum, span))
        if name in self.table.inputs:
            symbol = self.table.inputs[name]
            self.warn_missing(symbol.name, symbol.params, set(), span, "input symbol")
            matches.append(ir.InputRef(name, symbol.kind, symbol.enum, (), span))
        if name in self.table.outputs:
            output = self.table.outputs[name]
            matches.append(ir.OutputRef(name, output.kind, output.enum, span))
        if not matches:
            hint = f" (and no element of enumeration '{enum}')" if enum else ""
            if (enum is None and name in self.table.elements.values()) or self.is_enum_element(name):
                hint = " (enum elements can only be used where an enum value is expected)"
            if not hint:
                known = [*self.table.constants, *self.table.inputs, *self.table.outputs, *self.header.params]
                hint = _did_you_mean(name, known)
            self.diagnostics.add(
                "no-matching-symbol",
                f"no matching symbol found for '{name}': no constant, option parameter, input or "
                f"output symbol has this name{hint}",
                span,
            )
            return None
        if len(matches) > 1:
            kinds = ", ".join(type(m).__name__ for m in matches)
            self.diagnostics.add("multiple-matching-symbols", f"'{name}' names several things ({kinds})", span)
            return None
        self.note_use(matches[0])
        return matches[0]

    def is_enum_element(self, name: str) -> bool:
        """Whether ``name`` is an element of some enumeration (short or qualified), for a hint."""
        return any(q.endswith("." + name) or q == name for q in self.table.elements)

    def option_parameter(self, name: str) -> ir.Parameter | None:
        """This option's parameter named ``name`` (``@x`` or qualified), if any."""
        if name in self.header.params:
            return self.header.params[name]
        for param in self.header.params.values():
            if param.name == name:
                return param
        return None

    def note_use(self, expr: ir.Expression) -> None:
        """Record the use of a constant or symbol for the unused-symbol lint."""
        match expr:
            case ir.Constant(name=name):
                self.usage.add(("constant", name))
            case ir.InputRef(symbol=name):
                self.usage.add(("input", name))
            case ir.OutputRef(symbol=name):
                self.usage.add(("output-read", name))

    def input_call(self, node: ast.Call) -> ir.Expression | None:
        """Lower a call of a parameterized input symbol in an expression."""
        name = node.name.text
        symbol = self.table.inputs.get(name)
        if symbol is None:
            if name in self.table.options or name in self.table.behaviors:
                self.diagnostics.add(
                    "not-callable",
                    f"'{name}' is an option or basic behavior: call it as an action, not in an expression",
                    node.name.span,
                )
            else:
                self.diagnostics.add(
                    "no-matching-symbol", f"no matching input symbol found for '{name}'", node.name.span
                )
            return None
        self.usage.add(("input", name))
        args = self.arguments(name, symbol.params, node.args, node.name.span, "input symbol")
        if args is None:
            return None
        return ir.InputRef(name, symbol.kind, symbol.enum, args, node.span)

    def arguments(
        self,
        callee: str,
        params: tuple[ir.Parameter, ...],
        args: list[ast.CallArg],
        call_span: Span,
        what: str,
    ) -> tuple[ir.Argument, ...] | None:
        """Lower the arguments of a call; None (after reporting) if any is wrong."""
        by_short = {p.short_name: p for p in params}
        given: set[str] = set()
        lowered: list[ir.Argument] = []
        ok = True
        for arg in args:
            short = arg.name.text[1:] if arg.name.text.startswith("@") else arg.name.text
            param = by_short.get(short)
            if param is None:
                known = ", ".join(by_short) or "none"
                self.diagnostics.add(
                    "unknown-parameter",
                    f"{what} '{callee}' has no parameter '{short}' (parameters: {known})",
                    arg.name.span,
                )
                ok = False
                continue
            if short in given:
                self.diagnostics.add("parameter-set-twice", f"parameter '{short}' is set more than once", arg.name.span)
                ok = False
                continue
            given.add(short)
            value = self.expression(arg.value, param.enum if param.kind is Kind.ENUM else None)
            if value is None:
                ok = False
                continue
            if not self.same_type(value, param.kind, param.enum, arg.value.span, f"parameter '{short}'"):
                ok = False
                continue
            lowered.append(ir.Argument(param.name, param.kind, param.enum, value, arg.span))
        self.warn_missing(callee, params, given, call_span, what)
        return tuple(lowered) if ok else None

    def warn_missing(
        self, callee: str, params: tuple[ir.Parameter, ...], given: set[str], span: Span, what: str
    ) -> None:
        """Warn about each parameter a call leaves out (it gets 0, false or enum value 0)."""
        for param in params:
            if param.short_name not in given:
                default = {Kind.DECIMAL: "0", Kind.BOOLEAN: "false", Kind.ENUM: "the enum value 0"}[param.kind]
                self.diagnostics.add(
                    "parameter-missing",
                    f"{what} '{callee}' is called without parameter '{param.short_name}'; it gets {default}",
                    span,
                )

    def same_type(self, value: ir.Expression, kind: Kind, enum: str | None, span: Span, what: str) -> bool:
        """Whether ``value`` has type ``kind`` (and enumeration ``enum``); reports a mismatch."""
        if value.kind is not kind:
            expected = f"enum '{enum}'" if kind is Kind.ENUM else kind.value
            self.diagnostics.add(
                "type-mismatch", f"type mismatch: {what} expects {expected}, found {_describe(value)}", span
            )
            return False
        if kind is Kind.ENUM and value.enum != enum:
            self.diagnostics.add(
                "mismatching-domain",
                f"{what} expects a value of enumeration '{enum}', found one of '{value.enum}'",
                span,
            )
            return False
        return True

    def expect(self, value: ir.Expression, kind: Kind, op: str, span: Span) -> bool:
        """Whether an operand of ``op`` has the type ``kind``; reports a mismatch."""
        if value.kind is kind:
            return True
        shown = f" '{self.source(value.span)}'" if value.span is not None else ""
        self.diagnostics.add(
            "type-mismatch",
            f"type mismatch on '{op}': it takes {kind.value} operands, found {_describe(value)}{shown}",
            span,
        )
        return False

    def unary(self, node: ast.UnaryOp) -> ir.Expression | None:
        """Lower ``-x`` (a literal folds) or ``!x``."""
        operand = self.expression(node.operand)
        if operand is None:
            return None
        if node.op == "-":
            if not self.expect(operand, Kind.DECIMAL, "-", node.op_span):
                return None
            if isinstance(operand, ir.Number):
                # the compiler folds a minus in front of a literal: `-5` is `v -5` (§3.3)
                return ir.Number(-operand.value, node.span)
            return ir.Unary("-", operand, Kind.DECIMAL, node.span)
        if not self.expect(operand, Kind.BOOLEAN, "!", node.op_span):
            return None
        return ir.Unary("!", operand, Kind.BOOLEAN, node.span)

    def binary(self, node: ast.BinaryOp) -> ir.Expression | None:
        """Lower arithmetic and (enum) comparisons; ``&&``/``||`` go to :meth:`logical`."""
        op = node.op
        if op in ("&&", "||"):
            return self.logical(node)
        left = self.expression(node.left)
        if left is None:
            self.expression(node.right)  # still report problems on the right side
            return None
        if op in _EQUALITY and left.kind is Kind.ENUM:
            right = self.expression(node.right, left.enum)
            if right is None:
                return None
            if right.kind is not Kind.ENUM:
                self.expect(right, Kind.ENUM, op, node.op_span)
                return None
            if right.enum != left.enum:
                self.diagnostics.add(
                    "mismatching-domain",
                    f"'{op}' has mismatching domain: enumeration '{left.enum}' against '{right.enum}'",
                    node.op_span,
                )
                return None
            return ir.Binary("enum" + op, left, right, Kind.BOOLEAN, node.span)
        right = self.expression(node.right)
        if right is None:
            return None
        if op in _EQUALITY and left.kind is Kind.BOOLEAN:
            self.diagnostics.add(
                "type-mismatch",
                f"type mismatch on '{op}': booleans cannot be compared (use !, && and ||)",
                node.op_span,
            )
            return None
        if not (
            self.expect(left, Kind.DECIMAL, op, node.op_span) and self.expect(right, Kind.DECIMAL, op, node.op_span)
        ):
            return None
        kind = Kind.DECIMAL if op in _ARITHMETIC else Kind.BOOLEAN
        return ir.Binary(op, left, right, kind, node.span)

    def logical(self, node: ast.BinaryOp) -> ir.Expression | None:
        """Lower ``&&``/``||`` into one n-ary node, flattening chains of the same operator."""
        operands: list[ir.Expression] = []
        ok = True
        for side in (node.left, node.right):
            value = self.expression(side)
            if value is None:
                ok = False
                continue
            if not self.expect(value, Kind.BOOLEAN, node.op, node.op_span):
                ok = False
                continue
            # chains are n-ary, also through parentheses (§3.3)
            if isinstance(value, ir.Logical) and value.op == node.op:
                operands.extend(value.operands)
            else:
                operands.append(value)
        if not ok:
            return None
        return ir.Logical(node.op, tuple(operands), node.span)

    def conditional(self, node: ast.CondOp, enum: str | None) -> ir.Expression | None:
        """Lower ``c ? a : b``; ``enum`` is the enumeration an enum context expects."""
        condition = self.expression(node.condition)
        then = self.expression(node.then, enum)
        if then is None or condition is None:
            if then is None:
                self.expression(node.otherwise, enum)
            return None
        otherwise = self.expression(node.otherwise, enum or then.enum)
        if otherwise is None:
            return None
        if not self.expect(condition, Kind.BOOLEAN, "?", node.op_span):
            return None
        if then.kind is Kind.BOOLEAN:
            self.diagnostics.add(
                "boolean-conditional",
                "a conditional expression with boolean values is not supported by the engine; "
                "write (c && a) || (!c && b)",
                node.op_span,
            )
            return None
        if not self.same_type(otherwise, then.kind, then.enum, node.otherwise.span, "the else-branch of '?:'"):
            return None
        return ir.Conditional(condition, then, otherwise, then.kind, then.enum, node.span)

    def condition(self, node: ast.Expr) -> ir.Expression | None:
        """Lower a condition: an expression that must be boolean."""
        value = self.expression(node)
        if value is None:
            return None
        if value.kind is not Kind.BOOLEAN:
            self.diagnostics.add("type-mismatch", f"a condition must be boolean, found {_describe(value)}", node.span)
            return None
        return value

    def source(self, span: Span) -> str:
        """The source text of ``span`` in this option's file, whitespace runs collapsed."""
        return " ".join(self.text[span.start : span.end].split())

    # ================================================================== actions

    def action(self, node: ast.ActionStmt) -> ir.Action | None:
        """Lower one action: an assignment or a call."""
        if isinstance(node, ast.Assign):
            return self.assignment(node)
        return self.call(node)

    def assignment(self, node: ast.Assign) -> ir.Action | None:
        """Lower ``symbol = value;`` to an output or internal symbol."""
        name = node.target.text
        symbol = self.table.outputs.get(name)
        if symbol is None:
            if name in self.table.inputs or name in self.table.constants or self.option_parameter(name):
                self.diagnostics.add(
                    "not-assignable",
                    f"'{name}' cannot be assigned: only output and internal symbols can",
                    node.target.span,
                )
            else:
                self.diagnostics.add(
                    "no-matching-symbol", f"no output or internal symbol named '{name}'", node.target.span
                )
            self.expression(node.value)
            return None
        self.usage.add(("output-write", name))
        value = self.expression(node.value, symbol.enum if symbol.kind is Kind.ENUM else None)
        if value is None or not self.same_type(value, symbol.kind, symbol.enum, node.value.span, f"'{name}'"):
            return None
        return ir.Assignment(name, symbol.kind, symbol.enum, value, node.span)

    def call(self, node: ast.CallAction) -> ir.Action | None:
        """Lower a call of a subsequent option or basic behavior."""
        name = node.name.text
        option = self.table.options.get(name) if node.explicit in (None, "option") else None
        behavior = self.table.behaviors.get(name) if node.explicit in (None, "behavior") else None
        if option is not None and behavior is not None:
            self.diagnostics.add(
                "multiple-matching-symbols",
                f"'{name}' is both an option and a basic behavior: write '{name} option(...)' "
                f"or '{name} behavior(...)'",
                node.name.span,
            )
            return None
        if option is not None:
            self.usage.add(("option", name))
            params = tuple(option.params.values())
            args = self.arguments(name, params, node.args, node.name.span, "option")
            return None if args is None else ir.OptionCall(name, args, node.span)
        if behavior is not None:
            self.usage.add(("behavior", name))
            args = self.arguments(name, behavior.params, node.args, node.name.span, "basic behavior")
            return None if args is None else ir.BehaviorCall(name, args, node.span)
        if name in self.table.inputs or name in self.table.outputs:
            self.diagnostics.add(
                "not-callable",
                f"'{name}' is a symbol; only options and basic behaviors can be called here",
                node.name.span,
            )
        else:
            wanted = {"option": "option", "behavior": "basic behavior"}.get(
                node.explicit or "", "option or basic behavior"
            )
            self.diagnostics.add("no-matching-symbol", f"no {wanted} named '{name}'", node.name.span)
        return None

    def actions(self, nodes: list[ast.ActionStmt]) -> list[ir.Action]:
        """Lower a list of actions, dropping those with errors."""
        lowered = [self.action(n) for n in nodes]
        return [a for a in lowered if a is not None]

    # ================================================================== decision trees

    def tree(self, node: ast.DTree) -> ir.DecisionTree:
        """Lower a decision tree; ``stay`` becomes ``Transition(None, stay=True)`` for now."""
        match node:
            case ast.Goto(target=target, span=span):
                if target.text not in self.state_names:
                    self.diagnostics.add(
                        "unknown-state",
                        f"option '{self.name}' has no state '{target.text}'"
                        + _did_you_mean(target.text, self.state_names),
                        target.span,
                    )
                return ir.Transition(target.text, False, -1, span)
            case ast.Stay(span=span):
                return ir.Transition(None, True, -1, span)
            case ast.IfElse():
                condition = self.condition(node.condition)
                then = self.tree(node.then)
                assert node.otherwise is not None
                otherwise = self.tree(node.otherwise)
                return ir.If(
                    condition if condition is not None else ir.BooleanLiteral(False),
                    then,
                    otherwise,
                    self.source(node.condition.span),
                    node.doc,
                    node.else_doc,
                    node.span,
                )
        raise AssertionError(node)

    # ================================================================== the option

    def build(self, index: int) -> ir.Option:
        """The option's IR; ``index`` is its position in the IC."""
        decl = self.header.decl
        states = decl.states
        self.check_states(decl)

        common: list[ir.CommonBranch] = []
        if decl.common_decision:
            for branch in decl.common_decision.branches:
                condition = self.condition(branch.condition)
                common.append(
                    ir.CommonBranch(
                        condition if condition is not None else ir.BooleanLiteral(False),
                        self.tree(branch.then),
                        self.source(branch.condition.span),
                        branch.doc,
                        branch.span,
                    )
                )
        common_action = self.actions(decl.common_action or [])

        built: list[ir.State] = []
        for index_in_option, state in enumerate(states):
            self.check_leading_else(decl, state)
            own: ir.DecisionTree = (
                self.tree(state.decision)
                if state.decision is not None
                else ir.Transition(None, True, -1, state.name.span)
            )
            decision = own
            for common_branch in reversed(common):
                decision = ir.If(
                    common_branch.condition,
                    common_branch.tree,
                    decision,
                    common_branch.text,
                    common_branch.doc,
                    None,
                    common_branch.span,
                )
            decision = _finish_tree(decision, state.name.text)
            actions = tuple(common_action) + tuple(self.actions(state.actions))
            built.append(
                ir.State(
                    state.name.text,
                    index_in_option,
                    decision,
                    actions,
                    state.initial,
                    state.target,
                    state.coop,
                    state.coop_count,
                    state.decision is not None,
                    None,
                    state.name.span,
                )
            )
        initial = next((s.name.text for s in states if s.initial), states[0].name.text if states else "")
        return ir.Option(
            self.name,
            index,
            tuple(self.header.params.values()),
            tuple(built),
            initial,
            tuple(common),
            tuple(common_action),
            decl.doc,
            self.header.file.path,
            decl.name.span,
        )

    def check_states(self, decl: ast.OptionDecl) -> None:
        """Report duplicate states and a missing or repeated initial state."""
        seen: dict[str, Span] = {}
        initials = [s for s in decl.states if s.initial]
        for state in decl.states:
            if state.name.text in seen:
                self.diagnostics.add(
                    "duplicate-definition",
                    f"state '{state.name.text}' is defined more than once",
                    state.name.span,
                    related=(("first defined here", seen[state.name.text]),),
                )
            seen.setdefault(state.name.text, state.name.span)
        if decl.states and not initials:
            self.diagnostics.add(
                "missing-initial-state", f"initial state is missing on option '{self.name}'", decl.name.span
            )
        for extra in initials[1:]:
            self.diagnostics.add(
                "multiple-initial-states",
                f"multiple initial state definitions: '{extra.name.text}' (the first is '{initials[0].name.text}')",
                extra.name.span,
                related=(("first initial state", initials[0].name.span),),
            )

    def check_leading_else(self, decl: ast.OptionDecl, state: ast.StateDecl) -> None:
        """Check a decision's leading ``else`` against the option's common decision tree."""
        if state.decision is None or state.decision_span is None:
            return
        has_common = decl.common_decision is not None and bool(decl.common_decision.branches)
        if state.leading_else and not has_common:
            self.diagnostics.add(
                "else-without-common-decision",
                "decision tree must not start with else when the option has no common decision tree",
                state.decision_span,
            )
        elif has_common and not state.leading_else:
            self.diagnostics.add(
                "decision-must-start-with-else",
                "the option has a common decision tree: this decision should start with 'else' "
                "(it is evaluated after the common tree)",
                state.decision_span,
            )


def _finish_tree(tree: ir.DecisionTree, state: str) -> ir.DecisionTree:
    """The state's final decision tree, rebuilt once (nodes are frozen, so no ``replace``).

    ``stay`` (target None) becomes ``state``, and the leaves are numbered in pre-order
    (then-branch first) from 0.
    """
    counter = 0

    def visit(node: ir.DecisionTree) -> ir.DecisionTree:
        nonlocal counter
        if isinstance(node, ir.Transition):
            target = state if node.target is None else node.target
            leaf = counter
            counter += 1
            return ir.Transition(target, target == state, leaf, node.span)
        then = visit(node.then)
        return ir.If(node.condition, then, visit(node.otherwise), node.text, node.doc, node.else_doc, node.span)

    return visit(tree)


_TITLE_FIELDS = {
    "title": re.compile(r"^\s*\**\s*Title:\s*(.*?)\s*$", re.MULTILINE),
    "platform": re.compile(r"^\s*\**\s*Platform:\s*(.*?)\s*$", re.MULTILINE),
    "software_environment": re.compile(r"^\s*\**\s*Software-Environment:\s*(.*?)\s*$", re.MULTILINE),
}


def title_fields(comment: str | None) -> dict[str, str]:
    """``Title:``, ``Platform:`` and ``Software-Environment:`` of a ``/***`` comment."""
    fields = {}
    for key, pattern in _TITLE_FIELDS.items():
        match = pattern.search(comment or "")
        fields[key] = match.group(1) if match else ""
    return fields
