"""Symbolic facts derived from signal histories, with a cause for every change (doc §1.6, §4.1).

This module owns the ``FactDeriver``: table-driven *history predicates* over a per-tick snapshot of
signals (sensors, activations α, actuators, switch variables s_OP) that set and clear ground facts
such as ``at-robot a`` or ``has-robot book``, each with hysteresis through dwell and confirmation
timers. The paper derives facts from activation histories instead of action callbacks
(Hertzberg et al. 1998; the "transient attractor" view of Jaeger 1999, §1.1), and §0 item 6 shows
why confirmation windows matter: a single-tick detector produced a false Has-Robot.

Rules are data (:class:`FactRule`, or dicts via :meth:`FactRule.from_dict`), so the errands world
configures them without code; :func:`errands_rules` builds the §1.6 table. A condition is a list of
terms, all of which must hold; a term is one of::

    alpha.gather_book > 0.5      a signal compared with a number
    prev(γ_book) >= 0.8          the same signal one tick earlier
    fact(at-robot a)             a derived fact (as of the start of the tick)
    not fact(has-robot mug)

Signal names are whatever the caller puts in the snapshot; the Dual Dynamics system publishes
sensors and slow variables under their model names, activations as ``alpha.<behavior>``,
actuators under their names and switch variables as ``s.<operator>``.

Every change is a :class:`FactEvent` whose ``cause`` records the rule, the phase (``set``,
``tentative``, ``confirmed``, ``retracted``, ``cleared``, ``implied``, ``exclusive``), the
signal values the rule looked at and how long its condition had held, which is what the
debugger's facts table shows as "why" (§4.3 item 4).
"""

from __future__ import annotations

import math
import operator
import re
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field

from xabsl_studio.engine.errors import PlanningError
from xabsl_studio.engine.planning.strips import Fact

#: Float slack for "held for d seconds" on a tick grid (0.3 s = 15 ticks of 20 ms, give or take).
_EPS = 1e-9

_OPS: Mapping[str, Callable[[float, float], bool]] = {
    "<": operator.lt,
    "<=": operator.le,
    ">": operator.gt,
    ">=": operator.ge,
    "==": operator.eq,
    "!=": operator.ne,
}
_NUM = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_SIGNAL_TERM = re.compile(
    rf"^\s*(?:prev\(\s*(?P<prev>[^()\s]+)\s*\)|(?P<name>[^()\s<>=!]+))\s*"
    rf"(?P<op><=|>=|==|!=|<|>)\s*(?P<value>{_NUM})\s*$"
)
_FACT_TERM = re.compile(r"^\s*(?P<neg>not\s+)?fact\(\s*(?P<fact>[^()]+?)\s*\)\s*$")


class FactRuleError(PlanningError):
    """A fact rule or condition term is malformed; the message quotes it."""


@dataclass(frozen=True, slots=True)
class Term:
    """One conjunct of a rule condition: a signal comparison or a derived-fact test."""

    text: str
    signal: str | None = None
    op: str = ""
    value: float = 0.0
    prev: bool = False
    fact: Fact | None = None
    negated: bool = False

    @classmethod
    def parse(cls, text: str) -> Term:
        """Parse ``"prev(γ_book) >= 0.8"``, ``"alpha.roam > 0.5"`` or ``"not fact(at mug a)"``."""
        m = _FACT_TERM.match(text)
        if m:
            return cls(text.strip(), fact=" ".join(m["fact"].split()), negated=bool(m["neg"]))
        m = _SIGNAL_TERM.match(text)
        if m is None:
            raise FactRuleError(
                f"bad condition term {text!r}: expected 'NAME OP NUMBER', 'prev(NAME) OP NUMBER' or '[not] fact(FACT)'"
            )
        return cls(
            text.strip(),
            signal=m["prev"] or m["name"],
            op=m["op"],
            value=float(m["value"]),
            prev=m["prev"] is not None,
        )

    def holds(self, now: Mapping[str, float], before: Mapping[str, float], facts: frozenset[Fact]) -> bool:
        """Evaluate on this tick's signals, the previous tick's, and the facts at tick start."""
        if self.fact is not None:
            return (self.fact in facts) != self.negated
        assert self.signal is not None
        src = before if self.prev else now
        if self.signal not in src:
            if self.prev:
                return False  # first tick: no history yet, so an edge cannot have happened
            raise FactRuleError(f"condition {self.text!r} reads unknown signal {self.signal!r}")
        return _OPS[self.op](float(src[self.signal]), self.value)

    def observed(self, now: Mapping[str, float], before: Mapping[str, float]) -> tuple[str, float] | None:
        """Return the (label, value) this term looked at, for a FactEvent cause."""
        if self.signal is None:
            return None
        src = before if self.prev else now
        label = f"prev({self.signal})" if self.prev else self.signal
        return label, float(src.get(self.signal, math.nan))


#: A compiled condition: (this tick's signals, last tick's signals, facts at tick start) -> holds.
Check = Callable[[Mapping[str, float], Mapping[str, float], frozenset[Fact]], bool]


def _compile_term(term: Term) -> Check:
    """A closure equivalent to ``term.holds`` without the per-call dispatch on the term's kind."""
    if term.fact is not None:
        fact, negated = term.fact, term.negated
        return lambda now, before, facts: (fact in facts) != negated
    assert term.signal is not None
    sig, value, op = term.signal, term.value, _OPS[term.op]
    if term.prev:

        def prev_holds(now: Mapping[str, float], before: Mapping[str, float], facts: frozenset[Fact]) -> bool:
            v = before.get(sig)
            return False if v is None else op(float(v), value)  # first tick: no history, no edge

        return prev_holds

    def holds(now: Mapping[str, float], before: Mapping[str, float], facts: frozenset[Fact]) -> bool:
        try:
            v = now[sig]
        except KeyError:
            return term.holds(now, before, facts)  # raises the FactRuleError that names the signal
        return op(float(v), value)

    return holds


def compile_condition(terms: Sequence[Term]) -> Check:
    """All ``terms`` hold (an empty condition holds), as one callable; evaluation stops at the first false term."""
    checks = tuple(_compile_term(t) for t in terms)
    if len(checks) == 1:
        return checks[0]

    def all_hold(now: Mapping[str, float], before: Mapping[str, float], facts: frozenset[Fact]) -> bool:
        for check in checks:  # noqa: SIM110 - a plain loop is cheaper than all() over a generator here
            if not check(now, before, facts):
                return False
        return True

    return all_hold


def _terms(spec: Iterable[str | Term]) -> tuple[Term, ...]:
    return tuple(t if isinstance(t, Term) else Term.parse(t) for t in spec)


@dataclass(frozen=True, slots=True)
class FactRule:
    """A history predicate for one fact: when to set it, confirm it, and clear it.

    Attributes:
        fact: the ground fact, spelled as the planner does (``"has-robot book"``).
        set_when: all terms must hold continuously for ``set_dwell`` seconds to set the fact.
        set_dwell: seconds; 0 sets on the first tick the condition holds.
        confirm_for: if > 0, ``set_when`` only makes the fact *tentative*; it is set after this
            many seconds during which ``veto_when`` never held (a veto retracts it).
        veto_when: terms that retract a tentative fact (empty: no veto).
        clear_when: all terms must hold for ``clear_dwell`` seconds to clear the fact (empty:
            the rule never clears its own fact; other rules may, through ``clears``/``group``).
        clear_dwell: seconds.
        clears: facts cleared when this fact becomes true (e.g. At(o,L) clears Has-Robot(o)).
        group: facts sharing a group are mutually exclusive; setting one clears the others.
        name: label used in causes; defaults to the fact.
    """

    fact: Fact
    set_when: tuple[Term, ...]
    set_dwell: float = 0.0
    confirm_for: float = 0.0
    veto_when: tuple[Term, ...] = ()
    clear_when: tuple[Term, ...] = ()
    clear_dwell: float = 0.0
    clears: tuple[Fact, ...] = ()
    group: str | None = None
    name: str = ""

    @classmethod
    def make(
        cls,
        fact: Fact,
        set_when: Sequence[str | Term],
        *,
        set_dwell: float = 0.0,
        confirm_for: float = 0.0,
        veto_when: Sequence[str | Term] = (),
        clear_when: Sequence[str | Term] = (),
        clear_dwell: float = 0.0,
        clears: Sequence[Fact] = (),
        group: str | None = None,
        name: str = "",
    ) -> FactRule:
        """Build a rule from term strings, validating them and the timers."""
        if not set_when:
            raise FactRuleError(f"rule for {fact!r}: set_when is empty")
        for label, v in (
            ("set_dwell", set_dwell),
            ("confirm_for", confirm_for),
            ("clear_dwell", clear_dwell),
        ):
            if not (v >= 0.0 and math.isfinite(v)):
                raise FactRuleError(f"rule for {fact!r}: {label} must be a finite number >= 0, got {v!r}")
        return cls(
            fact=fact,
            set_when=_terms(set_when),
            set_dwell=float(set_dwell),
            confirm_for=float(confirm_for),
            veto_when=_terms(veto_when),
            clear_when=_terms(clear_when),
            clear_dwell=float(clear_dwell),
            clears=tuple(clears),
            group=group,
            name=name or fact,
        )

    @classmethod
    def from_dict(cls, data: Mapping[str, object]) -> FactRule:
        """Build a rule from JSON data with the attribute names as keys."""
        allowed = {
            "fact", "set_when", "set_dwell", "confirm_for", "veto_when",
            "clear_when", "clear_dwell", "clears", "group", "name",
        }  # fmt: skip
        unknown = sorted(set(data) - allowed)
        if unknown:
            raise FactRuleError(f"fact rule {data.get('fact')!r}: unknown keys {', '.join(unknown)}")
        if "fact" not in data or "set_when" not in data:
            raise FactRuleError("fact rule needs 'fact' and 'set_when'")
        kw = {k: v for k, v in data.items() if k not in ("fact", "set_when")}
        return cls.make(str(data["fact"]), list(data["set_when"]), **kw)  # type: ignore[arg-type, call-overload]


@dataclass(frozen=True, slots=True)
class FactEvent:
    """A change of the derived facts (or of a tentative one) and why it happened."""

    t: float
    fact: Fact
    value: bool
    cause: Mapping[str, object]

    def __str__(self) -> str:
        phase = self.cause.get("phase", "")
        return f"{self.t:8.3f}s {'+' if self.value else '-'}{self.fact} ({phase})"


@dataclass(slots=True)
class _RuleState:
    set_since: float | None = None
    clear_since: float | None = None
    tentative_since: float | None = None


@dataclass
class FactDeriver:
    """Run fact rules over a stream of signal snapshots; keep the derived facts and the event log.

    Rules are evaluated synchronously: every condition reads this tick's signals, the previous
    tick's signals and the facts as they were at the start of the tick, so rule order does not
    change which conditions hold (as in the PDL update of §1.4). Changes are then applied in
    rule order, and implied clears (``clears``, ``group``) after the rule that caused them.
    """

    rules: Sequence[FactRule]
    facts: frozenset[Fact] = frozenset()
    events: list[FactEvent] = field(default_factory=list)
    _state: dict[int, _RuleState] = field(default_factory=dict, repr=False)
    _prev: Mapping[str, float] = field(default_factory=dict, repr=False)
    _checks: list[tuple[Check, Check, Check]] = field(default_factory=list, repr=False)

    def __post_init__(self) -> None:
        self.facts = frozenset(self.facts)
        self._state = {i: _RuleState() for i in range(len(self.rules))}
        # Compiled once: the deriver runs every control tick (50 Hz) with a dozen rules.
        self._checks = [
            (compile_condition(r.set_when), compile_condition(r.veto_when), compile_condition(r.clear_when))
            for r in self.rules
        ]
        seen: dict[Fact, str] = {}
        for r in self.rules:
            if r.fact in seen:
                raise FactRuleError(f"two rules derive {r.fact!r} ({seen[r.fact]!r} and {r.name!r})")
            seen[r.fact] = r.name

    @property
    def tentative(self) -> frozenset[Fact]:
        """Facts waiting for confirmation (not part of ``facts`` yet)."""
        return frozenset(r.fact for i, r in enumerate(self.rules) if self._state[i].tentative_since is not None)

    def reset(self, facts: Iterable[Fact]) -> None:
        """Start over from ``facts`` (the planning problem's init, as the paper does)."""
        self.facts = frozenset(facts)
        self._state = {i: _RuleState() for i in range(len(self.rules))}
        self._prev = {}

    def update(self, t: float, signals: Mapping[str, float]) -> list[FactEvent]:
        """Advance to time ``t`` (seconds) with this tick's signal snapshot; return new events."""
        f0 = self.facts
        before = self._prev
        new: list[FactEvent] = []
        facts = set(f0)

        def cause(rule: FactRule, phase: str, terms: Sequence[Term], held: float | None) -> dict[str, object]:
            seen = dict(o for o in (term.observed(signals, before) for term in terms) if o is not None)
            c: dict[str, object] = {"rule": rule.name, "phase": phase, "signals": seen}
            fact_terms = [term.text for term in terms if term.fact is not None]
            if fact_terms:
                c["facts"] = fact_terms
            if held is not None:
                c["held"] = round(held, 6)
            return c

        def implied_clears(rule: FactRule) -> None:
            targets = list(rule.clears)
            if rule.group is not None:
                targets += [r.fact for r in self.rules if r.group == rule.group and r.fact != rule.fact]
            for other in targets:
                if other in facts:
                    facts.discard(other)
                    phase = "implied" if other in rule.clears else "exclusive"
                    new.append(FactEvent(t, other, False, {"rule": rule.name, "phase": phase, "by": rule.fact}))

        states = self._state
        for i, rule in enumerate(self.rules):
            st = states[i]
            set_check, veto_check, clear_check = self._checks[i]
            set_ok = set_check(signals, before, f0)
            if rule.fact in f0:
                st.set_since = None
                clear_ok = bool(rule.clear_when) and clear_check(signals, before, f0)
                if not clear_ok:
                    st.clear_since = None
                    continue
                if st.clear_since is None:
                    st.clear_since = t
                held = t - st.clear_since
                if held + _EPS >= rule.clear_dwell and rule.fact in facts:
                    facts.discard(rule.fact)
                    st.clear_since = None
                    new.append(FactEvent(t, rule.fact, False, cause(rule, "cleared", rule.clear_when, held)))
                continue
            st.clear_since = None
            if st.tentative_since is not None:
                if rule.veto_when and veto_check(signals, before, f0):
                    st.tentative_since = None
                    new.append(FactEvent(t, rule.fact, False, cause(rule, "retracted", rule.veto_when, None)))
                elif t - st.tentative_since + _EPS >= rule.confirm_for:
                    held = t - st.tentative_since
                    st.tentative_since = None
                    facts.add(rule.fact)
                    new.append(FactEvent(t, rule.fact, True, cause(rule, "confirmed", rule.veto_when, held)))
                    implied_clears(rule)
                continue
            if not set_ok:
                st.set_since = None
                continue
            if st.set_since is None:
                st.set_since = t
            held = t - st.set_since
            if held + _EPS < rule.set_dwell:
                continue
            st.set_since = None
            if rule.confirm_for > 0.0:
                st.tentative_since = t
                new.append(FactEvent(t, rule.fact, False, cause(rule, "tentative", rule.set_when, held)))
            else:
                facts.add(rule.fact)
                new.append(FactEvent(t, rule.fact, True, cause(rule, "set", rule.set_when, held)))
                implied_clears(rule)

        self.facts = frozenset(facts)
        self._prev = dict(signals)
        self.events.extend(new)
        return new


def errands_rules(locations: Sequence[str] = ("a", "b", "c"), items: Sequence[str] = ("book", "mug")) -> list[FactRule]:
    """Build the §1.6 table for the errands world, with the DD model's signal names.

    Signals read: ``δ_<x>`` (near beacon x), ``γ_<o>`` (object detector), ``alpha.gather_<o>``,
    ``alpha.dump_<o>``, ``g_<o>``, ``d_<o>`` (gripper actuators).
    """
    rules: list[FactRule] = []
    for x in locations:
        rules.append(
            FactRule.make(
                f"at-robot {x}",
                [f"δ_{x} >= 0.5"],
                set_dwell=0.3,
                clear_when=[f"δ_{x} < 0.5"],
                clear_dwell=0.3,
                group="at-robot",
            )
        )
    for o in items:
        rules.append(
            FactRule.make(
                f"has-robot {o}",
                # The object vanished into the closing gripper while gather was in charge.
                [f"alpha.gather_{o} > 0.5", f"g_{o} > 0.5", f"prev(γ_{o}) >= 0.8", f"γ_{o} <= 0"],
                confirm_for=1.0,
                veto_when=[f"γ_{o} > 0.3"],
                # Seen again while still gathering: the capture failed.
                clear_when=[f"γ_{o} > 0.3", f"alpha.gather_{o} > 0.5"],
                clears=[f"at {o} {x}" for x in locations],
            )
        )
        for x in locations:
            rules.append(
                FactRule.make(
                    f"at {o} {x}",
                    [f"alpha.dump_{o} > 0.5", f"d_{o} > 0.5", f"fact(at-robot {x})"],
                    set_dwell=0.3,
                    clears=[f"has-robot {o}"],
                    group=f"at {o}",
                )
            )
    return rules
