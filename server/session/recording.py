"""The live studio session recorded to a folder, in the server process, from the samples it receives.

:class:`LiveRecorder` turns the simulation's :class:`~xabsl_studio.server.protocol.host.Sample` messages (which the
server process receives anyway for its frames) into :class:`~xabsl_studio.engine.record.RecordingEncoder`
operations, so recording costs the simulation process nothing. Files roll: a new one every
``roll_ticks`` ticks (10 minutes at 40 Hz by default), named ``EXAMPLE-YYYYmmdd-HHMMSS-NNN.mcap``;
after each roll the oldest files of the folder are deleted while the folder holds more than
``cap_bytes``. Every file opens on its own (header, program descriptions, static scene).

A file the studio could not finish (killed, crashed, a full disk) stays ``NAME.mcap.part``; the next
studio on the folder recovers it to its last complete tick on start
(``xabsl_studio.engine.record.recover``), and a write that fails keeps what was written and
recovers it at once. Nothing recorded is deleted but by the folder's cap.

What a sample carries is what the frames show, so a live recording differs from a headless one
(``xabsl run --record``) in three ways, written into its header (``"source": "studio"``): values
are display values (decimals to 3 digits, enum values as element indices, which the header's
``tables.enums`` names), assignment values are not recorded (the trees have no assignment
nodes), and a tick whose sample the pipe dropped is missing (ticks are numbered as written).
What the decisions read (``reads``) is exact as in a headless recording: the simulation sends
it as the engine recorded it, so a replay explains any tick from the values the decision saw;
its enum values are the host's, named by the tables' ``read_enums``.

Generations become recording generations: a reload writes the new description on
``/xabsl/program`` and a ``reload`` event (with the files the compile read), a reset a ``reset``
event and the new static scene; commands (pause, step, speed, forcing, overrides, ...) become
events through :meth:`LiveRecorder.event`.
"""

from __future__ import annotations

import dataclasses
import logging
import os
import threading
import time
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import orjson

from xabsl_studio.engine.emit.ic import emit_ic
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.record import RecordingEncoder
from xabsl_studio.engine.record import schema as S
from xabsl_studio.engine.record.encoder import NO_CHANGE
from xabsl_studio.engine.record.folder import DEFAULT_CAP_BYTES, new_recording, prune
from xabsl_studio.engine.record.recover import RecoveryFailed, recover, recover_folder
from xabsl_studio.engine.record.sampler import ProgramTables
from xabsl_studio.engine.types import Kind
from xabsl_studio.server.protocol.host import Sample
from xabsl_studio.server.session.frames import Generation

__all__ = ["DEFAULT_ROLL_TICKS", "LiveRecorder", "command_event", "tables_of"]

log = logging.getLogger("xabsl.server")

#: Commands that become events, by op (resets are written with their generation).
_EVENT_OF = {
    "pause": "pause",
    "resume": "resume",
    "step": "step",
    "speed": "speed",
    "select_agent": "select_agent",
    "force_option": "force",
    "force_behavior": "force",
    "release": "release",
    "override_input": "override",
    "release_input": "release_input",
    "reset_agent": "reset_agent",
}


def command_event(command: Any, gen: Generation | None) -> tuple[str, str | None, dict[str, Any]] | None:
    """A command the session carried out as an event ``(kind, agent, data)``; None: not an event.

    ``agent`` is the name of the command's robot in ``gen`` (None without one), ``data`` the
    command's arguments (docs/recordings.md, "Events").
    """
    kind = _EVENT_OF.get(getattr(command, "op", None) or "")
    if kind is None:
        return None
    data = {k: v for k, v in dataclasses.asdict(command).items() if k not in ("type", "id", "op", "robot")}
    if "agent" in data:
        # the event's own ``agent`` is the robot; the XABSL agent it now runs is ``name``
        # (docs/recordings.md), so the two never collide
        data["name"] = data.pop("agent")
    robot = getattr(command, "robot", None)
    agent = None
    if robot is not None and gen is not None and 0 <= robot < len(gen.structure["robots"]):
        agent = str(gen.structure["robots"][robot]["name"])
    return kind, agent, data


#: Ticks per file by default (10 minutes at 40 Hz).
DEFAULT_ROLL_TICKS = 24_000


def _recover_quietly(part: Path) -> None:
    try:
        done = recover(part)
    except RecoveryFailed as error:
        log.warning("the cut recording stays as it is: %s", error)
    else:
        log.warning("recovered the cut recording %s: %d ticks in %s", part.name, done.ticks, done.path.name)


def tables_of(program: Program) -> ProgramTables:
    """The tables of ``program`` for display values: enum "host values" are element indices."""
    inputs = tuple(s for s in program.inputs.values() if not s.params)
    outputs = tuple(program.outputs.values())
    return ProgramTables(
        inputs=tuple(s.name for s in inputs),
        outputs=tuple(s.name for s in outputs),
        input_enums=tuple(s.enum if s.kind is Kind.ENUM else None for s in inputs),
        output_enums=tuple(s.enum if s.kind is Kind.ENUM else None for s in outputs),
        # display values are rounded already: the encoder keeps them as they are
        input_decimals=tuple(False for _ in inputs),
        output_decimals=tuple(False for _ in outputs),
        enums={name: dict(enumerate(enum.elements)) for name, enum in program.enums.items()},
        behavior_params={
            name: tuple((p.name, p.enum if p.kind is Kind.ENUM else None) for p in b.params)
            for name, b in program.behaviors.items()
        },
        assignment_sites=(),
    )


class LiveRecorder:
    """Records a studio session into rolling files of ``folder`` (see the module docstring)."""

    def __init__(
        self,
        folder: str | os.PathLike[str],
        example: str,
        behavior_hz: int,
        physics_hz: int,
        cap_bytes: int = DEFAULT_CAP_BYTES,
        roll_ticks: int = DEFAULT_ROLL_TICKS,
        key_every: int = S.KEY_EVERY,
    ) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        # Recordings an earlier studio left cut (killed, crashed, out of disk) become readable again.
        self.recovered, self.unrecovered = recover_folder(self.folder)
        for done in self.recovered:
            log.warning("recovered the cut recording %s: %d ticks in %s", done.part.name, done.ticks, done.path.name)
        self.example = example
        self.behavior_hz = behavior_hz
        self.physics_hz = physics_hz
        self.cap_bytes = cap_bytes
        self.roll_ticks = roll_ticks
        self.key_every = key_every
        self.files: list[Path] = []
        self.ticks = 0
        self._encoder: RecordingEncoder | None = None
        self._seq = 0
        self._gen: Generation | None = None
        self._programs: dict[str, Program] = {}
        self._descriptions: dict[str, bytes] = {}
        self._program_gen: dict[str, int] = {}
        self._seed = 0
        self._extras: list[bytes] = []
        self._failed = False
        self._t = 0
        #: seconds spent encoding samples (the server process's cost of recording)
        self.seconds = 0.0
        #: per behavior key: its source files (``xabsl_studio.engine.record.sources``), written with
        #: its program so that a fork can run the recorded behavior again (an attached session's
        #: hosts send them); keys without: no sources recorded
        self.sources: dict[str, dict[str, Any]] = {}

    # -- from the session ------------------------------------------------------------------------

    def generation(
        self, gen: Generation, programs: Mapping[str, Program | None], seed: int, changed_files: Mapping[str, list[str]]
    ) -> None:
        """A new generation arrived (start, reload, reset): describe it before its first sample."""
        self._seed = seed
        previous = self._gen
        self._gen = gen
        if self._failed:
            return
        try:
            if self._encoder is None:
                self._programs = {k: p for k, p in programs.items() if p is not None}
                self._open()
                return
            described = gen.structure["programs"]
            for key, description in described.items():
                data = orjson.dumps(description)
                program = programs.get(key)
                if data == self._descriptions.get(key) or program is None:
                    continue
                self._programs[key] = program
                self._descriptions[key] = data
                self._program_gen[key] = self._program_gen.get(key, -1) + 1
                files = list(changed_files.get(key, ()))
                self._write_program(key, description, "reload", files, program)
                self._event(
                    "reload",
                    None,
                    {
                        "key": key,
                        "gen": self._program_gen[key],
                        "changed_files": files,
                        "tables": self._tables_json(key, program),
                    },
                )
            # A fork rebuilds the world like a reset (at an earlier tick of the same seed).
            if gen.reason in ("reset", "fork") or previous is None or gen.scene_bytes != previous.scene_bytes:
                if gen.reason in ("reset", "fork"):
                    self._event("reset", None, {"reason": gen.reason, "gen": gen.number, "seed": seed})
                self._static(gen)
            self._bind(gen)
        except Exception:  # a full disk must not stop the studio
            self._fail()

    def sample(self, sample: Sample) -> None:
        """One tick of the current generation."""
        gen = self._gen
        if gen is None or self._failed:
            return
        started = time.perf_counter()
        try:
            if self._encoder is None:
                self._open()
            encoder = self._encoder
            assert encoder is not None
            loads = orjson.loads
            samples: list[Any] = []
            extras = self._extras
            for i, has_engine in enumerate(gen.engines):
                if not has_engine:
                    samples.append(None)
                    continue
                fault: Any = NO_CHANGE
                extra = sample.extras[i]
                if i >= len(extras) or extra != extras[i]:
                    fault = loads(b"{" + extra[1:] + b"}").get("fault") if extra else None
                    while len(extras) <= i:
                        extras.append(b"")
                    extras[i] = extra
                roots = NO_CHANGE
                # What the decisions read, exact, as the simulation encoded it (written as it came).
                reads = sample.reads[i] if i < len(sample.reads) and sample.reads[i] else None
                path = loads(sample.paths[i])
                samples.append((sample.seq, path, (), sample.inputs[i], sample.outputs[i], roots, fault, (), reads))
            seq = self._seq
            status = loads(sample.status) if seq % self.key_every == 0 else None
            encoder.handle(("tick", seq, sample.t, samples, loads(sample.scene), status))
            self._t = sample.t
            self._seq = seq + 1
            self.ticks += 1
            if self._seq >= self.roll_ticks:
                self._close()
        except Exception:
            self._fail()
        self.seconds += time.perf_counter() - started

    def stats(self) -> dict[str, Any]:
        """For ``/api/status``: where, how much, at what cost per tick."""
        current = self._encoder.path if self._encoder is not None else None
        return {
            "folder": str(self.folder),
            "file": str(current) if current is not None else None,
            "files": [str(p) for p in self.files],
            "ticks": self.ticks,
            "ms_per_tick": round(1000 * self.seconds / self.ticks, 4) if self.ticks else 0.0,
            "failed": self._failed,
        }

    def event(self, kind: str, agent: str | None = None, /, **data: Any) -> None:
        """A session event (``xabsl_studio.engine.record.schema.EVENT_KINDS``) before the next tick."""
        if kind not in S.EVENT_KINDS or self._failed:
            return
        try:
            if self._encoder is None and self._gen is not None:
                self._open()
            self._event(kind, agent, data)
        except Exception:
            self._fail()

    def command(self, command: Any) -> None:
        """A command the simulation carried out, as an event (those that change what runs)."""
        event = command_event(command, self._gen)
        if event is not None:
            kind, agent, data = event
            self.event(kind, agent, **data)

    def close(self) -> None:
        """Finish the current file (and keep the folder under its cap)."""
        if self._encoder is not None:
            self._close()

    # -- files ------------------------------------------------------------------------------------

    def _open(self) -> None:
        gen = self._gen
        assert gen is not None
        # Counted on from this recorder's earlier files: a name is never used twice, even when the
        # folder's cap removed the file that had it (rolls within one second reused -001).
        path = new_recording(self.folder, self.example, len(self.files) + 1)
        # Display values are rounded already (decimals=None: written as they come).
        self._encoder = RecordingEncoder(path, self.behavior_hz, self.key_every, decimals=None)
        self._seq = 0
        self._extras = []
        structure = gen.structure
        static = orjson.loads(gen.scene_bytes)
        self._program_gen = {key: 0 for key in structure["programs"]}
        self._descriptions = {key: orjson.dumps(d) for key, d in structure["programs"].items()}
        self._message(
            S.RECORDING,
            "xabsl.Recording",
            {
                "format": S.FORMAT,
                "version": S.VERSION,
                "example": self.example,
                "world": str(static.get("kind", "")),
                "seed": int(self._seed),
                "behavior_hz": self.behavior_hz,
                "physics_hz": self.physics_hz,
                "key_every": self.key_every,
                "decimals": 3,
                "deterministic": False,
                "agents": [
                    {
                        "id": r["id"],
                        "name": r["name"],
                        "team": r.get("team"),
                        "number": r.get("number"),
                        "program": r["program"],
                    }
                    for r in structure["robots"]
                ],
                "tables": {
                    key: self._tables_json(key, p) for key, p in self._programs.items() if key in structure["programs"]
                },
            },
        )
        for key, description in structure["programs"].items():
            self._write_program(key, description, "start", [], self._programs.get(key))
        self._bind(gen)
        self._static(gen)

    def _tables_json(self, key: str, program: Program) -> dict[str, Any]:
        """The value tables of ``program`` for the header or a reload, with the host's enum values of ``reads``."""
        tables = tables_of(program).to_json()
        gen = self._gen
        if gen is not None and key in gen.enums:
            tables["read_enums"] = {
                name: {str(v): e for v, e in table.items()} for name, table in gen.enums[key].items()
            }
        return tables

    def _close(self) -> None:
        encoder, self._encoder = self._encoder, None
        if encoder is None:
            return
        path, _, _, _ = encoder.close()
        self.files.append(Path(path))
        self._prune()

    def _prune(self) -> None:
        """Delete the oldest recordings while the folder holds more than the cap; never the newest."""
        prune(self.folder, self.cap_bytes)

    def _fail(self) -> None:
        log.exception("recording the session failed; the studio goes on without recording")
        self._failed = True
        if self._encoder is not None:
            # What was written stays (a full disk must not cost the recording so far): recovered
            # now, off the event loop, or at the next start if the disk is still full.
            part = self._encoder.abandon()
            self._encoder = None
            threading.Thread(target=_recover_quietly, args=(part,), name="xabsl-recover", daemon=True).start()

    # -- messages ---------------------------------------------------------------------------------

    def _message(self, topic: str, schema: str, message: dict[str, Any]) -> None:
        assert self._encoder is not None
        self._encoder.handle(("msg", topic, schema, self._seq, message))

    def _event(self, kind: str, agent: str | None, data: dict[str, Any]) -> None:
        self._message(
            S.EVENTS, "xabsl.Event", {"seq": self._seq, "t": self._t, "kind": kind, "agent": agent, "data": data}
        )

    def _write_program(
        self, key: str, description: dict[str, Any], reason: str, files: list[str], program: Program | None
    ) -> None:
        ic: dict[str, Any] = {"ic": emit_ic(program)} if program is not None else {}
        if key in self.sources:
            ic["sources"] = self.sources[key]
        self._message(
            S.PROGRAM,
            "xabsl.Program",
            {
                "seq": self._seq,
                "gen": self._program_gen.get(key, 0),
                "key": key,
                "reason": reason,
                "program": description,
                "changed_files": files,
                **ic,
            },
        )

    def _static(self, gen: Generation) -> None:
        assert self._encoder is not None
        static = orjson.loads(gen.scene_bytes)
        self._encoder.handle(("static", self._seq, static, {}))

    def _bind(self, gen: Generation) -> None:
        assert self._encoder is not None
        for robot in gen.structure["robots"]:
            key = robot["program"]
            program = self._programs.get(key) if key is not None else None
            if program is None:
                continue
            self._encoder.handle(
                ("agent", robot["id"], robot["name"], tables_of(program), self._program_gen.get(key, 0))
            )
        self._encoder.handle(("key",))
