"""IR -> JSON for the studio UI (``xabsl compile --json``), and back to the IR's shape on read.

The document describes the behavior, not its execution: agents; options with parameters,
states, decision trees (conditions as source text, leaf ids), transitions (from, to, leaf id;
the conditions leading to a leaf are its path in the decision tree) and calls; basic behaviors; symbols with types,
units, ranges and doc comments; enumerations and constants. Integer ids are the IR's indices:
an option's ``id`` is its IC index, a state's ``id`` its index in the option, a symbol's ``id``
its index among the inputs or outputs.

Expression texts come from the source (``source_text`` callback); for programs read from
intermediate code, where there is no source, a canonical XABSL rendering is used instead.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from xabsl_studio.engine import ir
from xabsl_studio.engine.types import Span, SpanJson

SCHEMA_VERSION = 1

SourceText = Callable[[Span], str]

_OPERATOR_TEXT = {"enum==": "==", "enum!=": "!="}


def render_expression(e: ir.Expression, option: str = "") -> str:
    """A canonical XABSL rendering of an IR expression (fully parenthesised where needed).

    ``option`` is the option that contains the expression: its parameters are written
    ``@declared.name``, the option's prefix stripped (names keep their inner dots).
    """
    match e:
        case ir.Number(value=value):
            return repr(value).removesuffix(".0") if value == int(value) else repr(value)
        case ir.Constant(name=name):
            return name
        case ir.BooleanLiteral(value=value):
            return "true" if value else "false"
        case ir.EnumLiteral(element=element, enum=enum):
            return element.removeprefix(enum + ".")
        case ir.InputRef(symbol=symbol, args=args):
            if not args:
                return symbol
            inner = ", ".join(f"{ir.short_name(a.param, symbol)} = {render_expression(a.value, option)}" for a in args)
            return f"{symbol}({inner})"
        case ir.OutputRef(symbol=symbol):
            return symbol
        case ir.ParameterRef(param=param):
            return "@" + ir.short_name(param, option)
        case ir.StateTime():
            return "state_time"
        case ir.OptionTime():
            return "option_time"
        case ir.ActionDone():
            return "action_done"
        case ir.Conflict():
            return "conflict"
        case ir.Unary(op=op, operand=operand):
            return f"{op}{_wrapped(operand, option)}"
        case ir.Binary(op=op, left=left, right=right):
            return f"{_wrapped(left, option)} {_OPERATOR_TEXT.get(op, op)} {_wrapped(right, option)}"
        case ir.Logical(op=op, operands=operands):
            return f" {op} ".join(_wrapped(o, option) for o in operands)
        case ir.Conditional(condition=c, then=t, otherwise=o):
            return f"{_wrapped(c, option)} ? {_wrapped(t, option)} : {_wrapped(o, option)}"
    raise AssertionError(e)


def _wrapped(e: ir.Expression, option: str) -> str:
    text = render_expression(e, option)
    return f"({text})" if isinstance(e, ir.Binary | ir.Logical | ir.Conditional) else text


class _Exporter:
    def __init__(self, source_text: SourceText | None) -> None:
        self.source_text = source_text
        #: the option being exported (the owner of the ``@`` parameters its expressions read)
        self.owner = ""

    def text(self, e: ir.Expression) -> str:
        if self.source_text is not None and e.span is not None:
            return self.source_text(e.span)
        return render_expression(e, self.owner)

    @staticmethod
    def span(span: Span | None) -> SpanJson | None:
        return span.as_dict() if span else None

    def parameter(self, p: ir.Parameter) -> dict[str, Any]:
        return {
            "name": p.name,
            "short_name": p.short_name,
            "type": p.kind.value,
            "enum": p.enum,
            "range": p.range,
            "unit": p.unit,
            "doc": p.doc,
            "span": self.span(p.span),
        }

    def arguments(self, args: tuple[ir.Argument, ...]) -> list[dict[str, Any]]:
        return [{"param": a.param, "type": a.kind.value, "value": self.text(a.value)} for a in args]

    def action(self, a: ir.Action) -> dict[str, Any]:
        if isinstance(a, ir.OptionCall):
            return {"type": "option", "name": a.option, "args": self.arguments(a.args), "span": self.span(a.span)}
        if isinstance(a, ir.BehaviorCall):
            return {"type": "behavior", "name": a.behavior, "args": self.arguments(a.args), "span": self.span(a.span)}
        return {"type": "assign", "symbol": a.symbol, "value": self.text(a.value), "span": self.span(a.span)}

    def tree(self, t: ir.DecisionTree) -> dict[str, Any]:
        if isinstance(t, ir.Transition):
            return {"to": t.target, "stay": t.stay, "leaf": t.leaf, "span": self.span(t.span)}
        return {
            "if": t.text or self.text(t.condition),
            "doc": t.doc,
            "span": self.span(t.span),
            "then": self.tree(t.then),
            "else": self.tree(t.otherwise),
        }

    def transitions(self, option: ir.Option, state: ir.State) -> list[dict[str, Any]]:
        # No condition texts here: the chain to each leaf is in the state's ``decision`` tree
        # already, and repeating it per leaf grows with the square of an ``else if`` chain.
        return [
            {"from": state.name, "to": leaf.target, "leaf": leaf.leaf, "stay": leaf.stay, "span": self.span(leaf.span)}
            for leaf in ir.leaves(state.decision)
        ]

    def option(self, option: ir.Option) -> dict[str, Any]:
        self.owner = option.name
        states = []
        for state in option.states:
            states.append(
                {
                    "id": state.index,
                    "name": state.name,
                    "initial": state.name == option.initial_state,
                    "target": state.target,
                    "coop": state.coop,
                    "coop_count": state.coop_count,
                    "doc": state.doc,
                    "span": self.span(state.span),
                    "actions": [self.action(a) for a in state.actions],
                    "decision": self.tree(state.decision),
                }
            )
        calls = []
        for state in option.states:
            for action in state.actions:
                if isinstance(action, ir.OptionCall | ir.BehaviorCall):
                    calls.append(
                        {
                            "state": state.name,
                            "type": "option" if isinstance(action, ir.OptionCall) else "behavior",
                            "name": action.option if isinstance(action, ir.OptionCall) else action.behavior,
                        }
                    )
        return {
            "id": option.index,
            "name": option.name,
            "file": option.file,
            "doc": option.doc,
            "span": self.span(option.span),
            "params": [self.parameter(p) for p in option.params],
            "initial_state": option.initial_state,
            "states": states,
            "transitions": [t for s in option.states for t in self.transitions(option, s)],
            "calls": calls,
            "common_decision": [
                {"if": b.text or self.text(b.condition), "doc": b.doc, "then": self.tree(b.tree)}
                for b in option.common_decision
            ],
            "common_action": [self.action(a) for a in option.common_action],
        }

    def symbol(self, s: ir.InputSymbol | ir.OutputSymbol) -> dict[str, Any]:
        data: dict[str, Any] = {
            "id": s.index,
            "name": s.name,
            "type": s.kind.value,
            "enum": s.enum,
            "range": s.range,
            "unit": s.unit,
            "doc": s.doc,
            "namespace": s.namespace,
            "span": self.span(s.span),
        }
        if isinstance(s, ir.InputSymbol):
            data["params"] = [self.parameter(p) for p in s.params]
        else:
            data["internal"] = s.internal
        return data

    def program(self, program: ir.Program) -> dict[str, Any]:
        return {
            "version": SCHEMA_VERSION,
            "title": program.title,
            "platform": program.platform,
            "software_environment": program.software_environment,
            "files": list(program.files),
            "agents": [
                {"name": a.name, "title": a.title, "root": a.root, "doc": a.doc, "span": self.span(a.span)}
                for a in program.agents
            ],
            "options": [self.option(o) for o in program.options.values()],
            "behaviors": [
                {
                    "id": b.index,
                    "name": b.name,
                    "doc": b.doc,
                    "namespace": b.namespace,
                    "params": [self.parameter(p) for p in b.params],
                    "span": self.span(b.span),
                }
                for b in program.behaviors.values()
            ],
            "inputs": [self.symbol(s) for s in program.inputs.values()],
            "outputs": [self.symbol(s) for s in program.outputs.values()],
            "enums": [
                {
                    "name": e.name,
                    "elements": list(e.elements),
                    "internal": e.internal,
                    "doc": e.doc,
                    "span": self.span(e.span),
                }
                for e in program.enums.values()
            ],
            "constants": [
                {
                    "name": c.name,
                    "value": c.value,
                    "text": c.text,
                    "unit": c.unit,
                    "doc": c.doc,
                    "span": self.span(c.span),
                }
                for c in program.constants.values()
            ],
        }


def program_to_json(program: ir.Program, source_text: SourceText | None = None) -> dict[str, Any]:
    """The JSON document of a program (plain dicts and lists, ready for orjson)."""
    return _Exporter(source_text).program(program)


def dumps(document: Any, *, indent: bool = True) -> bytes:
    """``document`` as UTF-8 JSON, at any nesting depth.

    orjson refuses documents nested deeper than 255 levels, which a long ``else if`` chain (one
    object per level) reaches; those go through the standard library's encoder instead.
    """
    import orjson

    try:
        return orjson.dumps(document, option=orjson.OPT_INDENT_2 if indent else 0)
    except orjson.JSONEncodeError:
        import json

        from xabsl_studio.engine.recursion import deep_recursion

        with deep_recursion():
            text = json.dumps(document, indent=2 if indent else None, ensure_ascii=False, allow_nan=False)
        return text.encode("utf-8")
