"""Reading a recording: iterate its ticks, seek any tick fast, rebuild activation trees.

:class:`Recording` opens a file written by :class:`~xabsl_studio.engine.record.writer.Recorder` with the
``mcap`` package's seeking reader. On open it reads the header, every program generation, the
static scenes and the events (a few messages); ticks are read on demand:

* ``recording.tick(seq)`` seeks: the symbols of a tick are the last key frame (at most
  ``key_every`` ticks earlier) plus the changes after it, so it reads the messages of that time
  window only, through MCAP's chunk index (timestamps are ``seq`` times the tick period);
* ``recording.ticks(start, stop)`` decodes a range in one pass (replay, tests, statistics).
* ``recording.paths(start, stop, agents)`` yields only the activation paths, scanning the MCAP
  chunks directly (the profiler's pass over a whole recording).

Each :class:`TickView` holds per agent an :class:`AgentTick`: the path, roots, assignment
values, input and output values (XABSL names, enums as element names; ``raw_inputs()`` gives host
values) and the fault; ``AgentTick.tree()`` rebuilds the engine's activation tree
(:class:`~xabsl_studio.engine.runtime.OptionNode` / ``BehaviorNode`` / ``AssignmentNode``, equal to what
``Engine.activation()`` returned live) from the recorded generation of the behavior.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any, BinaryIO

import orjson

from xabsl_studio.engine.errors import ReadError
from xabsl_studio.engine.ir.ic_reader import read_ic
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.record import schema as S
from xabsl_studio.engine.record import validate as V
from xabsl_studio.engine.record.mcapread import AttachmentIndex, McapFile, RecordingError, open_regular
from xabsl_studio.engine.runtime import AssignmentNode, BehaviorNode, OptionNode, Root
from xabsl_studio.engine.types import Kind, Value

__all__ = ["AgentTick", "ProgramBook", "ProgramView", "Recording", "RecordingError", "TickView"]


@dataclass(frozen=True, slots=True)
class ProgramView:
    """One program generation as the reader needs it to rebuild trees (from its program JSON)."""

    key: str
    gen: int
    seq: int
    description: dict[str, Any]
    tables: dict[str, Any]
    changed_files: tuple[str, ...] = ()
    #: the source files of a program at the start (``xabsl_studio.engine.record.sources``), None if not recorded
    sources: dict[str, Any] | None = None
    #: the generation's intermediate code (None in recordings made before it was recorded)
    ic: str | None = None
    #: the file it was read from (for errors)
    file: str = ""

    def program(self) -> Program | None:
        """The generation's program rebuilt from its intermediate code (None without IC).

        What the IC cannot carry stays out: source texts (conditions are rendered canonically),
        doc comments, and declarations nothing uses.
        """
        if self.ic is None:
            return None
        try:
            return read_ic(self.ic)
        except (ReadError, ValueError, IndexError, KeyError, RecursionError) as error:  # a damaged IC: the file's fault
            reason = f"generation {self.gen} of {self.key!r}: its intermediate code does not read ({error})"
            raise RecordingError(f"{self.file}: {reason}", path=self.file, reason=reason) from None

    def option(self, option_id: int) -> dict[str, Any]:
        """The option JSON with IR id ``option_id``."""
        return self._options[option_id]

    def read_enums(self) -> dict[str, dict[int, str]]:
        """Enum name -> host value -> element of the raw enum values in ``AgentTick.reads``."""
        tables = self.tables.get("read_enums") or self.tables.get("enums", {})
        return {name: {int(v): e for v, e in table.items()} for name, table in tables.items()}

    @property
    def _options(self) -> list[dict[str, Any]]:
        return self.description["options"]  # type: ignore[no-any-return]


@dataclass(slots=True)
class AgentTick:
    """One agent in one tick (values as recorded; see the module docstring)."""

    name: str
    program: ProgramView
    gen: int
    tick: int
    path: list[list[Any]]
    roots: tuple[Root, ...]
    assignments: tuple[Value | None, ...]
    inputs: dict[str, Value | None]
    outputs: dict[str, Value | None]
    fault: dict[str, Any] | None = None
    #: what the tick's decisions read (docs/recordings.md ``reads``), None if the file has none
    reads: list[Any] | None = None

    def tree(self) -> list[OptionNode | BehaviorNode | AssignmentNode]:
        """The activation tree of this tick, as ``Engine.activation()`` built it live."""
        return _rebuild(self.program, self.path, self.assignments)

    def option_names(self) -> list[str]:
        """The options that ran this tick, in path order (names)."""
        options = self.program.description["options"]
        return [options[node[2]]["name"] for node in self.path if node[0] == 0]

    def raw_inputs(self) -> dict[str, Value | None]:
        """The input values with enums as host values (as the engine read them)."""
        return _raw(self.inputs, self.program.description["inputs"], self.program.tables["enums"])

    def raw_outputs(self) -> dict[str, Value | None]:
        """The output values with enums as host values."""
        return _raw(self.outputs, self.program.description["outputs"], self.program.tables["enums"])


@dataclass(slots=True)
class TickView:
    """Everything recorded for one tick."""

    seq: int
    t: int
    agents: dict[str, AgentTick]
    scene: dict[str, Any] | None = None
    status: dict[str, Any] | None = None
    events: list[dict[str, Any]] = field(default_factory=list)


def _raw(
    values: dict[str, Value | None], symbols: list[dict[str, Any]], enums: dict[str, dict[str, str]]
) -> dict[str, Value | None]:
    out = dict(values)
    for symbol in symbols:
        enum = symbol.get("enum")
        name = symbol["name"]
        if symbol["type"] == "enum" and enum and name in out:
            by_element = {element: int(v) for v, element in enums.get(enum, {}).items()}
            value: Any = out[name]
            if isinstance(value, str):
                out[name] = by_element.get(value, value)  # type: ignore[arg-type]
    return out


#: How deep symbol names nest (``a.b.c``) in a recording's values at most.
_MAX_NESTING = 32
_SCENE = {"seq": V.SEQ, "t": int, "scene": dict}
_STATUS = {"seq": V.SEQ, "t": int, "status": dict}
_FAULT = {"seq": V.SEQ, "t": int, "fault": ({"message": str}, type(None))}


def _flatten(tree: dict[str, Any], into: dict[str, Value | None], prefix: str = "", depth: int = 0) -> None:
    """The nested symbol values of a message, by dotted name (raises ``validate.Invalid`` on a non-value)."""
    if depth > _MAX_NESTING:
        raise V.Invalid(f"the symbol values under {prefix[:60]!r} nest deeper than {_MAX_NESTING}")
    for key, value in tree.items():
        name = prefix[:-1] if key == "=" else prefix + key
        if isinstance(value, dict):
            _flatten(value, into, name + ".", depth + 1)
        elif value is None or isinstance(value, (int, float, str)):
            recorded: Any = value  # (enum values are recorded as element names)
            into[name] = recorded
        else:
            raise V.Invalid(f"the value of {name[:60]!r} is {type(value).__name__}, not a symbol value")


class _AgentState:
    """What the messages so far say about one agent (values carried between change messages)."""

    __slots__ = ("assignments", "fault", "gen", "inputs", "outputs", "roots")

    def __init__(self) -> None:
        self.inputs: dict[str, Value | None] = {}
        self.outputs: dict[str, Value | None] = {}
        self.roots: tuple[Root, ...] = ()
        self.assignments: tuple[Value | None, ...] = ()
        self.fault: dict[str, Any] | None = None
        self.gen = 0


class ProgramBook:
    """A recording's program generations as its messages bring them, for its reader and its writer.

    The header names each agent's program key and its value tables; a ``/xabsl/program`` message
    adds a generation (with its key's tables at that point); a reload event that carries tables
    replaces the key's tables, and those of the generation it names. Messages must be checked
    before (``validate``): the book only keeps them.
    """

    def __init__(self, header: dict[str, Any], path: str = "") -> None:
        self.path = path
        self.tables: dict[str, Any] = dict(header["tables"])
        self.program_of: dict[str, Any] = {a["name"]: a["program"] for a in header["agents"]}
        #: (key, gen) -> view, in the order the messages came
        self.views: dict[tuple[str, int], ProgramView] = {}

    def add_program(self, data: dict[str, Any]) -> ProgramView:
        """A ``/xabsl/program`` message: its generation."""
        view = ProgramView(
            data["key"],
            data["gen"],
            data["seq"],
            data["program"],
            self.tables[data["key"]],
            tuple(data.get("changed_files", ())),
            data.get("sources"),
            data.get("ic"),
            self.path,
        )
        self.views[(view.key, view.gen)] = view
        return view

    def add_event(self, data: dict[str, Any]) -> None:
        """An ``/xabsl/events`` message: a reload's tables replace its key's."""
        if data["kind"] == "reload" and data.get("data", {}).get("tables"):
            self.tables[data["data"]["key"]] = data["data"]["tables"]
            key = (data["data"]["key"], data["data"]["gen"])
            if key in self.views:
                old = self.views[key]
                self.views[key] = dataclasses.replace(old, tables=self.tables[old.key])

    def program(self, agent: str, gen: int) -> ProgramView | None:
        """The generation ``gen`` of ``agent``'s program (the latest at or before it; None: none)."""
        key = self.program_of.get(agent)
        best: ProgramView | None = None
        for (k, g), view in self.views.items():
            if k == key and g <= gen and (best is None or g > best.gen):
                best = view
        return best


class Recording:
    """An opened recording (see the module docstring). Use as a context manager or ``close()``.

    Raises:
        RecordingError: not an MCAP file, not a recording, or a newer format version.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = os.fspath(path)
        try:
            self._stream: BinaryIO = open_regular(self.path)
        except OSError as error:
            raise RecordingError(
                f"{self.path}: {error.strerror or error}", path=self.path, reason=str(error.strerror or error)
            ) from None
        try:
            self._open()
        except BaseException:
            self._stream.close()
            raise

    def _open(self) -> None:
        self._file = McapFile.open(self.path, self._stream)
        for attachment in self._file.attachments:
            # checked now (a few MB, their CRCs), so that every reader refuses a damaged file alike
            self._file.attachment(attachment)
        self._topics = {ch.id: ch.topic for ch in self._file.channels.values()}
        by_topic: dict[str, list[int]] = {}
        for channel, topic in self._topics.items():
            by_topic.setdefault(topic, []).append(channel)
        self._by_topic = by_topic
        header = None
        for _channel, _time, data in self._messages([S.RECORDING]):
            header = self._json(data, "the header")
            break
        if not isinstance(header, dict) or header.get("format") != S.FORMAT:
            raise self._invalid("not an xabsl recording (no xabsl.Recording header)")
        version = header.get("version", 0)
        if isinstance(version, int) and version > S.VERSION:
            raise self._invalid(f"format version {version} is newer than {S.VERSION}")
        self._check(V.check_header, header)
        self.header: dict[str, Any] = header
        self.behavior_hz = int(header["behavior_hz"])
        self.key_every = int(header["key_every"])
        self.agents: list[str] = [a["name"] for a in header["agents"] if a["program"] is not None]
        self._program_of = {a["name"]: a["program"] for a in header["agents"]}
        self.events: list[dict[str, Any]] = []
        self.static_scenes: list[dict[str, Any]] = []
        book = self._book = ProgramBook(header, self.path)
        #: every program generation, (key, gen) -> view, in file order
        self.programs: dict[tuple[str, int], ProgramView] = book.views
        for channel, _time, raw in self._messages([S.PROGRAM, S.EVENTS, S.WORLD_STATIC]):
            topic = self._topics[channel]
            data = self._json(raw, f"a message on {topic}")
            if topic == S.PROGRAM:
                self._check(V.check_program, data, book.tables)
                book.add_program(data)
            elif topic == S.EVENTS:
                self._check(V.check_event, data)
                self.events.append(data)
                book.add_event(data)
            else:
                self._check(V.check, data, {"seq": V.SEQ, "scene": dict}, "a static scene")
                self.static_scenes.append(data)
        for agent in self.agents:
            key = self._program_of[agent]
            if not any(k == key and g == 0 for k, g in self.programs):
                raise self._invalid(f"no description of program {key!r} (agent {agent!r}) at its start")
        counts = self._file.counts
        scene_channels = by_topic.get(S.WORLD_SCENE, [])
        #: number of ticks recorded (seq runs first .. first + ticks - 1)
        self.ticks_count = sum(counts.get(c, 0) for c in scene_channels)
        #: the seq of the first tick: 0, or where the run this continues was forked
        self.first = int(header.get("first_seq") or 0)
        #: one past the seq of the last tick
        self.end = self.first + self.ticks_count
        #: how the file was recovered after its writer died (``xabsl_studio.engine.record.recover``), else None
        self.cut: dict[str, Any] | None = header.get("cut")

    # -- checking what is read ------------------------------------------------------------------------

    def _invalid(self, reason: str) -> RecordingError:
        return RecordingError(f"{self.path}: {reason}", path=self.path, reason=reason)

    def _json(self, data: bytes, what: str) -> Any:
        try:
            return orjson.loads(data)
        except orjson.JSONDecodeError as error:
            raise self._invalid(f"{what} is not JSON ({error})") from None

    def _tick_message(self, raw: bytes, agent: str) -> dict[str, Any]:
        """An agent's tick message, checked (the common case without building an error text)."""
        try:
            message = orjson.loads(raw)
        except orjson.JSONDecodeError as error:
            raise self._invalid(f"a message of {agent} is not JSON ({error})") from None
        if not V.tick_ok(message):
            self._check(V.check_tick, message)
        return message  # type: ignore[no-any-return]

    def _check(self, checker: Any, *args: Any) -> None:
        try:
            checker(*args)
        except V.Invalid as error:
            raise self._invalid(str(error)) from None

    def _messages(
        self, topics: list[str], start: int | None = None, stop: int | None = None
    ) -> Iterator[tuple[int, int, bytes]]:
        channels = {c for topic in topics for c in self._by_topic.get(topic, ())}
        if not channels:
            return iter(())
        return self._file.messages(channels, start, stop)

    # -- basics -------------------------------------------------------------------------------------

    def __len__(self) -> int:
        return self.ticks_count

    def close(self) -> None:
        """Close the file."""
        self._stream.close()

    def __enter__(self) -> Recording:
        return self

    def __exit__(self, *_: object) -> None:
        self.close()

    def time_ns(self, seq: int) -> int:
        """The MCAP timestamp of tick ``seq``."""
        return S.tick_time_ns(seq, self.behavior_hz)

    def topics(self) -> dict[str, str]:
        """Topic -> schema name of every channel in the file."""
        schemas = self._file.schemas
        return {
            ch.topic: schemas[ch.schema_id].name if ch.schema_id in schemas else ""
            for ch in self._file.channels.values()
        }

    def attachments(self, name: str, media_type: str) -> list[AttachmentIndex]:
        """The file's attachments called ``name`` of ``media_type``, in file order."""
        found = [a for a in self._file.attachments if a.name == name and a.media_type == media_type]
        return sorted(found, key=lambda a: a.offset)

    def attachment(self, index: AttachmentIndex) -> bytes:
        """The data of one attachment (see :meth:`attachments`).

        Raises:
            RecordingError: the attachment is damaged or not where its index says.
        """
        return self._file.attachment(index)

    def tick_messages(self, agent: str) -> int:
        """How many tick messages of ``agent`` the file's statistics count (0: not a recorded agent)."""
        counts = self._file.counts
        return sum(counts.get(c, 0) for c in self._by_topic.get(S.agent_topic(agent), ()))

    def program_key(self, agent: str) -> str | None:
        """The key of the behavior set ``agent`` runs (None: no XABSL program)."""
        key = self._program_of.get(agent)
        return None if key is None else str(key)

    def program(self, agent: str, gen: int) -> ProgramView:
        """The program generation ``gen`` of ``agent``'s program key (the latest one at or before ``gen``)."""
        best = self._book.program(agent, gen)
        if best is None:
            raise self._invalid(f"no program {self._program_of.get(agent)!r} of generation {gen} in it")
        return best

    # -- ticks ----------------------------------------------------------------------------------------

    def tick(self, seq: int) -> TickView:
        """Tick ``seq`` (0-based), read from the last key frame at or before it.

        Raises:
            RecordingError: ``seq`` is outside the recording.
        """
        if not self.first <= seq < self.end:
            raise self._invalid(f"tick {seq} is outside the recording ({self.first}..{self.end - 1})")
        start = max(self.first, seq - seq % self.key_every)  # the first tick is a key frame too
        last = None
        for last in self._decode(start, seq + 1):  # noqa: B007 -- only the last view is wanted
            pass
        if last is None or last.seq != seq:
            raise self._invalid(f"tick {seq} is counted in the file's statistics but not in it")
        return last

    def ticks(self, start: int | None = None, stop: int | None = None) -> Iterator[TickView]:
        """Ticks ``start`` .. ``stop - 1`` (default: all), decoded in one pass."""
        start = self.first if start is None else max(start, self.first)
        stop = self.end if stop is None else min(stop, self.end)
        if start >= stop:
            return
        key = max(self.first, start - start % self.key_every)
        for view in self._decode(key, stop):
            if view.seq >= start:
                yield view

    def series(
        self, agent: str, symbols: list[str], start: int = 0, stop: int | None = None, every: int = 1
    ) -> dict[str, list[tuple[int, Value | str | None]]]:
        """Per symbol its ``(seq, value)`` pairs over ticks ``start`` .. ``stop - 1`` (for plots).

        Reads only ``agent``'s channel; ``every`` > 1 keeps every n-th tick. Values as recorded
        (enums as element names); a symbol absent in a tick (not in this program generation)
        has no pair there.

        Raises:
            RecordingError: ``agent`` is not a recorded XABSL agent.
        """
        if agent not in self.agents:
            raise RecordingError(f"no agent {agent!r} in {self.path} (agents: {', '.join(self.agents)})")
        start = max(start, self.first)
        stop = self.end if stop is None else min(stop, self.end)
        out: dict[str, list[tuple[int, Value | str | None]]] = {name: [] for name in symbols}
        if start >= stop:
            return out
        key = max(self.first, start - start % self.key_every)
        values: dict[str, Any] = {}
        for _channel, _time, raw in self._messages(
            [S.agent_topic(agent)], self.time_ns(key), self.time_ns(stop - 1) + 1
        ):
            data = self._json(raw, f"a message of {agent}")
            self._check(V.check_tick, data)
            if data["key"]:
                values = {}
            self._check(_flatten, data["inputs"], values)
            self._check(_flatten, data["outputs"], values)
            seq = data["seq"]
            if seq < start or (seq - start) % every:
                continue
            for name, pairs in out.items():
                if name in values:
                    pairs.append((seq, values[name]))
        return out

    def paths(
        self, start: int = 0, stop: int | None = None, agents: list[str] | None = None
    ) -> Iterator[tuple[int, int, str, int, list[list[Any]]]]:
        """``(seq, t, agent, gen, path)`` per agent and tick, in recorded order: only the paths.

        The cheap pass for statistics over a whole recording (``xabsl_studio.engine.profile``): reads only the
        agents' tick channels and builds no views, symbol tables or trees. ``path`` is the recorded
        activation path (docs/recordings.md, ``xabsl.AgentTick``); ``gen`` indexes
        :meth:`program`.

        Raises:
            RecordingError: an agent in ``agents`` is not a recorded XABSL agent.
        """
        window = self._agent_window(start, stop, agents)
        if window is None:
            return
        channels, start, stop = window
        first, last = self.time_ns(start), self.time_ns(stop - 1)
        descriptions: dict[tuple[str, int], dict[str, Any]] = {}
        for channel, _time, raw in self._file.messages(channels, first, last + 1):
            message = self._tick_message(raw, channels[channel])
            agent, gen = channels[channel], message["gen"]
            description = descriptions.get((agent, gen))
            if description is None:
                description = descriptions[(agent, gen)] = self.program(agent, gen).description
            self._check(V.check_path, message["path"], description)
            yield message["seq"], message["t"], agent, gen, message["path"]

    def _agent_window(
        self, start: int, stop: int | None, agents: list[str] | None
    ) -> tuple[dict[int, str], int, int] | None:
        """The tick channels of ``agents`` (channel id -> agent) and ``start`` .. ``stop`` clamped; None: empty.

        Raises:
            RecordingError: an agent in ``agents`` is not a recorded XABSL agent.
        """
        names = self.agents if agents is None else agents
        for name in names:
            if name not in self.agents:
                raise RecordingError(f"no agent {name!r} in {self.path} (agents: {', '.join(self.agents)})")
        start = max(start, self.first)
        stop = self.end if stop is None else min(stop, self.end)
        if start >= stop:
            return None
        wanted = {S.agent_topic(name): name for name in names}
        return {cid: wanted[topic] for cid, topic in self._topics.items() if topic in wanted}, start, stop

    def agent_messages(
        self, start: int = 0, stop: int | None = None, agents: list[str] | None = None
    ) -> Iterator[tuple[str, dict[str, Any]]]:
        """``(agent, message)`` per agent and tick in recorded order: the ``xabsl.AgentTick`` messages as JSON.

        The pass for scans of whole recordings that need more than :meth:`paths` (the query
        engine's columns): key frames and changes as recorded (docs/recordings.md), no views;
        every message checked like the ticks :meth:`ticks` decodes.

        Raises:
            RecordingError: an agent in ``agents`` is not a recorded XABSL agent; a damaged message.
        """
        window = self._agent_window(start, stop, agents)
        if window is None:
            return
        channels, start, stop = window
        # from the key frame at or before start, so that the first message yielded is a key frame
        key = max(self.first, start - start % self.key_every)
        first, last = self.time_ns(key), self.time_ns(stop - 1)
        for channel, _time, raw in self._file.messages(channels, first, last + 1):
            agent = channels[channel]
            yield agent, self._tick_message(raw, agent)

    def _decode(self, start: int, stop: int) -> Iterator[TickView]:
        """Views of ticks ``start`` .. ``stop - 1``; ``start`` must be a key frame tick."""
        states = {name: _AgentState() for name in self.agents}
        agent_topics: dict[str, tuple[str, bool]] = {}
        for name in self.agents:
            agent_topics[S.agent_topic(name)] = (name, True)
            agent_topics[S.fault_topic(name)] = (name, False)
        events_by_seq: dict[int, list[dict[str, Any]]] = {}
        for event in self.events:
            events_by_seq.setdefault(event["seq"], []).append(event)
        topics = [*agent_topics, S.WORLD_SCENE, S.WORLD_STATUS]
        current: TickView | None = None
        status: dict[str, Any] | None = None
        for channel, _time, raw in self._messages(topics, self.time_ns(start), self.time_ns(stop - 1) + 1):
            topic = self._topics[channel]
            data = self._json(raw, f"a message on {topic}")
            entry = agent_topics.get(topic)
            if entry is not None and entry[1]:
                self._check(V.check_tick, data)
                self._check(V.check_path, data["path"], self.program(entry[0], data["gen"]).description)
            else:
                shape = _FAULT if entry is not None else _SCENE if topic == S.WORLD_SCENE else _STATUS
                self._check(V.check, data, shape, f"a message on {topic}")
            seq = data["seq"]
            if current is not None and seq != current.seq:
                yield current
                current = None
            if current is None:
                current = TickView(seq, data["t"], {}, None, status, events_by_seq.get(seq, []))
            if topic == S.WORLD_SCENE:
                current.scene = data["scene"]
                continue
            if topic == S.WORLD_STATUS:
                status = current.status = data["status"]
                continue
            name, is_tick = agent_topics[topic]
            state = states[name]
            if not is_tick:
                state.fault = data["fault"]
                agent = current.agents.get(name)
                if agent is not None:
                    agent.fault = state.fault
                continue
            state.gen = data["gen"]
            if "roots" in data:
                state.roots = tuple(Root(kind, root) for kind, root in data["roots"])
            if "assignments" in data:
                state.assignments = tuple(data["assignments"])
            if data["key"]:
                state.inputs, state.outputs = {}, {}
            else:  # a new dict per tick: views already yielded keep their values
                state.inputs, state.outputs = dict(state.inputs), dict(state.outputs)
            self._check(_flatten, data["inputs"], state.inputs)
            self._check(_flatten, data["outputs"], state.outputs)
            for unread in data.get("unread", ()):
                target = state.outputs if unread in state.outputs else state.inputs
                target[unread] = None
            current.agents[name] = AgentTick(
                name,
                self.program(name, state.gen),
                state.gen,
                data["tick"],
                data["path"],
                state.roots,
                state.assignments,
                state.inputs,
                state.outputs,
                state.fault,
                data.get("reads"),
            )
        if current is not None:
            yield current


def _rebuild(program: ProgramView, path: list[list[Any]], assignments: tuple[Value | None, ...]) -> list[Any]:
    """The activation tree of a recorded path (``xabsl_studio.engine.runtime.activation.build_tree``'s result)."""
    description = program.description
    options = description["options"]
    behaviors = description["behaviors"]
    behavior_params = program.tables["behavior_params"]
    sites = {(s[0], s[1], s[2]): (k, s[3], Kind(s[4]), s[5]) for k, s in enumerate(program.tables["assignment_sites"])}
    position = 0

    def node_at(depth: int) -> Any:
        nonlocal position
        node = path[position]
        position += 1
        if node[0] == 1:
            behavior = behaviors[node[2]]
            declared = behavior_params.get(behavior["name"], [[p["name"], p["enum"]] for p in behavior["params"]])
            params = {p[0]: v for p, v in zip(declared, node[4], strict=False)}
            enums = {p[0]: p[1] for p in declared if p[1] is not None}
            return BehaviorNode(behavior["name"], params, node[3], enums)
        option = options[node[2]]
        state = option["states"][node[3]]
        sub: list[Any] = []
        for k, action in enumerate(state["actions"]):
            kind = action["type"]
            if kind == "assign":
                site = sites.get((option["id"], node[3], k))
                if site is not None and site[0] < len(assignments):
                    value = assignments[site[0]]
                    if value is not None:
                        sub.append(AssignmentNode(site[1], value, site[2], site[3]))
                continue
            if position < len(path) and path[position][1] == depth + 1:
                child = path[position]
                wanted = 0 if kind == "option" else 1
                names = options if wanted == 0 else behaviors
                if child[0] == wanted and names[child[2]]["name"] == action["name"]:
                    sub.append(node_at(depth + 1))
        params_declared = option["params"]
        params = {p["name"]: v for p, v in zip(params_declared, node[8], strict=False)}
        enums = {p["name"]: p["enum"] for p in params_declared if p["enum"] is not None}
        return OptionNode(
            option["name"],
            state["name"],
            node[4],
            node[5],
            params,
            node[7],
            option["states"][node[6]]["name"],
            tuple(sub),
            enums,
        )

    tree = []
    while position < len(path):
        if path[position][1] != 0:  # pragma: no cover - a well-formed path starts every root at depth 0
            raise RecordingError(f"malformed path at node {position}: {path[position]}")
        tree.append(node_at(0))
    return tree
