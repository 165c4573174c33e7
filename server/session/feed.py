"""The session's ticks as the recording's topics: ring entries -> JSON messages per topic.

A live viewer that speaks MCAP's vocabulary (Foxglove, Lichtblick; ``xabsl_studio.server.api.foxglove``)
sees the studio's session on the topics and schemas of a recording (docs/recordings.md,
``xabsl_studio.engine.record.schema``), so a layout made on a recording works on the session. This
module owns that translation; it knows nothing of websockets.

:class:`TopicFeed` is fed the ring's :class:`~xabsl_studio.server.session.frames.Entry` objects in
order (a live session's, or a replay's as it plays or seeks) and turns each into
:class:`FeedMessage` objects, timestamped like a recording's (``seq`` x the tick period, in ns):

* ``/xabsl/agents/NAME`` (``xabsl.AgentTick``) every tick: the path and *every* symbol value
  (``key: true`` always): a viewer may subscribe at any tick and a slow one may lose messages, so
  no message depends on an earlier one. ``gen`` is the studio's generation number, the same as in
  the ``/xabsl/program`` message that describes it; ``tick`` is the studio's ``seq`` (the studio's
  frames do not carry the engine's own counter, as in a studio recording);
* ``/xabsl/agents/NAME/fault`` when the fault changes; ``/world/scene`` every tick;
  ``/world/status`` when it changed (and on the first tick); ``/foxglove/scene`` every
  :data:`~xabsl_studio.engine.record.encoder.FOXGLOVE_EVERY`-th tick and on the first of a generation;
* per generation: ``/xabsl/program`` (one message per program key), ``/world/static`` and,
  for planar worlds, ``/foxglove/field``.

A viewer that subscribes later still needs the messages that describe what it sees:
:meth:`TopicFeed.latched` keeps the last ones of the topics that are not sent every tick
(programs, static scene, field, status, faults). ``/xabsl/recording`` (a file's header) is not
served: a session is not a file, and its generations are on ``/xabsl/program``.

Values are the frames' display values (decimals to the studio's precision, enums named by their
element), unknown values null.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import orjson

from xabsl_studio.engine.record import foxglove
from xabsl_studio.engine.record import schema as S
from xabsl_studio.engine.record.encoder import FOXGLOVE_EVERY, Nesting
from xabsl_studio.server.session.frames import Entry, Generation

__all__ = ["FeedMessage", "TopicFeed", "schema_of"]

#: The schemas the feed's topics use, by name (the recording's, and Foxglove's SceneUpdate).
SCHEMAS: dict[str, dict[str, Any]] = {
    **S.SCHEMAS,
    str(foxglove.SCENE_UPDATE_SCHEMA["title"]): foxglove.SCENE_UPDATE_SCHEMA,
}


def schema_of(name: str) -> dict[str, Any]:
    """The JSON Schema called ``name`` (``xabsl.AgentTick``, ``foxglove.SceneUpdate``, ...)."""
    return SCHEMAS[name]


@dataclass(frozen=True, slots=True)
class FeedMessage:
    """One message of a topic: its timestamp (ns, the tick's) and JSON bytes."""

    topic: str
    time_ns: int
    data: bytes


class _Agent:
    """How one robot's values become nested JSON in one generation."""

    __slots__ = ("inputs", "name", "outputs", "topic")

    def __init__(self, name: str, inputs: Nesting, outputs: Nesting) -> None:
        self.name = name
        self.topic = S.agent_topic(name)
        self.inputs = inputs
        self.outputs = outputs


def _nesting(symbols: dict[int, dict[str, Any]], ids: tuple[int, ...], tables: dict[str, dict[int, str]]) -> Nesting:
    """Values aligned with ``ids`` (display values: enums as element indices) -> nested names."""
    described = [symbols[i] for i in ids]
    return Nesting(
        tuple(str(s["name"]) for s in described),
        tuple(s.get("enum") if s.get("type") == "enum" else None for s in described),
        tuple(False for _ in described),  # display values are rounded already
        tables,
        None,
    )


class TopicFeed:
    """Ring entries -> recording-topic messages (see the module docstring).

    Args:
        behavior_hz: the session's tick rate (timestamps are ``seq`` x its period).
        generation_events: write ``reload`` and ``reset`` events on ``/xabsl/events`` when a new
            generation comes (a live session; a replay serves its recorded events instead).
    """

    def __init__(self, behavior_hz: int, generation_events: bool = True) -> None:
        self.behavior_hz = behavior_hz
        self.generation_events = generation_events
        self._descriptions: dict[str, bytes] = {}
        #: topic -> schema name of every topic the feed has produced or will produce
        self.topics: dict[str, str] = {
            S.PROGRAM: "xabsl.Program",
            S.EVENTS: "xabsl.Event",
            S.WORLD_STATIC: "xabsl.StaticScene",
            S.WORLD_SCENE: "xabsl.DynamicScene",
            S.WORLD_STATUS: "xabsl.WorldStatus",
        }
        self._gen: Generation | None = None
        self._number: int | None = None
        self._agents: list[_Agent | None] = []
        self._scene: foxglove.SceneBuilder | None = None
        self._scene_due = True
        self._status: bytes | None = None
        self._faults: dict[int, Any] = {}
        self._latched: dict[str, list[FeedMessage]] = {}
        self.last_seq: int | None = None

    def time_ns(self, seq: int) -> int:
        """The timestamp of tick ``seq`` (as a recording's ``log_time``)."""
        return S.tick_time_ns(seq, self.behavior_hz)

    def latched(self, topic: str) -> list[FeedMessage]:
        """The messages a new subscriber of ``topic`` receives at once (none for per-tick topics)."""
        return list(self._latched.get(topic, ()))

    # -- entries ------------------------------------------------------------------------------------

    def entry(self, entry: Entry, wanted: Iterable[str] | None = None) -> list[FeedMessage]:
        """The messages of one tick; only per-tick topics in ``wanted`` are built (None: all).

        Generation messages and the latched topics are always kept (a subscriber may come later).
        """
        want = None if wanted is None else set(wanted)
        out: list[FeedMessage] = []
        time_ns = self.time_ns(entry.seq)
        if entry.gen is not self._gen:
            fresh = self._number != entry.gen.number
            self._generation(entry, time_ns, out, fresh)
        seq, t = entry.seq, entry.t
        dumps = orjson.dumps
        loads = orjson.loads
        if entry.paths is not None and entry.inputs is not None and entry.outputs is not None:
            extras = entry.extras or ()
            for i, agent in enumerate(self._agents):
                if agent is None:
                    continue
                extra = extras[i] if i < len(extras) else b""
                fault = loads(b"{" + extra[1:] + b"}").get("fault") if extra else None
                if i not in self._faults or self._faults[i] != fault:
                    self._faults[i] = fault
                    topic = S.fault_topic(agent.name)
                    message = FeedMessage(topic, time_ns, dumps({"seq": seq, "t": t, "fault": fault}))
                    self._latched[topic] = [message]
                    out.append(message)
                if want is not None and agent.topic not in want:
                    continue
                tick: dict[str, Any] = {
                    "seq": seq,
                    "t": t,
                    "gen": entry.gen.number,
                    "tick": seq,
                    "path": orjson.Fragment(entry.paths[i]),
                    "key": True,
                    "inputs": agent.inputs.encode(entry.inputs[i], ()),
                    "outputs": agent.outputs.encode(entry.outputs[i], ()),
                }
                if i < len(entry.reads) and entry.reads[i]:
                    tick["reads"] = orjson.Fragment(entry.reads[i])
                out.append(FeedMessage(agent.topic, time_ns, dumps(tick)))
        if want is None or S.WORLD_SCENE in want:
            scene = {"seq": seq, "t": t, "scene": orjson.Fragment(entry.scene)}
            out.append(FeedMessage(S.WORLD_SCENE, time_ns, dumps(scene)))
        if entry.status != self._status:
            self._status = entry.status
            message = FeedMessage(
                S.WORLD_STATUS, time_ns, dumps({"seq": seq, "t": t, "status": orjson.Fragment(entry.status)})
            )
            self._latched[S.WORLD_STATUS] = [message]
            out.append(message)
        builder = self._scene
        due = builder is not None and (self._scene_due or seq % FOXGLOVE_EVERY == 0)
        if builder is not None and due and (want is None or S.FOXGLOVE_SCENE in want):
            self._scene_due = False
            out.append(FeedMessage(S.FOXGLOVE_SCENE, time_ns, dumps(builder.update(loads(entry.scene), time_ns))))
        self.last_seq = seq
        return out

    def event(self, seq: int, t: int, kind: str, agent: str | None, data: dict[str, Any]) -> FeedMessage:
        """An ``xabsl.Event`` at tick ``seq`` (a command the session carried out, a recorded event)."""
        body = {"seq": seq, "t": t, "kind": kind, "agent": agent, "data": data}
        return FeedMessage(S.EVENTS, self.time_ns(seq), orjson.dumps(body))

    def _generation_events(self, entry: Entry, out: list[FeedMessage]) -> None:
        """The events of a new generation: a ``reload`` per program that changed, or a ``reset``."""
        gen = entry.gen
        if gen.reason == "reload":
            for key, description in gen.structure.get("programs", {}).items():
                if orjson.dumps(description) != self._descriptions.get(key):
                    data = {"key": key, "gen": gen.number, "changed_files": list(gen.changed.get(key, ()))}
                    out.append(self.event(entry.seq, entry.t, "reload", None, data))
        elif gen.reason in ("reset", "fork"):
            out.append(self.event(entry.seq, entry.t, "reset", None, {"reason": gen.reason, "gen": gen.number}))

    def _generation(self, entry: Entry, time_ns: int, out: list[FeedMessage], fresh: bool) -> None:
        """A new generation (or the same number rebuilt, as a replay's seek does): its descriptions."""
        gen = entry.gen
        self._gen = gen
        first = self._number is None
        self._number = gen.number
        programs = gen.structure.get("programs", {})
        static = orjson.loads(gen.scene_bytes)
        dumps = orjson.dumps
        descriptions = []
        for key, description in programs.items():
            body = {
                "seq": entry.seq,
                "gen": gen.number,
                "key": key,
                "reason": "start" if gen.reason == "connect" else gen.reason,
                "program": description,
                "changed_files": list(gen.changed.get(key, ())),
            }
            descriptions.append(FeedMessage(S.PROGRAM, time_ns, dumps(body)))
        self._latched[S.PROGRAM] = descriptions
        static_message = FeedMessage(S.WORLD_STATIC, time_ns, dumps({"seq": entry.seq, "scene": static}))
        self._latched[S.WORLD_STATIC] = [static_message]
        if fresh:
            out.extend(descriptions)
            out.append(static_message)
            if not first and self.generation_events:  # after the descriptions they refer to
                self._generation_events(entry, out)
        self._descriptions = {key: orjson.dumps(d) for key, d in programs.items()}
        dynamic = orjson.loads(entry.scene)
        self._scene = None
        self._latched.pop(S.FOXGLOVE_FIELD, None)
        if foxglove.supports(static, dynamic):
            self.topics[S.FOXGLOVE_FIELD] = self.topics[S.FOXGLOVE_SCENE] = "foxglove.SceneUpdate"
            field = FeedMessage(S.FOXGLOVE_FIELD, time_ns, dumps(foxglove.static_update(static, time_ns)))
            self._latched[S.FOXGLOVE_FIELD] = [field]
            if fresh:
                out.append(field)
            self._scene = foxglove.SceneBuilder(static)
            self._scene_due = True
        self._agents = []
        tables_of: dict[str, tuple[dict[int, dict[str, Any]], dict[int, dict[str, Any]], dict[str, dict[int, str]]]]
        tables_of = {}
        for robot in gen.structure.get("robots", []):
            index = int(robot["id"])
            key = robot.get("program")
            has_engine = index < len(gen.engines) and gen.engines[index]
            if key is None or key not in programs or not has_engine:
                self._agents.append(None)
                continue
            if key not in tables_of:
                description = programs[key]
                tables_of[key] = (
                    {int(s["id"]): s for s in description["inputs"]},
                    {int(s["id"]): s for s in description["outputs"]},
                    {e["name"]: dict(enumerate(e["elements"])) for e in description["enums"]},
                )
            inputs, outputs, enums = tables_of[key]
            name = str(robot["name"])
            self._agents.append(
                _Agent(
                    name,
                    _nesting(inputs, gen.input_ids[index], enums),
                    _nesting(outputs, gen.output_ids[index], enums),
                )
            )
            self.topics[S.agent_topic(name)] = "xabsl.AgentTick"
            self.topics[S.fault_topic(name)] = "xabsl.Fault"
        if fresh:
            self._faults = {}
