"""Load-time checks of the option graph (§2.10): loops, and double execution under policy B2.

Both original engine generations reject an option reachable from itself along a call path
(a loop would recurse forever). Generation B2 additionally rejects any option or basic
behavior that could occur twice in one activation tree, for example when two subsequent
behaviors of one state share a sub-behavior. The checks run per agent root (and for every root
a debugger forces), exactly as the original checks per agent.
"""

from __future__ import annotations

import enum

from xabsl_studio.engine.errors import LoadError
from xabsl_studio.engine.ir.model import BehaviorCall, OptionCall, Program

__all__ = ["Policy", "check_root"]


class Policy(enum.Enum):
    """Which original engine generation's structural rules apply (§2.2, §2.10)."""

    #: Reject loops only; an option executed twice in one tick logs a warning and runs again.
    B1 = "B1"
    #: Reject loops and anything that could run twice in one activation tree; a double
    #: execution at run time is a fault.
    B2 = "B2"


def check_root(program: Program, root: str, policy: Policy) -> None:
    """Check the option graph below option ``root``.

    Raises:
        LoadError: a loop (always) or a possible double execution (policy B2), with the path.
    """
    reach: dict[str, frozenset[str]] = {}

    def visit(option: str, path: tuple[str, ...]) -> frozenset[str]:
        if option in path:
            cycle = " -> ".join((*path[path.index(option) :], option))
            raise LoadError(f"option {option} is reachable from itself: {cycle}")
        if option in reach:
            return reach[option]
        result: set[str] = {f"option {option}"}
        for state in program.options[option].states:
            seen: set[str] = set()
            for action in state.actions:
                if isinstance(action, OptionCall):
                    below = visit(action.option, (*path, option))
                elif isinstance(action, BehaviorCall):
                    below = frozenset({f"basic behavior {action.behavior}"})
                else:
                    continue
                if policy is Policy.B2:
                    twice = (seen & below) | ({f"option {option}"} & below)
                    if twice:
                        name = sorted(twice)[0]
                        raise LoadError(
                            f"{name} could be executed twice in one activation tree "
                            f"(state {option}.{state.name}, rejected under policy B2)"
                        )
                seen |= below
            result |= seen
        reach[option] = frozenset(result)
        return reach[option]

    visit(root, ())
