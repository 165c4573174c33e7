"""Forking a recorded run: rebuild its world at any tick, then go on with the same or an edited behavior.

A recording of a deterministic world (header ``deterministic``) is a pure function of its seed
and programs, so the exact state at tick ``k`` is reached by re-simulating from the seed:
:func:`resimulate` builds the world again, runs ticks ``0 .. k - 1`` and checks the result
against the recording (the world's scene and every agent's activation path at tick ``k - 1``),
so a fork never silently starts from a state the recording did not have. :func:`switch_programs`
then hot-reloads edited programs into the engines (``Engine.reload`` keeps the active states and
times of the options and states that still exist), and the caller runs on from tick ``k``. With
the unchanged behavior the fork continues exactly like the recording (``tests/record``).

Re-simulation, with the recorder's reads repeated (see ``_observer``), costs about 1.8 times
what the match cost: about 85x real time for 5 vs 5 soccer, so a fork at the end of a 10-minute
match takes about 7 s (``benchmarks/fork_cost.py``). World snapshots
would bound that only if a restored world continued bit for bit, and a copied pymunk space does
not: ``Space.copy()`` loses chipmunk's contact cache and rebuilds its spatial index, and of
copies of the soccer world taken at random ticks most drift within 600 physics steps, even some
taken while no two shapes touched (measured by the same benchmark). Events of a
live session before the fork tick (forcing, overrides) are not replayed yet: such recordings are
refused.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from xabsl_studio.engine.host import Agent, BehaviorLoop, World
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.record.reader import Recording, RecordingError
from xabsl_studio.engine.record.sampler import AgentSampler
from xabsl_studio.engine.record.sources import compile_sources, same_sources
from xabsl_studio.engine.record.writer import engines_of

__all__ = ["fork_programs", "resimulate", "switch_programs"]


def resimulate(recording: Recording, build_world: Callable[[int], World], at: int, verify: bool = True) -> BehaviorLoop:
    """The recorded world re-simulated from its seed up to (not including) tick ``at``.

    Args:
        recording: the recording to fork.
        build_world: ``build_world(seed)`` -> the world with the recorded programs' controllers
            plugged in, as the recorded run built it.
        at: the fork tick: the returned loop's next tick is recording tick ``at``.
        verify: compare tick ``at - 1`` with the recording (scene and every agent's path).

    Returns:
        The loop driving the world (``loop.world``); ``loop.tick()`` runs tick ``at``.

    Raises:
        RecordingError: the recording is not of a deterministic run, ``at`` is outside it, it has
            session events before ``at``, the world has other agents, or the re-simulated state
            differs from the recording.
    """
    header = recording.header
    if not header.get("deterministic", False):
        raise RecordingError(f"{recording.path}: not a recording of a deterministic run")
    if recording.first:
        raise RecordingError(f"{recording.path} is itself a fork (from tick {recording.first}): fork its original")
    if not 0 <= at < len(recording):
        raise RecordingError(f"fork tick {at} is outside the recording (0..{len(recording) - 1})")
    early = [e["kind"] for e in recording.events if e["seq"] < at and e["kind"] != "note"]
    if early:
        raise RecordingError(f"cannot replay the session events before tick {at} yet: {', '.join(early)}")
    if not isinstance(header.get("seed"), int) or not isinstance(header.get("physics_hz"), int):
        raise RecordingError(f"{recording.path}: no seed or physics rate in its header: it cannot be re-simulated")
    try:
        world = build_world(header["seed"])
    except (TypeError, ValueError, KeyError) as error:  # recorded world options this world does not take
        raise RecordingError(f"{recording.path}: the recorded world does not build again ({error})") from None
    names = [a.name for a in world.agents]
    if names != [a["name"] for a in header["agents"]]:
        raise RecordingError(f"the rebuilt world has other agents: {names}")
    loop = BehaviorLoop(world, int(header["physics_hz"]), int(header["behavior_hz"]))
    observe = _observer(recording, world)
    for seq in range(at):
        loop.tick()
        observe(seq)
    if verify and at > 0:
        _verify(recording, world, at - 1)
    return loop


def _observer(recording: Recording, world: World) -> Callable[[int], None]:
    """Per tick, the reads the recorder made of the world in the recorded run, in its order.

    Reading need not be free of effects in every world: a host's getter may compute on its first
    read in a tick or remember what it answered (the soccer bindings' team queries once kept the
    last team ball found, ``tests/soccer/test_symbols_pure.py``), so a getter read only by the
    recorder's sampler could change what it answers later. A fork reads what the recording run
    read (every agent's sampled symbols, the dynamic scene, the status on key frames) so that it
    is the recorded run, read for read, whatever the world; it costs about as much again as the
    re-simulation itself (``benchmarks/fork_cost.py``).
    """
    recorded = {a["name"] for a in recording.header["agents"] if a["program"] is not None}
    samplers = [
        AgentSampler(engine)
        for agent, engine in zip(world.agents, engines_of(world), strict=True)
        if engine is not None and agent.name in recorded
    ]
    key_every = recording.key_every
    world.static_scene()  # what Recorder.__init__ reads
    world.dynamic_scene()

    def observe(seq: int) -> None:
        for sampler in samplers:
            sampler.sample()
        if seq % key_every == 0:
            world.status()
        world.dynamic_scene()

    return observe


def _verify(recording: Recording, world: World, seq: int) -> None:
    view = recording.tick(seq)
    if view.scene is not None and world.dynamic_scene() != view.scene:
        raise RecordingError(f"the re-simulated world differs from the recording at tick {seq} (scene)")
    for agent, engine in zip(world.agents, engines_of(world), strict=True):
        recorded = view.agents.get(agent.name)
        if engine is None or recorded is None:
            continue
        if engine.path() != recorded.path:
            raise RecordingError(f"the re-simulated {agent.name} differs from the recording at tick {seq} (path)")


def switch_programs(world: World, programs: Mapping[str, Program], program_key: Callable[[Agent], str | None]) -> int:
    """Hot-reload ``programs[key]`` into every agent whose program key is ``key``; returns how many.

    Raises:
        xabsl_studio.engine.runtime.EngineError: a program does not link or load (the agent keeps its old one).
    """
    switched = 0
    for agent, engine in zip(world.agents, engines_of(world), strict=True):
        key = program_key(agent) if engine is not None else None
        if engine is not None and key is not None and key in programs:
            engine.reload(programs[key])
            switched += 1
    return switched


def fork_programs(
    recording: Recording, current: Mapping[str, tuple[Program, Mapping[str, Any] | None]]
) -> tuple[dict[str, Program], dict[str, Program]]:
    """The programs a fork re-simulates with, and those it switches to at the fork tick.

    Args:
        recording: the recording to fork.
        current: per program key the behavior on disk now: its program and its sources
            (``xabsl_studio.engine.record.sources.program_sources``).

    Returns:
        ``(recorded, switch)``: per key the program of the recorded ticks (compiled again from
        the recorded sources; the current program itself when its sources are the recorded ones,
        or when the recording holds none) and the programs that differ from the recorded ones
        (for :func:`switch_programs`).

    Raises:
        RecordingError: the recording's program keys are not ``current``'s, or its recorded
            sources do not compile.
    """
    keys = sorted({a["program"] for a in recording.header["agents"] if a["program"] is not None})
    if keys != sorted(current):
        raise RecordingError(
            f"{recording.path} runs the behaviors {', '.join(keys)}; this run has {', '.join(sorted(current))}"
        )
    recorded: dict[str, Program] = {}
    switch: dict[str, Program] = {}
    for key in keys:
        program, sources = current[key]
        view = recording.programs.get((key, 0))
        kept = view.sources if view is not None else None
        if kept is None or same_sources(kept, sources):
            recorded[key] = program
        else:
            recorded[key] = compile_sources(kept, f"the recorded behavior {key!r} of {recording.path}")
            switch[key] = program
    return recorded, switch
