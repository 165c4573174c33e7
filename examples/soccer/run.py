"""``xabsl run examples/soccer``: a headless match between two XABSL team behaviors.

What to watch for (see also ``examples/soccer/README.md``): the example team (``behavior/``,
31 options) against the chase team (``chase/``, 2 options, every player runs to the ball). The
example team should win clearly: its goalie stays home, defenders block the way to the goal, one
striker at a time plays the ball (roles change by team messages as the ball moves), and it
shoots only when the lane to the goal is free.

The pieces, reusable by tests and benchmarks:

* :func:`load_team` compiles a behavior folder (``agents.xabsl``);
* :func:`build_world` makes a seeded world with an :class:`~xabsl_studio.examples.soccer.bindings.XabslController`
  on every robot (home = blue = team 0, away = red = team 1);
* :class:`MatchStats` watches a running match: possession, shots, passes, goals;
* :func:`play_match` runs a whole match and returns a :class:`MatchReport`.

The command line part (:func:`add_arguments`, :func:`main`) is what ``engine/cli/run.py`` plugs
under ``xabsl run``.
"""

from __future__ import annotations

import argparse
import hashlib
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import orjson

from xabsl_studio.engine.cli import UsageError, recording
from xabsl_studio.engine.emit.dot import option_graph
from xabsl_studio.engine.errors import HostError
from xabsl_studio.engine.files import write_atomically
from xabsl_studio.engine.host import DEFAULT_BEHAVIOR_HZ, DEFAULT_PHYSICS_HZ, run_headless
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.examples.soccer.bindings import XabslController
from xabsl_studio.examples.soccer.game import GameState
from xabsl_studio.examples.soccer.world import SoccerWorld
from xabsl_studio.examples.soccer.world import build_world as build_soccer_world

HERE = Path(__file__).resolve().parent
#: The example team.
DEFAULT_HOME = HERE / "behavior"
#: The simple opponent.
DEFAULT_AWAY = HERE / "chase"
AGENTS_FILE = "agents.xabsl"

#: A robot "has" the ball when its centre is this close to the ball's centre [m] (body 0.13 m + ball 0.05 m + reach).
POSSESSION_DISTANCE = 0.35
#: A kick is a shot when the ball's path crosses the goal line this close to the goal centre [m].
SHOT_HALF_WIDTH = 0.9
#: A kick is a pass when it heads within this angle of a teammate [deg] ...
PASS_ANGLE = 20.0
#: ... that is between these distances from the ball [m].
PASS_DISTANCE = (0.6, 5.0)

TEAM_KEYS = ("home", "away")


class TeamError(HostError):
    """A team behavior does not compile; ``diagnostics`` holds the printed diagnostics."""

    def __init__(self, folder: Path, diagnostics: list[str]) -> None:
        super().__init__(f"{folder / AGENTS_FILE}: {len(diagnostics)} errors")
        self.diagnostics = diagnostics


def load_team(folder: str | Path) -> Program:
    """Compile the team behavior in ``folder`` (its ``agents.xabsl`` and what that includes).

    Raises:
        UsageError: the folder or its agents file does not exist.
        TeamError: the behavior has errors.
    """
    folder = Path(folder)
    agents = folder / AGENTS_FILE
    if not folder.is_dir():
        raise UsageError(f"no such behavior folder: {folder}")
    if not agents.is_file():
        raise UsageError(f"{folder} has no {AGENTS_FILE}")
    compilation = compile_file(str(agents))
    errors = [d for d in compilation.diagnostics if d.is_error]
    if errors or compilation.program is None:
        raise TeamError(folder, [str(d) for d in errors])
    return compilation.program


def build_world(
    seed: int,
    home: Program | None = None,
    away: Program | None = None,
    *,
    players: int = 5,
    half_duration_s: float = 600.0,
    record: bool = False,
    **options: Any,
) -> SoccerWorld:
    """A seeded match with XABSL controllers plugged in (home plays blue, away red).

    Args:
        seed: the only source of randomness.
        home: the home team's program (default: the example team).
        away: the away team's program (default: the chase team).
        players: robots per team.
        half_duration_s: playing time per half.
        record: count option activations and hash activation traces (see ``XabslController``).
        **options: further ``SoccerWorld`` arguments (``sensor``, ``rules``, ...).
    """
    home = home if home is not None else load_team(DEFAULT_HOME)
    away = away if away is not None else load_team(DEFAULT_AWAY)
    world = build_soccer_world(seed, players_per_team=players, half_duration_s=half_duration_s, **options)
    for agent in world.agents:
        program = home if agent.team_index == 0 else away
        agent.controller = XabslController(agent.perception, agent.motion, program, record=record, name=agent.name)
    return world


@dataclass
class TeamStats:
    """What one team did in a match."""

    goals: int = 0
    shots: int = 0
    passes: int = 0
    kicks: int = 0
    possession_ticks: int = 0


class MatchStats:
    """Watches a match tick by tick (``on_tick`` of ``run_headless``): possession and kicks.

    A kick is seen as a change of a robot's ``last_kick_ms``; it counts as a *shot* if the ball
    then heads for the opponent goal mouth, as a *pass* if it heads for a teammate, else only as a
    kick (a clearance). Possession goes, each PLAYING tick, to the team of the robot closest to the
    ball if that robot is within ``POSSESSION_DISTANCE``.
    """

    def __init__(self, world: SoccerWorld) -> None:
        self.world = world
        self.teams = (TeamStats(), TeamStats())
        self._last_kick: list[int | None] = [a.robot.last_kick_ms for a in world.agents]
        self._agents = [(a.index, a.team_index, a.robot) for a in world.agents]

    def on_tick(self, now_ms: int) -> None:
        """Collect the tick's statistics (possession, shots, passes)."""
        world = self.world
        if world.game.state != GameState.PLAYING:
            return
        # The poses the world reads for the next tick's perception anyway (read once per step).
        snap = world.pose_snapshot()
        bx, by, xs, ys = snap.ball_x, snap.ball_y, snap.x, snap.y
        best, best_team = POSSESSION_DISTANCE, -1
        last_kick = self._last_kick
        hypot = math.hypot
        for i, (index, team, robot) in enumerate(self._agents):
            d = hypot(xs[index] - bx, ys[index] - by)
            if d < best:
                best, best_team = d, team
            kicked = robot.last_kick_ms
            if kicked != last_kick[i]:
                last_kick[i] = kicked
                self._count_kick(team, index, bx, by)
        if best_team >= 0:
            self.teams[best_team].possession_ticks += 1

    def _count_kick(self, team: int, robot_index: int, bx: float, by: float) -> None:
        stats = self.teams[team]
        stats.kicks += 1
        world = self.world
        side = world.game.side[team]
        vx, vy = world.physics.ball_velocity()
        # In the kicker's team frame the opponent goal is at +x.
        tvx, tvy, tbx, tby = vx * side, vy * side, bx * side, by * side
        goal_x = world.dims.half_length
        if tvx > 0.0:
            y_at_goal = tby + tvy * (goal_x - tbx) / tvx
            if abs(y_at_goal) < SHOT_HALF_WIDTH:
                stats.shots += 1
                return
        heading = math.atan2(vy, vx)
        for agent in world.agents:
            if agent.team_index != team or agent.index == robot_index:
                continue
            x, y = world.physics.robots[agent.index].position
            d = math.hypot(x - bx, y - by)
            off = abs(math.remainder(math.atan2(y - by, x - bx) - heading, math.tau))
            if PASS_DISTANCE[0] < d < PASS_DISTANCE[1] and math.degrees(off) < PASS_ANGLE:
                stats.passes += 1
                return

    def finish(self) -> None:
        """Close the statistics at the end of the match."""
        score = self.world.game.score
        for team, stats in enumerate(self.teams):
            stats.goals = score[team]


@dataclass
class MatchReport:
    """The result of :func:`play_match`, JSON-ready through :meth:`as_dict`."""

    seed: int
    score: tuple[int, int]
    teams: tuple[TeamStats, TeamStats]
    activations: tuple[dict[str, int], dict[str, int]]
    trace_hash: str
    sim_seconds: float
    wall_seconds: float
    phases: dict[str, float] = field(default_factory=dict)
    faults: list[str] = field(default_factory=list)
    #: per team, ``(option, state index) -> (ticks active, entries)`` summed over its robots
    #: (``ActivationRecorder.state_counts``); not part of :meth:`as_dict`
    states: tuple[dict[tuple[str, int], tuple[int, int]], ...] = ()

    def as_dict(self) -> dict[str, Any]:
        """The statistics as JSON data (``xabsl run --json``)."""
        possession = [t.possession_ticks for t in self.teams]
        total = sum(possession) or 1
        return {
            "score": {"home": self.score[0], "away": self.score[1]},
            "seed": self.seed,
            "teams": {
                key: {
                    "goals": t.goals,
                    "shots": t.shots,
                    "passes": t.passes,
                    "kicks": t.kicks,
                    "possession": round(t.possession_ticks / total, 3),
                }
                for key, t in zip(TEAM_KEYS, self.teams, strict=True)
            },
            "activations": dict(zip(TEAM_KEYS, self.activations, strict=True)),
            "trace_hash": self.trace_hash,
            "sim_seconds": round(self.sim_seconds, 3),
            "wall_seconds": round(self.wall_seconds, 3),
            "real_time_factor": round(self.sim_seconds / self.wall_seconds, 1) if self.wall_seconds else None,
            "phases": {k: round(v, 3) for k, v in self.phases.items()},
            "faults": self.faults,
        }


def play_match(
    seed: int,
    home: Program | None = None,
    away: Program | None = None,
    *,
    players: int = 5,
    half_duration_s: float = 600.0,
    progress: Any = None,
    record: str | None = None,
    record_keys: tuple[str, str] = ("behavior", "chase"),
    record_sources: tuple[dict[str, Any] | None, dict[str, Any] | None] = (None, None),
    **options: Any,
) -> MatchReport:
    """Play a whole match headless and report score, statistics and option activations.

    Args:
        seed: the only source of randomness.
        home: the home team's program (default: the example team).
        away: the away team's program (default: the chase team).
        players: robots per team.
        half_duration_s: playing time per half (a match has two).
        progress: called as ``progress(time_ms, status)`` every simulated second, if given.
        record: write the match to this MCAP file (``xabsl_studio.engine.record``).
        record_keys: the names of the home and away programs in the recording.
        record_sources: the home and away programs' source files (``xabsl_studio.engine.record.sources``), kept
            in the recording so that a fork can re-simulate it (``xabsl run ... --fork``).
        **options: further ``SoccerWorld`` arguments.
    """
    world = build_world(seed, home, away, players=players, half_duration_s=half_duration_s, record=True, **options)
    stats = MatchStats(world)
    on_tick = stats.on_tick
    if progress is not None:
        ticks = 0

        def on_tick(now_ms: int) -> None:
            nonlocal ticks
            stats.on_tick(now_ms)
            ticks += 1
            if ticks % DEFAULT_BEHAVIOR_HZ == 0:
                progress(world.time_ms, world.game)

    recorder = None
    if record is not None:
        from xabsl_studio.engine.record import Recorder

        recorder = Recorder.for_world(
            record,
            world,
            lambda agent: record_keys[agent.team_index],  # type: ignore[attr-defined]
            example="soccer",
            behavior_hz=DEFAULT_BEHAVIOR_HZ,
            physics_hz=DEFAULT_PHYSICS_HZ,
            sources={k: v for k, v in zip(record_keys, record_sources, strict=True) if v is not None},
            # How the world was built, for forks (options that are not plain JSON values are left
            # out: a fork rebuilds without them, and its check against the recording says so).
            world_options={
                "robots": players,
                "half_duration_s": half_duration_s,
                **{k: v for k, v in options.items() if isinstance(v, bool | int | float | str)},
            },
        )
        watch = on_tick

        def on_tick(now_ms: int) -> None:
            watch(now_ms)
            recorder.tick(now_ms)

    # Generous bound: the referee ends the match; pre-game and kick-off phases add a few seconds each.
    try:
        run = run_headless(world, duration_s=2 * half_duration_s + 600.0, on_tick=on_tick)
    finally:
        # a match that fails (a timeout, an error) keeps the ticks it played: the odd match is
        # the one worth opening
        if recorder is not None:
            recorder.close()
    stats.finish()
    digest = hashlib.blake2b(digest_size=16)
    activations: tuple[dict[str, int], dict[str, int]] = ({}, {})
    states: tuple[dict[tuple[str, int], tuple[int, int]], ...] = ({}, {})
    faults = []
    for agent in world.agents:
        controller = agent.controller
        assert isinstance(controller, XabslController) and controller.recorder is not None
        digest.update(controller.recorder.hash.digest())
        counts = activations[agent.team_index]
        for name, ticks in controller.recorder.counts().items():
            counts[name] = counts.get(name, 0) + ticks
        team_states = states[agent.team_index]
        for key, (ticks, entries) in controller.recorder.state_counts().items():
            had = team_states.get(key, (0, 0))
            team_states[key] = (had[0] + ticks, had[1] + entries)
        if controller.fault is not None:
            faults.append(f"{agent.name}: {controller.fault}")
    return MatchReport(
        seed=seed,
        score=(world.game.score[0], world.game.score[1]),
        teams=stats.teams,
        activations=(dict(sorted(activations[0].items())), dict(sorted(activations[1].items()))),
        trace_hash=digest.hexdigest(),
        sim_seconds=run.sim_seconds,
        wall_seconds=run.wall_seconds,
        phases=run.phases.shares(),
        faults=faults,
        states=states,
    )


# -- command line -----------------------------------------------------------------------------------


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """The soccer example's own flags (``xabsl run examples/soccer --help``)."""
    parser.add_argument(
        "--home",
        metavar="DIR",
        default=str(DEFAULT_HOME),
        help="home team behavior folder with agents.xabsl (default: the example team)",
    )
    parser.add_argument(
        "--away", metavar="DIR", default=str(DEFAULT_AWAY), help="away team behavior folder (default: the chase team)"
    )
    parser.add_argument(
        "--duration",
        metavar="S",
        type=float,
        default=None,
        help="playing time of the match in simulated seconds, two halves (default 1200); with --fork: "
        "how long to go on (default: to the end of the match)",
    )
    parser.add_argument("--seed", metavar="N", type=int, default=1, help="random seed (default 1)")
    parser.add_argument("--players", metavar="N", type=int, default=5, help="robots per team, 1..7 (default 5)")
    parser.add_argument(
        "--json", action="store_true", help="print one JSON object: score, per-team statistics, option activations"
    )
    recording.add_arguments(parser, "match")
    parser.add_argument(
        "--fork",
        metavar="REC.mcap",
        help="go on from tick --at of this recording with the behaviors on disk (re-simulated to that tick)",
    )
    parser.add_argument("--at", metavar="SEQ", type=int, help="the tick of --fork to go on from")
    parser.add_argument(
        "--render", metavar="OUT.dot", help="write the home team's option graph as Graphviz DOT and exit"
    )


def main(args: argparse.Namespace) -> int:
    """Play one match as the flags say; print the score (or JSON). Returns the exit status."""
    if not 1 <= args.players <= 7:
        raise UsageError(f"--players must be in 1..7, got {args.players}")
    if args.duration is not None and not 0 < args.duration < math.inf:
        raise UsageError(f"--duration must be positive, got {args.duration}")
    try:
        home = load_team(args.home)
        away = load_team(args.away)
    except TeamError as error:
        print("\n".join(error.diagnostics), file=sys.stderr)
        print(f"xabsl run: {error}", file=sys.stderr)
        return 1
    if args.render:
        root = home.agents[0].root if home.agents else None
        try:
            write_atomically(args.render, option_graph(home, root).encode("utf-8"))
        except OSError as error:
            raise UsageError(f"cannot write {args.render}: {error.strerror}") from error
        print(f"wrote the option graph of {args.home} to {args.render}")
        return 0

    if args.fork is not None or args.at is not None:
        return _fork_main(args, home, away)
    duration = args.duration if args.duration is not None else 1200.0
    half = duration / 2.0
    record: dict[str, Any] = {}
    target = recording.target(args, [Path(args.home) / AGENTS_FILE, Path(args.away) / AGENTS_FILE], "soccer")
    if target.path is not None:
        record = {
            "record": target.path,
            "record_keys": _record_keys(args.home, args.away),
            "record_sources": (_sources(args.home, home), _sources(args.away, away)),
        }
    if sys.stdout.isatty() and not args.json:
        report = _play_with_progress(args.seed, home, away, args.players, half, **record)
    else:
        report = play_match(args.seed, home, away, players=args.players, half_duration_s=half, **record)
    target.finish()
    if args.json:
        result = report.as_dict()
        result["recording"] = str(target.path) if target.path is not None else None
        sys.stdout.buffer.write(orjson.dumps(result) + b"\n")
        return 0
    result = report.as_dict()
    h, a = report.score
    print(
        f"home {h} : {a} away   (seed {args.seed}, {duration:.0f} s of play, {result['real_time_factor']}x real time)"
    )
    for key in TEAM_KEYS:
        t = result["teams"][key]
        print(
            f"  {key:<4} possession {100 * t['possession']:4.1f} %  shots {t['shots']:3d}  "
            f"passes {t['passes']:3d}  kicks {t['kicks']:3d}"
        )
    for fault in report.faults:
        print(f"  fault: {fault}")
    if target.path is not None:
        # recording is not free yet (docs/recordings.md, "Cost"): say how to run without it
        hint = "" if args.record else " (--no-record: not recorded, about 4x faster)"
        print(f"  recorded to {target.path}{hint}")
    return 0


def _sources(folder: str, program: Program) -> dict[str, Any]:
    """The source files of a team behavior, for its recording."""
    from xabsl_studio.engine.record.sources import program_sources

    return program_sources(Path(folder) / AGENTS_FILE, program.files)


@dataclass
class ForkReport:
    """What :func:`fork_match` did."""

    at: int
    t: int
    switched: list[str]
    ticks: int
    score: tuple[int, int]
    resimulate_seconds: float
    record: str | None

    def as_dict(self) -> dict[str, Any]:
        """JSON data (``xabsl run --fork --json``)."""
        return {
            "at": self.at,
            "t": self.t,
            "switched": self.switched,
            "ticks": self.ticks,
            "score": {"home": self.score[0], "away": self.score[1]},
            "resimulate_seconds": round(self.resimulate_seconds, 3),
            "record": self.record,
        }


def fork_match(
    recording_path: str | Path,
    at: int,
    home: tuple[Program, dict[str, Any] | None],
    away: tuple[Program, dict[str, Any] | None],
    keys: tuple[str, str] = ("behavior", "chase"),
    duration_s: float | None = None,
    record: str | Path | None = None,
) -> ForkReport:
    """Go on from tick ``at`` of a recorded match with the programs ``home`` and ``away``.

    The match is re-simulated from the recorded seed to ``at`` with the recorded behaviors
    (compiled again from the sources the recording keeps), checked against the recording at
    ``at - 1``, the edited behaviors are switched in, and the match goes on headless for
    ``duration_s`` simulated seconds (default: to its end). ``record`` writes the continuation:
    its header names the original and the tick, its seqs and times continue the original's.

    Args:
        recording_path: a recording of ``xabsl run examples/soccer --record``.
        at: the fork tick.
        home: the home team's program on disk and its sources (``xabsl_studio.engine.record.sources``).
        away: the away team's, likewise.
        keys: the teams' program keys (as in the recording).
        duration_s: simulated seconds to go on.
        record: the continuation's recording.

    Raises:
        UsageError: not a soccer recording, a tick outside it, a recording that cannot be
            re-simulated (not deterministic, other behaviors before ``at``, no world options).
    """
    import time

    from xabsl_studio.engine.host import BehaviorLoop
    from xabsl_studio.engine.record import Recorder, Recording, RecordingError
    from xabsl_studio.engine.record.fork import fork_programs, resimulate, switch_programs

    try:
        recording = Recording(recording_path)
    except (RecordingError, OSError) as error:
        raise UsageError(f"--fork: {error}") from None
    with recording:
        header = recording.header
        if header.get("example") != "soccer":
            raise UsageError(f"--fork: {recording_path} is a recording of {header.get('example')!r}, not of soccer")
        options = dict(header.get("world_options") or {})
        if "robots" not in options or "half_duration_s" not in options:
            raise UsageError(f"--fork: {recording_path} does not say how its world was built (no world_options)")
        try:
            players = int(options.pop("robots"))
            half = float(options.pop("half_duration_s"))
        except (TypeError, ValueError) as error:
            raise UsageError(f"--fork: {recording_path}: malformed world_options ({error})") from None
        behavior_hz = int(header["behavior_hz"])

        def key_of(agent: Any) -> str:
            return keys[agent.team_index]

        started = time.perf_counter()
        try:
            if not recording.first <= at < recording.end:
                raise RecordingError(f"--at {at} is outside the recording ({recording.first}..{recording.end - 1})")
            recorded, switch = fork_programs(recording, {keys[0]: home, keys[1]: away})
            loop: BehaviorLoop = resimulate(
                recording,
                lambda seed: build_world(
                    seed, recorded[keys[0]], recorded[keys[1]], players=players, half_duration_s=half, **options
                ),
                at,
            )
        except RecordingError as error:
            raise UsageError(f"--fork: {error}") from None
        resimulated = time.perf_counter() - started
        world = loop.world
        assert isinstance(world, SoccerWorld)
        switch_programs(world, switch, key_of)
        t = loop.now_ms
        recorder = None
        if record is not None:
            from xabsl_studio.engine.record import Recorder

            recorder = Recorder.for_world(
                record,
                world,
                key_of,
                example="soccer",
                behavior_hz=behavior_hz,
                physics_hz=int(header["physics_hz"]),
                sources={k: s for k, (_p, s) in zip(keys, (home, away), strict=True) if s is not None},
                world_options=header.get("world_options"),
                first_seq=at,
                forked_from={"file": Path(recording_path).name, "seq": at},
            )
    # Generous bound, as play_match's: the referee ends the match.
    limit = duration_s if duration_s is not None else 2 * half + 600.0
    ticks = max(0, -(-round(limit * behavior_hz * 1000) // 1000))
    ran = 0
    try:
        for _ in range(ticks):
            if duration_s is None and world.finished:
                break
            now = loop.now_ms
            loop.tick()
            ran += 1
            if recorder is not None:
                recorder.tick(now)
    except BaseException:
        if recorder is not None:
            recorder.abort()
        raise
    if recorder is not None:
        recorder.close()
    return ForkReport(
        at,
        t,
        sorted(switch),
        ran,
        (world.game.score[0], world.game.score[1]),
        resimulated,
        None if record is None else str(record),
    )


def _fork_main(args: argparse.Namespace, home: Program, away: Program) -> int:
    if args.fork is None or args.at is None:
        raise UsageError("--fork REC.mcap and --at SEQ go together")
    report = fork_match(
        args.fork,
        args.at,
        (home, _sources(args.home, home)),
        (away, _sources(args.away, away)),
        _record_keys(args.home, args.away),
        args.duration,
        args.record,
    )
    if args.json:
        sys.stdout.buffer.write(orjson.dumps(report.as_dict()) + b"\n")
        return 0
    switched = ", ".join(report.switched) or "none (the behaviors are the recorded ones)"
    h, a = report.score
    print(
        f"forked {args.fork} at tick {report.at} (t = {report.t} ms), re-simulated in {report.resimulate_seconds:.1f} s"
    )
    print(f"  behaviors switched: {switched}")
    print(
        f"  went on {report.ticks} ticks: home {h} : {a} away" + (f"; recorded to {args.record}" if args.record else "")
    )
    return 0


def _record_keys(home: str, away: str) -> tuple[str, str]:
    """The program keys of a recording: the team folders' names (``behavior``, ``chase``) if they differ."""
    keys = (Path(home).resolve().name, Path(away).resolve().name)
    return keys if keys[0] != keys[1] else ("home", "away")


def _play_with_progress(
    seed: int, home: Program, away: Program, players: int, half: float, **record: Any
) -> MatchReport:
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    total_ms = 2 * half * 1000.0
    with Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.fields[score]}"),
        TimeElapsedColumn(),
        transient=True,
    ) as bar:
        task = bar.add_task("match", total=total_ms, score="0 : 0")

        def progress(_time_ms: int, game: Any) -> None:
            played = (game.half - 1) * half * 1000.0 + (half * 1000.0 - game.half_time_left_ms)
            bar.update(
                task,
                completed=played,
                score=f"{game.score[0]} : {game.score[1]}",
                description=f"half {game.half} {game.state.name.lower():<8}",
            )

        return play_match(seed, home, away, players=players, half_duration_s=half, progress=progress, **record)
