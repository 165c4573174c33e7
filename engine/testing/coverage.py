"""The coverage of a test suite: options, states, transitions and decision leaves reached.

Counted from the activation trees of the tested robot, tick by tick: an option is reached when
it ran, a state when an option ran in it, a transition ``option: a -> b`` when a decision that
ran in state ``a`` left the option in ``b``, a decision leaf ``option/state#leaf`` when it fired.
The totals come from the program: every option and state, every leaf of every state's (inlined)
decision tree, and every distinct ``goto`` target other than the state itself.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

from xabsl_studio.engine.ir.model import Program, leaves
from xabsl_studio.engine.runtime.activation import Node, OptionNode

__all__ = ["Coverage", "ProgramCoverage"]

Key = tuple[str, ...]


@dataclass(slots=True)
class ProgramCoverage:
    """What one program (by key) offers and what of it was reached."""

    options: set[Key] = field(default_factory=set)
    states: set[Key] = field(default_factory=set)
    transitions: set[Key] = field(default_factory=set)
    leaves: set[Key] = field(default_factory=set)
    reached_options: set[Key] = field(default_factory=set)
    reached_states: set[Key] = field(default_factory=set)
    reached_transitions: set[Key] = field(default_factory=set)
    reached_leaves: set[Key] = field(default_factory=set)

    @classmethod
    def of(cls, program: Program) -> ProgramCoverage:
        """The totals of ``program``."""
        cov = cls()
        for option in program.options.values():
            cov.options.add((option.name,))
            for state in option.states:
                cov.states.add((option.name, state.name))
                for leaf in leaves(state.decision):
                    cov.leaves.add((option.name, state.name, str(leaf.leaf)))
                    if leaf.target is not None and not leaf.stay and leaf.target != state.name:
                        cov.transitions.add((option.name, state.name, leaf.target))
        return cov

    def add(self, tree: Sequence[Node]) -> None:
        """Count what ran in one tick."""
        stack = list(tree)
        while stack:
            node = stack.pop()
            if not isinstance(node, OptionNode):
                continue
            self.reached_options.add((node.option,))
            self.reached_states.add((node.option, node.state))
            if node.leaf >= 0:
                self.reached_leaves.add((node.option, node.decided_in, str(node.leaf)))
            if node.decided_in != node.state:
                self.reached_transitions.add((node.option, node.decided_in, node.state))
            stack.extend(node.sub)

    def merge(self, other: ProgramCoverage) -> None:
        """Add what ``other`` reached (same program)."""
        for name in ("options", "states", "transitions", "leaves"):
            getattr(self, name).update(getattr(other, name))
            getattr(self, f"reached_{name}").update(getattr(other, f"reached_{name}"))

    def figures(self) -> dict[str, tuple[int, int]]:
        """Per kind ``(reached, total)``; reached counts only what the program has."""
        return {
            name: (len(getattr(self, f"reached_{name}") & getattr(self, name)), len(getattr(self, name)))
            for name in ("options", "states", "transitions", "leaves")
        }

    def unreached_options(self) -> list[str]:
        """The options no test ran, sorted."""
        return sorted(o[0] for o in self.options - self.reached_options)


@dataclass(slots=True)
class Coverage:
    """Coverage per program key (a suite may test several behavior sets)."""

    programs: dict[str, ProgramCoverage] = field(default_factory=dict)

    def add_program(self, key: str, program: Program) -> None:
        """Count against ``program`` under ``key``."""
        if key not in self.programs:
            self.programs[key] = ProgramCoverage.of(program)

    def add(self, key: str, tree: Sequence[Node]) -> None:
        """Count one tick of the program ``key``."""
        self.programs[key].add(tree)

    def merge(self, other: Coverage) -> None:
        """Add another run's coverage."""
        for key, cov in other.programs.items():
            mine = self.programs.get(key)
            if mine is None:
                self.programs[key] = mine = ProgramCoverage()
            mine.merge(cov)

    @classmethod
    def total(cls, parts: Iterable[Coverage | None]) -> Coverage:
        """The merged coverage of several runs."""
        out = cls()
        for part in parts:
            if part is not None:
                out.merge(part)
        return out

    def lines(self) -> list[str]:
        """The report: one line per program, then the options no test reached."""
        out = []
        for key, cov in sorted(self.programs.items()):
            figures = cov.figures()
            shown = ", ".join(f"{name} {r}/{t} ({100 * r / t if t else 100:.0f}%)" for name, (r, t) in figures.items())
            out.append(f"coverage of {key}: {shown}")
            missing = cov.unreached_options()
            if missing:
                out.append(f"  options not reached: {', '.join(missing)}")
        return out

    def to_json(self) -> dict[str, dict[str, list[int]]]:
        """Per program and kind ``[reached, total]``."""
        return {key: {k: list(v) for k, v in cov.figures().items()} for key, cov in self.programs.items()}
