"""Cooperative states through the team-message interface (§2.11)."""

from __future__ import annotations

from tests.runtime.helpers import Host, ic
from xabsl_studio.engine.runtime.coop import TeamMessage

TEAM = """
0 0 1 team 0
3 idle n busy c 1 meet s 0 idle
0 0 i > i x 0 v 0 t busy t idle
0 1 b o.conflict x  i > i x 0 v 5 t meet t busy
0 0 t meet
1 member team
"""


def test_capacity_state_is_blocked_while_another_agent_executes_it() -> None:
    host = Host(ic(TEAM))
    coop = host.engine.coop
    coop.agent = "me"
    coop.prepare_incoming_messages()
    coop.process_incoming_message(TeamMessage("mate", executing=frozenset({"team.busy"}), options=frozenset({"team"})))
    host.tick(0, x=1.0)
    assert host.state("team") == "idle"
    assert coop.generate_outgoing_message().entering == frozenset({"team.busy"})
    coop.prepare_incoming_messages()
    host.tick(10)
    assert host.state("team") == "busy"
    assert host.engine.output("o.conflict") is False


def test_synchronized_state_is_entered_when_everyone_enters_together() -> None:
    host = Host(ic(TEAM))
    coop = host.engine.coop
    coop.agent = "me"
    host.tick(0, x=1.0)
    host.tick(10, x=9.0)
    assert host.state("team") == "busy", "nobody announced entering meet"
    coop.prepare_incoming_messages()
    for agent in ("me", "mate"):
        coop.process_incoming_message(
            TeamMessage(agent, entering=frozenset({"team.meet"}), options=frozenset({"team"}))
        )
    host.tick(20)
    assert host.state("team") == "meet"
