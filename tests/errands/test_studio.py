"""The errands world in the studio: its panels' data in the frames and its world commands.

A client written against docs/protocol.md reads the plan and the DD model from the session, sees
α of every behavior, the Δα terms, s_OP and the actuator fusion in the frames, sends a
perturbation through the generic op ``world_command`` and watches the plan change.
"""

from __future__ import annotations

import gc
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.server.conftest import LiveServer, WsClient
from xabsl_studio.engine.worlds.loader import load_example
from xabsl_studio.server.session.live import Session

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture
def errands_session(tmp_path: Path) -> Iterator[Session]:
    root = tmp_path / "errands"
    root.mkdir()
    shutil.copytree(REPO / "examples" / "errands" / "behavior", root / "behavior")
    shutil.copytree(REPO / "examples" / "errands" / "model", root / "model")
    (root / "studio.py").write_text(
        '"""The errands plug-in."""\n\nfrom xabsl_studio.examples.errands.studio import example\n'
    )
    plugin = load_example(root)
    session = Session(plugin, seed=1, speed=20.0, behavior_hz=plugin.behavior_hz, physics_hz=plugin.physics_hz)
    yield session
    session.stop()
    del session
    gc.collect()  # pymunk spaces must be freed while the interpreter runs


def world(client: WsClient, name: str | None = None, **args: Any) -> dict[str, Any]:
    reply = client.command("world_command", **({} if name is None else {"name": name, "args": args}))
    assert reply["ok"], reply
    return reply["result"]  # type: ignore[no-any-return]


def test_the_world_announces_its_panels_and_commands_and_the_frames_carry_the_dynamics(
    errands_session: Session, client_for: Any
) -> None:
    with LiveServer(errands_session) as server:
        client = client_for(server)
        hello = client.until(lambda m: m["type"] == "hello")
        scene = hello["scene"]
        assert scene["panels"] == ["dynamics", "plan", "facts"]
        behaviors = scene["dd"]["behaviors"]
        assert len(behaviors) == 8 and "roam" in behaviors and scene["dd"]["actuators"][:2] == ["m_l", "m_r"]
        listed = world(client)["commands"]
        assert [c["name"] for c in listed] == [c["name"] for c in scene["commands"]]
        groups = {c["name"]: c["group"] for c in listed}
        assert groups["teleport"] == groups["remove"] == groups["block"] == "perturb"
        assert groups["force_operator"] == groups["replan"] == groups["set_fact"] == "monitor"

        frame = client.frame_after(
            lambda f: f["scene"]["op"] == "goto a c" and f["scene"]["s"].get("goto a c", 0) > 0.3
        )
        dyn = frame["scene"]
        assert len(dyn["alpha"]) == 8 and all(0.0 <= a <= 1.0 for a in dyn["alpha"])
        terms = dyn["terms"]
        assert set(scene["dd"]["terms"]) == set(terms)
        approach_c = behaviors.index("approach_c")
        # The plan bias pulls approach_c on while GOTO(a, c) runs; the drive's parts add up to u.
        assert terms["plan"][approach_c] > 0.0
        for i in range(8):
            parts = terms["sensors"][i] + terms["self"][i] + terms["others"][i] + terms["bias"][i]
            assert parts == pytest.approx(terms["u"][i], abs=1e-3)
        fusion = dyn["fusion"]["m_l"]
        assert len(fusion["shares"]) == 8 and isinstance(fusion["value"], float)
        assert dyn["plan_version"] == 1 and dyn["op_timeout"] == 60000 and dyn["op_since"] <= frame["t"]

        # The DD model and the plan, read from the session.
        model = world(client, "model")
        assert model["behaviors"] == behaviors and set(model["oct"]) == {"goto", "load", "unload"}
        plan = world(client, "plan")
        (first,) = plan["versions"]
        assert first["reason"] == "start" and first["layers"][0] == ["goto a c"]
        assert first["layers"][-1] == ["unload book a", "unload mug a"]
        stats = world(client, "plan_stats", version=1)["runs"][0]
        assert stats["solved"] and len(stats["levels"]) == 7 and stats["text"].startswith("level |P| |A|")
        assert stats["levels"][5]["extraction"] == "failed" and stats["levels"][6]["extraction"] == "success"


def test_a_teleported_mug_leads_to_a_replan_with_its_reason_and_facts_say_why(
    errands_session: Session, client_for: Any
) -> None:
    with LiveServer(errands_session) as server:
        client = client_for(server)
        client.frame_after(lambda f: f["scene"]["op"] == "goto a c")
        done = world(client, "teleport", object="mug", to="b")
        assert done["done"] == "teleported the mug to b"
        frame = client.frame_after(lambda f: f["scene"]["plan_version"] >= 2, timeout=60)
        versions = world(client, "plan")["versions"]
        assert versions[1]["reason"] == "precondition_lost" and versions[1]["kind"] == "partial"
        assert versions[0]["failed"] == {"load mug c": "precondition_lost"}
        assert versions[0]["done"] == ["goto a c"] and not versions[0]["current"] and versions[1]["current"]
        # Why did the robot stop believing the mug is at c? The search rule, after 12 s.
        events = world(client, "fact_events")["events"]
        assert len(events) <= frame["scene"]["fact_events"] + 5
        lost = next(e for e in events if e["fact"] == "at mug c" and not e["value"])
        assert lost["cause"]["phase"] == "cleared" and lost["cause"]["held"] >= 12.0
        assert lost["cause"]["signals"], "the cause names the signals that held"
        later = world(client, "fact_events", since=lost["i"])["events"]
        assert later[0] == lost


def test_forcing_an_operator_a_replan_and_a_fact_by_hand(errands_session: Session, client_for: Any) -> None:
    with LiveServer(errands_session) as server:
        client = client_for(server)
        client.frame_after(lambda f: f["scene"]["op"] == "goto a c")
        world(client, "force_operator", operator="goto a b")
        frame = client.frame_after(lambda f: f["scene"]["op"] == "goto a b")
        assert frame["scene"]["forced_op"] == "goto a b"
        world(client, "force_operator", operator="none")
        client.frame_after(lambda f: f["scene"]["op"] == "goto a c" and f["scene"]["forced_op"] is None)

        assert world(client, "replan")["version"] == 2
        plan = world(client, "plan")
        assert plan["versions"][1]["reason"] == "by_hand"
        assert [i["what"] for i in plan["interventions"]] == [
            "forced operator goto a b",
            "released the operator",
            "replanned by hand",
        ]

        world(client, "set_fact", fact="has-robot book", value=True)
        frame = client.frame_after(lambda f: "has-robot book" in f["scene"]["facts"] or f["scene"]["fact_events"] > 0)
        events = world(client, "fact_events")["events"]
        forced = [e for e in events if e["fact"] == "has-robot book"]
        assert forced and forced[0]["value"] is True and forced[0]["cause"] == {"rule": "by hand", "phase": "forced"}


def test_the_model_file_is_checked_with_key_line_and_column_saved_atomically_and_hot_reloaded(
    errands_session: Session, client_for: Any
) -> None:
    path = errands_session.example.root / "model" / "errands_dd.json"
    with LiveServer(errands_session) as server:
        client = client_for(server)
        client.frame_after(lambda f: f["scene"]["op"] == "goto a c")
        source = world(client, "model_source")
        assert source["path"] == "model/errands_dd.json" and source["text"] == path.read_text()
        text = source["text"]
        assert world(client, "model_check", text=text) == {"ok": True, "diagnostics": []}
        # An unknown name in roam's drive: the diagnostic points at it, inside the expression.
        broken = text.replace('"drive": "1 - 1.2*max(', '"drive": "1 - zork*max(', 1)
        (diagnostic,) = world(client, "model_check", text=broken)["diagnostics"]
        assert diagnostic["key"] == "behaviors.roam.drive" and "unknown name 'zork'" in diagnostic["message"]
        span = diagnostic["span"]
        assert broken[span["start"] : span["start"] + 4] == "zork"
        line = broken.splitlines()[span["line"] - 1]
        assert line[span["col"] - 1 :].startswith("zork")
        (bad_json,) = world(client, "model_check", text=text.replace('"dt": 0.02,', '"dt": 0.02,,'))["diagnostics"]
        assert bad_json["message"].startswith("not valid JSON") and bad_json["span"]["line"] == 5

        # A broken save keeps the file (the text is never lost) and the running model.
        saved = world(client, "model_save", text=broken, version=source["version"])
        assert saved["saved"] and not saved["ok"] and not saved["reloaded"] and path.read_text() == broken
        # Saving against an old version is refused; against the current one it hot-reloads.
        stale = client.command("world_command", name="model_save", args={"text": text, "version": source["version"]})
        assert stale["ok"] is False and "changed on disk" in stale["error"]
        tuned = text.replace('"c_oct": 10.0', '"c_oct": 9.0')
        assert tuned != text
        saved = world(client, "model_save", text=tuned, version=saved["version"])
        assert saved["ok"] and saved["reloaded"] and path.read_text() == tuned
        assert {c["c"] for c in world(client, "model")["oct"]["goto"]["couplings"]} == {9.0}
        # The robot goes on with the new model (its run did not restart).
        frame = client.frame_after(lambda f: f["scene"]["op"] == "goto a c" and f["t"] > 2000)
        assert frame["scene"]["plan_version"] == 1


@pytest.mark.parametrize(
    ("name", "args", "error"),
    [
        ("fly", {}, "unknown world command 'fly'"),
        ("teleport", {"object": "cup", "to": "b"}, "object must be one of book, mug"),
        ("block", {"from": "c", "to": "c"}, "different beacons"),
        ("force_operator", {"operator": "goto a z"}, "operator must be one of"),
        ("set_fact", {"fact": "at mug c", "value": "yes"}, "value must be true or false"),
        ("plan_stats", {"version": 9}, "version must be in 1..1"),
        ("fact_events", {"since": -1}, "since must be >= 0"),
    ],
)
def test_bad_world_commands_are_refused_with_a_message(
    errands_session: Session, client_for: Any, name: str, args: dict[str, Any], error: str
) -> None:
    with LiveServer(errands_session) as server:
        client = client_for(server)
        client.frame_after(lambda f: f["scene"]["plan_version"] == 1)
        reply = client.command("world_command", name=name, args=args)
        assert reply["ok"] is False and error in reply["error"]
        bad = client.command("world_command", name=3)
        assert bad["ok"] is False and "name: Input should be a valid string" in bad["error"]


def test_a_world_command_it_does_not_have_is_named(live_demo: LiveServer, client_for: Any) -> None:
    # the bench world has commands of its own (values by hand), not the errands world's
    client = client_for(live_demo)
    client.frame_after()
    reply = client.command("world_command", name="teleport")
    assert (
        reply["ok"] is False and reply["error"] == "unknown command 'teleport' (set_input, set_function, follow_world)"
    )
