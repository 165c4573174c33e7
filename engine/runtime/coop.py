"""Cooperative states and the team-message interface of one agent (§2.11).

``state s capacity n`` admits at most ``n`` agents, ``state s synchronized [n]`` is entered only
when all agents in the option (and at least ``n``) enter together, and ``conflict`` is true while
more agents than the capacity execute the active capacity state. Agents learn about each other
only through :class:`TeamMessage` s the host exchanges: ``prepare_incoming_messages()`` clears
what was heard, ``process_incoming_message()`` adds one teammate's message,
``generate_outgoing_message()`` describes this agent after its tick.

Our model of the original checks (the original sources of ``XabslCoopState.h`` are not part
of the spec; this model reproduces the kit's ``cooperative`` trace and the rules above):

* capacity ``n``: entering is allowed when fewer than ``n`` *other* agents execute the state,
  no other agent with a higher priority is entering it, and this agent has been trying for more
  than ``synchronization_ticks`` consecutive ticks (0: at once);
* synchronized ``[n]``: entering is allowed when the agents that announce entering it (from
  processed messages; a host that loops an agent's own message back counts it) number at least
  ``n`` and at least the agents announcing the option; with no messages it is never entered;
* the check only runs when the decision names another state: a blocked transition, like a
  ``stay``, leaves the option in its active state without resetting it;
* ``conflict``: in a capacity state, other executing agents + this one > capacity; otherwise
  false.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from xabsl_studio.engine.ir.model import Program

__all__ = ["CoopStates", "TeamMessage"]


@dataclass(frozen=True, slots=True)
class TeamMessage:
    """What one agent tells its team after a tick (names are ``"option.state"``)."""

    agent: str
    priority: int = 0
    executing: frozenset[str] = frozenset()
    entering: frozenset[str] = frozenset()
    options: frozenset[str] = frozenset()


@dataclass(slots=True)
class _CoopState:
    name: str
    option: str
    synchronized: bool
    count: int
    others_executing: int = 0
    announced_entering: int = 0
    higher_priority_entering: bool = False
    tries: int = 0
    last_try: int = -10


@dataclass
class CoopStates:
    """The cooperative states of one engine and what the agent heard about them."""

    agent: str = ""
    agent_priority: int = 0
    synchronization_ticks: int = 0
    states: dict[tuple[int, int], _CoopState] = field(default_factory=dict)
    options_heard: dict[str, int] = field(default_factory=dict)
    #: returns the current tick (the engine's counter)
    tick: Callable[[], int] = lambda: 0
    #: returns the ``(option index, state index)`` of every coop state executed this tick
    executing: Callable[[], list[tuple[int, int]]] = list
    entering_now: set[tuple[int, int]] = field(default_factory=set)

    @classmethod
    def of(cls, program: Program) -> CoopStates:
        """The coop states of ``program`` (keys are option and state indices)."""
        coop = cls()
        for i, option in enumerate(program.options.values()):
            for state in option.states:
                if state.coop != "n":
                    coop.states[(i, state.index)] = _CoopState(
                        f"{option.name}.{state.name}", option.name, state.coop == "s", state.coop_count
                    )
        return coop

    # -- team-message interface ---------------------------------------------------------------

    def prepare_incoming_messages(self) -> None:
        """Forget what was heard: call before processing a new round of messages."""
        self.options_heard.clear()
        for state in self.states.values():
            state.others_executing = 0
            state.announced_entering = 0
            state.higher_priority_entering = False

    def process_incoming_message(self, message: TeamMessage) -> None:
        """Take one message into account (own messages count only for synchronization)."""
        own = message.agent == self.agent
        for option in message.options:
            self.options_heard[option] = self.options_heard.get(option, 0) + 1
        for state in self.states.values():
            if state.name in message.executing and not own:
                state.others_executing += 1
            if state.name in message.entering:
                state.announced_entering += 1
                if not own and message.priority > self.agent_priority:
                    state.higher_priority_entering = True

    def generate_outgoing_message(self) -> TeamMessage:
        """This agent's message after its tick."""
        executing = {self.states[k].name for k in self.executing() if k in self.states}
        options = {self.states[k].option for k in self.executing() if k in self.states}
        entering = {self.states[k].name for k in self.entering_now}
        return TeamMessage(
            self.agent, self.agent_priority, frozenset(executing), frozenset(entering), frozenset(options)
        )

    # -- called by generated code ---------------------------------------------------------------

    def check(self, option: int, target: int, _active: int) -> bool:
        """Run ``coopCheck()`` of the state the decision chose: may the agent enter it now."""
        state = self.states[(option, target)]
        tick = self.tick()
        state.tries = state.tries + 1 if state.last_try == tick - 1 else 1
        state.last_try = tick
        if state.synchronized:
            needed = max(state.count, self.options_heard.get(state.option, 0), 1)
            allowed = state.announced_entering >= needed
        else:
            allowed = (
                state.others_executing < state.count
                and not state.higher_priority_entering
                and state.tries > self.synchronization_ticks
            )
        if allowed:
            self.entering_now.discard((option, target))
        else:
            self.entering_now.add((option, target))
        return allowed

    def conflict(self, option: int, active: int) -> bool:
        """``conflict`` in the active state: more agents than its capacity execute it."""
        state = self.states.get((option, active))
        if state is None or state.synchronized:
            return False
        return state.others_executing + 1 > state.count
