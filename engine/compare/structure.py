"""The structural diff of two programs: added, removed, renamed and changed parts, each reported once.

:func:`diff_programs` walks two checked programs side by side and lists a :class:`Change` per
edit, in the place a reader looks for it:

* program level: the title, agents, enumerations, input/output/internal symbols, constants and
  basic behaviors (by name; their fields and parameters);
* per option: its doc comment, file, parameters, initial state, the common decision (its
  transitions) and common action, and its states;
* per state: its flags (``target``, cooperative kind), its own action items and its own
  decision's transitions (the common decision is the option's, compared once, not per state).

Identity never depends on position:

* a **transition** is identified by its *decision path*: the conditions on the way to its leaf
  that held (the ``if`` branches taken), in order, plus ``else`` when the leaf is the else branch
  of its ``if`` (the leaf of ``if (a) goto x; else if (b) goto y; else stay;`` reached by ``b``
  is ``[b]``, the last one ``[else]``). Conditions compare as IR expressions (spans and
  whitespace ignored, constants by name): adding an ``else if`` leaves the other transitions
  alone; a changed target is a changed transition; a condition that changed is one ``condition``
  change however many leaves lie below it;
* an **action item** by what it calls or sets (and its occurrence among those in the state);
* options and states by name, with renames: an option or a state that is gone while one of
  another name appeared, with the same body once the names are mapped, is **renamed** (one
  change; the calls and ``goto``\\ s naming it are no changes). With a different body it is a
  removed and an added one. The parts of an added or removed option or state are not listed
  again.

Constants are compared by name where expressions use them, so a changed value is reported at the
constant only.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field

from xabsl_studio.engine import ir
from xabsl_studio.engine.docs.xref import own_actions, own_decision
from xabsl_studio.engine.emit.json import render_expression
from xabsl_studio.engine.types import Kind, Span

__all__ = ["COMMON", "ELSE", "Change", "Detail", "LeafRef", "StructuralDiff", "Where", "diff_programs"]

#: The ``state`` of a change in an option's common decision or common action.
COMMON = "(common)"
#: The marker of a decision path whose leaf is the else branch of its ``if``.
ELSE = "else"


@dataclass(frozen=True, slots=True)
class Where:
    """A place in a source file (a display name as the compiler prints it, 1-based line and column)."""

    file: str
    line: int
    col: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}"

    @staticmethod
    def of(span: Span | None) -> Where | None:
        """The place of ``span`` (None for a program read from intermediate code)."""
        return Where(span.file, span.line, span.col) if span is not None else None


@dataclass(frozen=True, slots=True)
class Detail:
    """One field of a changed part: its old and new value as text (None: not there)."""

    field: str
    old: str | None
    new: str | None


@dataclass(frozen=True, slots=True)
class LeafRef:
    """A decision leaf in a state's (inlined) decision: the state's index and the leaf id."""

    state: int
    leaf: int


@dataclass(frozen=True, slots=True)
class Change:
    """One edit.

    ``kind``: ``title``, ``agent``, ``enum``, ``input``, ``output``, ``internal``, ``constant``,
    ``behavior``, ``option``, ``parameter``, ``state``, ``transition``, ``condition``, ``decision``
    (the order of its transitions), ``action`` (an item, or ``order``: the items' order).
    ``change``: ``added``, ``removed``, ``renamed`` or ``changed``. ``name`` is the part's name in
    the new version (the old one when removed); ``option`` and ``state`` where it is
    (:data:`COMMON` for the common decision and action); ``path`` a transition's decision path.
    """

    kind: str
    change: str
    name: str
    option: str | None = None
    state: str | None = None
    path: tuple[str, ...] | None = None
    details: tuple[Detail, ...] = ()
    old: Where | None = None
    new: Where | None = None
    #: the decision leaves of a transition or condition change, per side (for the drawings)
    old_leaves: tuple[LeafRef, ...] = ()
    new_leaves: tuple[LeafRef, ...] = ()

    @property
    def where(self) -> str:
        """``option/state`` or the part's own name for program-level parts."""
        if self.option is None:
            return self.name
        return self.option if self.state is None else f"{self.option}/{self.state}"

    def as_dict(self) -> dict[str, object]:
        """The change as a JSON-ready dict (docs/compare.md)."""
        return {
            "kind": self.kind,
            "change": self.change,
            "name": self.name,
            "option": self.option,
            "state": self.state,
            "path": list(self.path) if self.path is not None else None,
            "details": [{"field": d.field, "old": d.old, "new": d.new} for d in self.details],
            "old": _where_dict(self.old),
            "new": _where_dict(self.new),
        }


def _where_dict(where: Where | None) -> dict[str, object] | None:
    return {"file": where.file, "line": where.line, "col": where.col} if where is not None else None


@dataclass
class StructuralDiff:
    """Every change between ``old`` and ``new``, program-level parts first, then option by option."""

    old: ir.Program
    new: ir.Program
    changes: list[Change] = field(default_factory=list)
    #: old option name -> new name
    option_renames: dict[str, str] = field(default_factory=dict)
    #: per option (new name): old state name -> new name
    state_renames: dict[str, dict[str, str]] = field(default_factory=dict)

    def status(self, option: str) -> str | None:
        """``added``, ``removed``, ``renamed`` or ``changed`` for an option (by new name; old if removed)."""
        own = [c for c in self.changes if c.option == option]
        head = next((c.change for c in own if c.kind == "option" and c.change != "changed"), None)
        if head is not None:
            return head
        return "changed" if own else None

    def state_status(self, option: str, state: str) -> str | None:
        """``added``, ``removed``, ``renamed`` or ``changed`` for a state of a matched option."""
        own = [c for c in self.changes if c.option == option and c.state == state]
        head = next((c.change for c in own if c.kind == "state" and c.change != "changed"), None)
        if head is not None:
            return head
        return "changed" if own else None

    @property
    def changed_options(self) -> list[str]:
        """Options of the new version with changes inside (not added or removed ones), in IC order."""
        names = {c.option for c in self.changes if c.option is not None}
        return [
            name
            for name in self.new.options
            if name in names and self.status(name) in ("changed", "renamed") and self._has_inner(name)
        ]

    def _has_inner(self, option: str) -> bool:
        return any(c.option == option and not (c.kind == "option" and c.change == "renamed") for c in self.changes)

    def counts(self) -> dict[str, int]:
        """How many changes of each ``change``."""
        out = {"added": 0, "removed": 0, "renamed": 0, "changed": 0}
        for c in self.changes:
            out[c.change] += 1
        return out


def diff_programs(old: ir.Program, new: ir.Program) -> StructuralDiff:
    """The changes from ``old`` to ``new`` (see the module docstring)."""
    return _Differ(old, new).run()


# -- canonical forms ------------------------------------------------------------------------------


def _expr(e: ir.Expression, owner: str) -> str:
    """An expression as comparable text: the canonical rendering (no spans, no layout, constants by name)."""
    return render_expression(e, owner)


def _text(e: ir.Expression, owner: str, source: str = "") -> str:
    """What a reader sees of an expression: its source text, else the canonical rendering."""
    return source or render_expression(e, owner)


def _args(args: Iterable[ir.Argument], callee: str, owner: str) -> dict[str, str]:
    return {ir.short_name(a.param, callee): _expr(a.value, owner) for a in args}


def _action_key(action: ir.Action, options: Mapping[str, str]) -> tuple[str, str]:
    if isinstance(action, ir.OptionCall):
        return ("option", options.get(action.option, action.option))
    if isinstance(action, ir.BehaviorCall):
        return ("behavior", action.behavior)
    return ("set", action.symbol)


def _action_label(key: tuple[str, str]) -> str:
    kind, name = key
    return f"{name} = ..." if kind == "set" else f"{name}()"


def _action_values(action: ir.Action, owner: str) -> dict[str, str]:
    """What an action item passes: argument values by parameter short name, or the assigned value."""
    if isinstance(action, ir.OptionCall):
        return _args(action.args, action.option, owner)
    if isinstance(action, ir.BehaviorCall):
        return _args(action.args, action.behavior, owner)
    return {"value": _expr(action.value, owner)}


def _action_text(action: ir.Action, owner: str) -> str:
    if isinstance(action, ir.Assignment):
        return f"{action.symbol} = {_expr(action.value, owner)}"
    name = action.option if isinstance(action, ir.OptionCall) else action.behavior
    args = ", ".join(f"{k} = {v}" for k, v in _action_values(action, owner).items())
    return f"{name}({args})"


@dataclass(frozen=True, slots=True)
class _Leaf:
    """A decision leaf with its identity: the path key, its target, where it is."""

    key: tuple[str, ...]
    #: what a reader sees of the path (source texts)
    shown: tuple[str, ...]
    target: str
    span: Span | None
    #: the ``if`` nodes on the way and whether their condition held (for a changed condition's place)
    steps: tuple[tuple[ir.If, bool], ...]
    #: the leaf ids of this leaf in each state's inlined decision (a common leaf is in every state)
    refs: tuple[LeafRef, ...]


def _leaves(
    tree: ir.DecisionTree, owner: str, stay_as: str | None, refs: Callable[[int], tuple[LeafRef, ...]]
) -> list[_Leaf]:
    """The leaves of ``tree`` keyed by decision path, occurrence numbers making equal paths unique.

    ``stay_as``: the target a ``stay`` leaf reads as (None: ``stay``, for the common tree);
    ``refs(i)``: the :class:`LeafRef` s of the tree's ``i``-th leaf (pre-order).
    """
    found: list[_Leaf] = []

    def visit(
        node: ir.DecisionTree,
        key: tuple[str, ...],
        shown: tuple[str, ...],
        steps: tuple[tuple[ir.If, bool], ...],
    ) -> None:
        if isinstance(node, ir.Transition):
            target = "stay" if node.stay or node.target is None or node.target == stay_as else node.target
            in_else = bool(steps) and not steps[-1][1]
            full = (*key, ELSE) if in_else else key
            seen = (*shown, ELSE) if in_else else shown
            found.append(_Leaf(full, seen, target, node.span, steps, refs(len(found))))
            return
        condition = _expr(node.condition, owner)
        text = _text(node.condition, owner, node.text)
        visit(node.then, (*key, condition), (*shown, text), (*steps, (node, True)))
        visit(node.otherwise, key, shown, (*steps, (node, False)))

    visit(tree, (), (), ())
    counts: dict[tuple[str, ...], int] = {}
    unique = []
    for leaf in found:
        n = counts.get(leaf.key, 0)
        counts[leaf.key] = n + 1
        key = leaf.key if n == 0 else (*leaf.key, f"#{n + 1}")
        unique.append(_Leaf(key, leaf.shown, leaf.target, leaf.span, leaf.steps, leaf.refs))
    return unique


def _common_tree(option: ir.Option) -> ir.DecisionTree:
    """The common decision as one tree (an ``if``/``else if`` chain ending in a placeholder leaf)."""
    tree: ir.DecisionTree = ir.Transition("\0own", False, -1, None)
    for branch in reversed(option.common_decision):
        tree = ir.If(branch.condition, branch.tree, tree, branch.text, branch.doc, None, branch.span)
    return tree


def _common_refs(option: ir.Option) -> list[tuple[LeafRef, ...]]:
    """Per leaf of the common decision (pre-order), its leaf in every state's inlined decision."""
    per_state: list[list[int]] = []
    for state in option.states:
        ids: list[int] = []
        tree = state.decision
        for _ in option.common_decision:
            if not isinstance(tree, ir.If):
                break
            ids.extend(leaf.leaf for leaf in ir.leaves(tree.then))
            tree = tree.otherwise
        per_state.append(ids)
    total = max((len(ids) for ids in per_state), default=0)
    return [
        tuple(LeafRef(s.index, ids[i]) for s, ids in zip(option.states, per_state, strict=True) if i < len(ids))
        for i in range(total)
    ]


# -- the walk -------------------------------------------------------------------------------------


def _fields(pairs: Iterable[tuple[str, object, object]]) -> tuple[Detail, ...]:
    """The details of the fields that differ (values shown as text)."""
    return tuple(Detail(name, _show(a), _show(b)) for name, a, b in pairs if a != b)


def _show(value: object) -> str | None:
    if value is None:
        return None
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, Kind):
        return value.value
    if isinstance(value, tuple | list):
        return ", ".join(str(v) for v in value)
    return str(value)


class _Differ:
    def __init__(self, old: ir.Program, new: ir.Program) -> None:
        self.old = old
        self.new = new
        self.out = StructuralDiff(old, new)
        self.changes = self.out.changes

    def add(self, change: Change) -> None:
        self.changes.append(change)

    def run(self) -> StructuralDiff:
        old, new = self.old, self.new
        if old.title != new.title:
            self.add(
                Change("title", "changed", new.title or old.title, details=_fields([("title", old.title, new.title)]))
            )
        self.out.option_renames = self.option_renames()
        self.agents()
        self.named("enum", old.enums, new.enums, self.enum_fields)
        self.named("input", old.inputs, new.inputs, self.input_fields, self.input_params)
        for internal in (False, True):
            kind = "internal" if internal else "output"
            self.named(
                kind,
                {k: v for k, v in old.outputs.items() if v.internal == internal},
                {k: v for k, v in new.outputs.items() if v.internal == internal},
                self.output_fields,
            )
        self.named("constant", old.constants, new.constants, self.constant_fields)
        self.named("behavior", old.behaviors, new.behaviors, self.behavior_fields, self.params_of)
        self.options()
        return self.out

    # -- program level ----------------------------------------------------------------------------

    def named(
        self,
        kind: str,
        old: Mapping[str, object],
        new: Mapping[str, object],
        fields: Callable[[object, object], tuple[Detail, ...]],
        parameters: Callable[[object, object], None] | None = None,
    ) -> None:
        for name in old:
            if name not in new:
                self.add(Change(kind, "removed", name, old=Where.of(getattr(old[name], "span", None))))
        for name, after in new.items():
            before = old.get(name)
            if before is None:
                self.add(Change(kind, "added", name, new=Where.of(getattr(after, "span", None))))
                continue
            details = fields(before, after)
            if details:
                self.add(
                    Change(
                        kind,
                        "changed",
                        name,
                        details=details,
                        old=Where.of(getattr(before, "span", None)),
                        new=Where.of(getattr(after, "span", None)),
                    )
                )
            if parameters is not None:
                parameters(before, after)

    @staticmethod
    def enum_fields(a: object, b: object) -> tuple[Detail, ...]:
        assert isinstance(a, ir.Enumeration) and isinstance(b, ir.Enumeration)
        short_a = [e.removeprefix(a.name + ".") for e in a.elements]
        short_b = [e.removeprefix(b.name + ".") for e in b.elements]
        details = []
        gone = [e for e in short_a if e not in short_b]
        came = [e for e in short_b if e not in short_a]
        if gone or came:
            details.append(Detail("elements", _show(gone) or None, _show(came) or None))
        elif short_a != short_b:
            details.append(Detail("element order", _show(short_a), _show(short_b)))
        details.extend(_fields([("internal", a.internal, b.internal), ("doc", a.doc, b.doc)]))
        return tuple(details)

    @staticmethod
    def input_fields(a: object, b: object) -> tuple[Detail, ...]:
        assert isinstance(a, ir.InputSymbol) and isinstance(b, ir.InputSymbol)
        return _fields(
            [
                ("type", a.kind, b.kind),
                ("enum", a.enum, b.enum),
                ("range", a.range, b.range),
                ("unit", a.unit, b.unit),
                ("doc", a.doc, b.doc),
                ("namespace", a.namespace, b.namespace),
            ]
        )

    @staticmethod
    def output_fields(a: object, b: object) -> tuple[Detail, ...]:
        assert isinstance(a, ir.OutputSymbol) and isinstance(b, ir.OutputSymbol)
        return _fields(
            [
                ("type", a.kind, b.kind),
                ("enum", a.enum, b.enum),
                ("range", a.range, b.range),
                ("unit", a.unit, b.unit),
                ("doc", a.doc, b.doc),
                ("namespace", a.namespace, b.namespace),
            ]
        )

    @staticmethod
    def constant_fields(a: object, b: object) -> tuple[Detail, ...]:
        assert isinstance(a, ir.ConstantDecl) and isinstance(b, ir.ConstantDecl)
        value = [("value", a.text, b.text)] if a.value != b.value else []
        return _fields([*value, ("unit", a.unit, b.unit), ("doc", a.doc, b.doc)])

    @staticmethod
    def behavior_fields(a: object, b: object) -> tuple[Detail, ...]:
        assert isinstance(a, ir.BasicBehavior) and isinstance(b, ir.BasicBehavior)
        return _fields([("doc", a.doc, b.doc), ("namespace", a.namespace, b.namespace)])

    def input_params(self, a: object, b: object) -> None:
        assert isinstance(a, ir.InputSymbol) and isinstance(b, ir.InputSymbol)
        self.parameters(a.params, b.params, a.name, b.name, None)

    def params_of(self, a: object, b: object) -> None:
        assert isinstance(a, ir.BasicBehavior) and isinstance(b, ir.BasicBehavior)
        self.parameters(a.params, b.params, a.name, b.name, None)

    def agents(self) -> None:
        old = {a.name: a for a in self.old.agents}
        new = {a.name: a for a in self.new.agents}
        renames = self.out.option_renames

        def fields(a: object, b: object) -> tuple[Detail, ...]:
            assert isinstance(a, ir.Agent) and isinstance(b, ir.Agent)
            return _fields(
                [("root", renames.get(a.root, a.root), b.root), ("title", a.title, b.title), ("doc", a.doc, b.doc)]
            )

        self.named("agent", old, new, fields)

    def parameters(
        self,
        old: tuple[ir.Parameter, ...],
        new: tuple[ir.Parameter, ...],
        old_owner: str,
        new_owner: str,
        option: str | None,
    ) -> None:
        """Parameters of an option, a basic behavior or an input symbol, by declared name."""
        before = {p.short_name: p for p in old}
        after = {p.short_name: p for p in new}
        owner = option if option is not None else new_owner
        for name, p in before.items():
            if name not in after:
                self.add(Change("parameter", "removed", name, option=owner, old=Where.of(p.span)))
        for name, p in after.items():
            q = before.get(name)
            if q is None:
                self.add(Change("parameter", "added", name, option=owner, new=Where.of(p.span)))
                continue
            details = _fields(
                [
                    ("type", q.kind, p.kind),
                    ("enum", q.enum, p.enum),
                    ("range", q.range, p.range),
                    ("unit", q.unit, p.unit),
                    ("doc", q.doc, p.doc),
                ]
            )
            if details:
                self.add(
                    Change(
                        "parameter",
                        "changed",
                        name,
                        option=owner,
                        details=details,
                        old=Where.of(q.span),
                        new=Where.of(p.span),
                    )
                )

    # -- options ----------------------------------------------------------------------------------

    def option_signature(self, option: ir.Option, options: Mapping[str, str]) -> str:
        """Everything of an option but its name and places, with option names mapped (rename test)."""
        states = {s.name: s.name for s in option.states}
        name = option.name  # the owner of its ``@`` parameters: they read by their declared names
        parts = [
            repr([(p.short_name, p.kind, p.enum, p.range, p.unit, p.doc) for p in option.params]),
            option.initial_state,
            repr(option.doc),
            self.leaf_signature(_common_tree(option), name, None, states),
            repr([(*_action_key(a, options), repr(_action_values(a, name))) for a in option.common_action]),
        ]
        for state in option.states:
            parts.append(self.state_signature(option, state, name, options, states))
        return "\n".join(parts)

    def state_signature(
        self, option: ir.Option, state: ir.State, owner: str, options: Mapping[str, str], states: Mapping[str, str]
    ) -> str:
        """A state's body: flags, own actions and own decision, with names mapped (rename test)."""
        actions = [(*_action_key(a, options), repr(_action_values(a, owner))) for a in own_actions(option, state)]
        own = self.leaf_signature(own_decision(option, state), owner, state.name, states)
        return repr((states.get(state.name, state.name), state.target, state.coop, state.coop_count, actions, own))

    @staticmethod
    def leaf_signature(tree: ir.DecisionTree, owner: str, stay_as: str | None, states: Mapping[str, str]) -> str:
        leaves = _leaves(tree, owner, stay_as, lambda i: ())
        return repr([(leaf.key, states.get(leaf.target, leaf.target)) for leaf in leaves])

    def option_renames(self) -> dict[str, str]:
        """Old name -> new name of the options that were renamed with the same body."""
        gone = [n for n in self.old.options if n not in self.new.options]
        came = [n for n in self.new.options if n not in self.old.options]
        if not gone or not came:
            return {}
        renames: dict[str, str] = {}
        # Two passes: the second maps the first's renames, so options calling each other match.
        for _ in range(2):
            taken: set[str] = set()
            found: dict[str, str] = {}
            for name in gone:
                for candidate in came:
                    if candidate in taken:
                        continue
                    mapping = {**renames, name: candidate}
                    before = self.option_signature(self.old.options[name], mapping)
                    after = self.option_signature(self.new.options[candidate], {})
                    # parameters are compared by their declared names, so the bodies compare as they read
                    if before == after:
                        found[name] = candidate
                        taken.add(candidate)
                        break
            renames = found
        return renames

    def options(self) -> None:
        renames = self.out.option_renames
        renamed_to = set(renames.values())
        for name, option in self.old.options.items():
            if name not in self.new.options and name not in renames:
                self.add(Change("option", "removed", name, option=name, old=Where.of(option.span)))
        for name, option in self.new.options.items():
            old_name = next((o for o, n in renames.items() if n == name), name)
            before = self.old.options.get(old_name)
            if before is None:
                self.add(Change("option", "added", name, option=name, new=Where.of(option.span)))
                continue
            self.option(before, option, renamed=name in renamed_to)

    def option(self, a: ir.Option, b: ir.Option, renamed: bool) -> None:
        name = b.name
        states = self.state_renames(a, b)
        if states:
            self.out.state_renames[name] = states
        details = _fields(
            [
                ("doc", a.doc, b.doc),
                ("file", a.file, b.file),
                ("initial state", states.get(a.initial_state, a.initial_state), b.initial_state),
            ]
        )
        if renamed:  # one change: the new name, and the file it moved to with it
            details = (Detail("name", a.name, b.name), *details)
        if details:
            self.add(
                Change(
                    "option",
                    "renamed" if renamed else "changed",
                    name,
                    option=name,
                    details=details,
                    old=Where.of(a.span),
                    new=Where.of(b.span),
                )
            )
        self.parameters(a.params, b.params, a.name, b.name, name)
        old_refs, new_refs = _common_refs(a), _common_refs(b)
        self.transitions(
            _leaves(_common_tree(a), a.name, None, lambda i: old_refs[i] if i < len(old_refs) else ()),
            _leaves(_common_tree(b), b.name, None, lambda i: new_refs[i] if i < len(new_refs) else ()),
            name,
            COMMON,
            states,
        )
        self.actions(a.common_action, b.common_action, a.name, b.name, name, COMMON)
        old_by_new = {states.get(s.name, s.name): s for s in a.states}
        for state in b.states:
            before = old_by_new.get(state.name)
            if before is None:
                self.add(Change("state", "added", state.name, option=name, state=state.name, new=Where.of(state.span)))
                continue
            self.state(a, b, before, state, states)
        # removed states last: the new version's order is the reading order
        new_names = {s.name for s in b.states}
        for state in a.states:
            if state.name not in states and state.name not in new_names:
                self.add(
                    Change("state", "removed", state.name, option=name, state=state.name, old=Where.of(state.span))
                )

    def state_renames(self, a: ir.Option, b: ir.Option) -> dict[str, str]:
        old_names = [s.name for s in a.states]
        new_names = [s.name for s in b.states]
        gone = [n for n in old_names if n not in new_names]
        came = [n for n in new_names if n not in old_names]
        if not gone or not came:
            return {}
        options = self.out.option_renames
        renames: dict[str, str] = {}
        for _ in range(2):
            found: dict[str, str] = {}
            taken: set[str] = set()
            for name in gone:
                for candidate in came:
                    if candidate in taken:
                        continue
                    mapping = {**renames, name: candidate}
                    before = self.state_signature(a, a.state(name), a.name, options, mapping)
                    after = self.state_signature(b, b.state(candidate), b.name, {}, {})
                    if before == after:
                        found[name] = candidate
                        taken.add(candidate)
                        break
            renames = found
        return renames

    def state(
        self, option_a: ir.Option, option_b: ir.Option, a: ir.State, b: ir.State, states: Mapping[str, str]
    ) -> None:
        name = option_b.name
        if a.name != b.name:
            self.add(
                Change(
                    "state",
                    "renamed",
                    b.name,
                    option=name,
                    state=b.name,
                    details=(Detail("name", a.name, b.name),),
                    old=Where.of(a.span),
                    new=Where.of(b.span),
                )
            )
        coop = {"n": "plain", "c": "capacity", "s": "synchronized"}
        details = _fields(
            [
                ("target", a.target, b.target),
                ("cooperative", coop.get(a.coop, a.coop), coop.get(b.coop, b.coop)),
                ("capacity", a.coop_count, b.coop_count),
            ]
        )
        if details:
            self.add(
                Change(
                    "state",
                    "changed",
                    b.name,
                    option=name,
                    state=b.name,
                    details=details,
                    old=Where.of(a.span),
                    new=Where.of(b.span),
                )
            )
        self.actions(own_actions(option_a, a), own_actions(option_b, b), option_a.name, option_b.name, name, b.name)
        self.transitions(
            _leaves(own_decision(option_a, a), option_a.name, a.name, _own_refs(option_a, a)),
            _leaves(own_decision(option_b, b), option_b.name, b.name, _own_refs(option_b, b)),
            name,
            b.name,
            states,
        )

    # -- actions ----------------------------------------------------------------------------------

    def actions(
        self,
        old: Iterable[ir.Action],
        new: Iterable[ir.Action],
        old_owner: str,
        new_owner: str,
        option: str,
        state: str,
    ) -> None:
        renames = self.out.option_renames
        before = dict(_numbered((_action_key(x, renames), x) for x in old))
        after = dict(_numbered((_action_key(x, {}), x) for x in new))
        # the items both have, in another order: they run in the order written (action_done too)
        kept_before = [k for k in before if k in after]
        kept_after = [k for k in after if k in before]
        if kept_before != kept_after:
            self.add(
                Change(
                    "action",
                    "changed",
                    "order",
                    option=option,
                    state=state,
                    details=(
                        Detail(
                            "order",
                            ", ".join(_action_label(k[:2]) for k in kept_before),
                            ", ".join(_action_label(k[:2]) for k in kept_after),
                        ),
                    ),
                    old=Where.of(before[kept_before[0]].span),
                    new=Where.of(after[kept_after[0]].span),
                )
            )
        for key, action in before.items():
            if key not in after:
                self.add(
                    Change(
                        "action",
                        "removed",
                        _action_label(key[:2]),
                        option=option,
                        state=state,
                        details=(Detail("action", _action_text(action, old_owner), None),),
                        old=Where.of(action.span),
                    )
                )
        for key, action in after.items():
            was = before.get(key)
            if was is None:
                self.add(
                    Change(
                        "action",
                        "added",
                        _action_label(key[:2]),
                        option=option,
                        state=state,
                        details=(Detail("action", None, _action_text(action, new_owner)),),
                        new=Where.of(action.span),
                    )
                )
                continue
            values_a, values_b = _action_values(was, old_owner), _action_values(action, new_owner)
            details = tuple(
                Detail(k if isinstance(action, ir.Assignment) else f"argument {k}", values_a.get(k), values_b.get(k))
                for k in [*values_a, *(k for k in values_b if k not in values_a)]
                if values_a.get(k) != values_b.get(k)
            )
            if details:
                self.add(
                    Change(
                        "action",
                        "changed",
                        _action_label(key[:2]),
                        option=option,
                        state=state,
                        details=details,
                        old=Where.of(was.span),
                        new=Where.of(action.span),
                    )
                )

    # -- transitions ------------------------------------------------------------------------------

    def transitions(
        self, old: list[_Leaf], new: list[_Leaf], option: str, state: str, states: Mapping[str, str]
    ) -> None:
        """Leaves matched by decision path; then changed conditions; the rest added and removed."""
        old = [leaf for leaf in old if leaf.target != "\0own"]
        new = [leaf for leaf in new if leaf.target != "\0own"]
        by_key = {leaf.key: leaf for leaf in new}
        unmatched_old: list[_Leaf] = []
        matched: set[tuple[str, ...]] = set()
        for leaf in old:
            other = by_key.get(leaf.key)
            if other is None:
                unmatched_old.append(leaf)
                continue
            matched.add(leaf.key)
            target = states.get(leaf.target, leaf.target)
            if target != other.target:
                self.add(
                    Change(
                        "transition",
                        "changed",
                        _path_name(other.shown),
                        option=option,
                        state=state,
                        path=other.shown,
                        details=(Detail("target", target, other.target),),
                        old=Where.of(leaf.span),
                        new=Where.of(other.span),
                        old_leaves=leaf.refs,
                        new_leaves=other.refs,
                    )
                )
        unmatched_new = [leaf for leaf in new if leaf.key not in matched]
        # the same paths in another order: the first that holds decides, so the order matters
        order_old = [leaf for leaf in old if leaf.key in matched]
        order_new = [leaf for leaf in new if leaf.key in matched]
        if [leaf.key for leaf in order_old] != [leaf.key for leaf in order_new]:
            first = next(i for i, (x, y) in enumerate(zip(order_old, order_new, strict=True)) if x.key != y.key)
            self.add(
                Change(
                    "decision",
                    "changed",
                    "order",
                    option=option,
                    state=state,
                    details=(
                        Detail(
                            "order",
                            " | ".join(_path_name(leaf.shown) for leaf in order_old),
                            " | ".join(_path_name(leaf.shown) for leaf in order_new),
                        ),
                    ),
                    old=Where.of(order_old[first].span),
                    new=Where.of(order_new[first].span),
                )
            )
        self.conditions(unmatched_old, unmatched_new, option, state, states)
        for leaf in unmatched_old:
            self.add(
                Change(
                    "transition",
                    "removed",
                    _path_name(leaf.shown),
                    option=option,
                    state=state,
                    path=leaf.shown,
                    details=(Detail("target", states.get(leaf.target, leaf.target), None),),
                    old=Where.of(leaf.span),
                    old_leaves=leaf.refs,
                )
            )
        for leaf in unmatched_new:
            self.add(
                Change(
                    "transition",
                    "added",
                    _path_name(leaf.shown),
                    option=option,
                    state=state,
                    path=leaf.shown,
                    details=(Detail("target", None, leaf.target),),
                    new=Where.of(leaf.span),
                    new_leaves=leaf.refs,
                )
            )

    def conditions(
        self, old: list[_Leaf], new: list[_Leaf], option: str, state: str, states: Mapping[str, str]
    ) -> None:
        """Pairs of unmatched leaves whose paths differ by one condition, same target: one change per condition.

        Removes the paired leaves from ``old`` and ``new``.
        """
        groups: dict[tuple[int, str, str], list[tuple[_Leaf, _Leaf]]] = {}
        for a in old:
            for b in new:
                if len(a.key) != len(b.key) or states.get(a.target, a.target) != b.target:
                    continue
                differ = [i for i, (x, y) in enumerate(zip(a.key, b.key, strict=True)) if x != y]
                if len(differ) == 1 and a.key[differ[0]] not in (ELSE,) and b.key[differ[0]] not in (ELSE,):
                    i = differ[0]
                    groups.setdefault((i, a.key[i], b.key[i]), []).append((a, b))
        used_old: set[int] = set()
        used_new: set[int] = set()
        for (i, _x, _y), pairs in sorted(groups.items(), key=lambda item: -len(item[1])):
            pairs = [(a, b) for a, b in pairs if id(a) not in used_old and id(b) not in used_new]
            if not pairs:
                continue
            for a, b in pairs:
                used_old.add(id(a))
                used_new.add(id(b))
            first_a, first_b = pairs[0]
            node_a, node_b = _condition_node(first_a, i), _condition_node(first_b, i)
            self.add(
                Change(
                    "condition",
                    "changed",
                    _path_name(first_b.shown[: i + 1]),
                    option=option,
                    state=state,
                    path=first_b.shown[: i + 1],
                    details=(Detail("condition", first_a.shown[i], first_b.shown[i]),),
                    old=Where.of(node_a.span if node_a is not None else first_a.span),
                    new=Where.of(node_b.span if node_b is not None else first_b.span),
                    old_leaves=tuple(r for a, _ in pairs for r in a.refs),
                    new_leaves=tuple(r for _, b in pairs for r in b.refs),
                )
            )
        old[:] = [a for a in old if id(a) not in used_old]
        new[:] = [b for b in new if id(b) not in used_new]


def _condition_node(leaf: _Leaf, index: int) -> ir.If | None:
    """The ``if`` of the ``index``-th condition that held on the way to ``leaf``."""
    held = [node for node, taken in leaf.steps if taken]
    return held[index] if index < len(held) else None


def _own_refs(option: ir.Option, state: ir.State) -> Callable[[int], tuple[LeafRef, ...]]:
    ids = [leaf.leaf for leaf in ir.leaves(own_decision(option, state))]
    return lambda i: (LeafRef(state.index, ids[i]),) if i < len(ids) else ()


def _path_name(shown: tuple[str, ...]) -> str:
    """A decision path as one line: ``a && b``, ``a && else``, ``else``, or ``always``."""
    return " && ".join(shown) if shown else "always"


def _numbered(items: Iterable[tuple[tuple[str, str], ir.Action]]) -> Iterator[tuple[tuple[str, str, int], ir.Action]]:
    """Items keyed by (kind, name, occurrence): the second call of one option is another item."""
    seen: dict[tuple[str, str], int] = {}
    for key, action in items:
        n = seen.get(key, 0)
        seen[key] = n + 1
        yield (*key, n), action
