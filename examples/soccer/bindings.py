"""XABSL bindings of the soccer robot: input symbols, output symbols, enumerations, basic behaviors.

This module is the host half of the symbol files in ``behavior/symbols/`` and of
``behavior/basic_behaviors.xabsl``: every name declared there is bound here to one robot's
:class:`~xabsl_studio.examples.soccer.perception.WorldModel` (what it believes), its
:class:`~xabsl_studio.examples.soccer.robot.MotionRequest` (what it commands) and its team message
(``WorldModel.outgoing``). It is the model to copy for your own robot:

1. **Enumerations** (:func:`register_enums`): the host gives each element its value. Here the
   values are the world's own (``GameState`` numbers, :class:`Role`), so symbols need no
   translation.
2. **Input symbols**: most are one attribute of the world model, which perception updates in
   place, registered with ``Bindings.input_attribute`` so that generated code reads the
   attribute directly; the others are getters of :class:`SoccerSymbols`, bound *once* when the
   engine is built, so a tick allocates nothing. Input *functions* (``distance_to(x, y)``) are
   plain Python functions of their parameters, registered with the parameter names in the order
   the function takes them.
3. **Output symbols**: a setter/getter pair writing straight into the outgoing team message
   dict, updated in place (the team channel copies it when it sends).
4. **Basic behaviors** (:mod:`xabsl_studio.examples.soccer.skills`): one instance per robot.
5. **The controller** (:class:`XabslController`): the ``xabsl_studio.engine.host.AgentController`` of one
   robot; it owns an :class:`xabsl_studio.engine.runtime.Engine` and runs one tick per ``execute``.

Per-tick cost matters (ten robots at 40 Hz, 100x real time): world-model symbols are attribute
reads, team queries are computed at most once per tick and cached, and the opponent list is
only built when a behavior asks about opponents.

Units: mm, degrees, ms; field positions and directions in the team frame (own goal at negative
x, direction 0 points at the opponent goal).
"""

from __future__ import annotations

import array
import enum
import hashlib
import math
from functools import partial

import numpy as np

from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.runtime import Bindings, Engine, Fault
from xabsl_studio.engine.types import Kind
from xabsl_studio.examples.soccer.game import GameState
from xabsl_studio.examples.soccer.perception import WorldModel
from xabsl_studio.examples.soccer.robot import MotionMode, MotionRequest
from xabsl_studio.examples.soccer.skills import SKILLS
from xabsl_studio.examples.soccer.units import DEG_PER_RAD, RAD_PER_DEG, normalize_deg

D, B, E = Kind.DECIMAL, Kind.BOOLEAN, Kind.ENUM

#: A teammate's message older than this is ignored: the teammate is fallen, penalised or gone.
MESSAGE_TIMEOUT_MS = 1000
#: A teammate's ball sighting older than this (at reception) is not worth walking to.
TEAM_BALL_TIMEOUT_MS = 3000
#: The goalie's player number (SPL rule); the goalie never competes for field roles.
GOALIE_NUMBER = 1
#: Published time-to-ball before the behavior computed one: worse than any real estimate.
NO_TIME_TO_BALL = 1.0e6


class Role(enum.IntEnum):
    """The ``role`` enumeration of ``team_symbols.xabsl``: what a player does for the team."""

    NONE = 0
    GOALIE = 1
    DEFENDER = 2
    SUPPORTER = 3
    STRIKER = 4


def register_enums(bindings: Bindings) -> None:
    """Register the external enumerations with the host values of the world."""
    bindings.enum(
        "game.state",
        {
            "init": GameState.INITIAL,
            "ready": GameState.READY,
            "set": GameState.SET,
            "playing": GameState.PLAYING,
            "finished": GameState.FINISHED,
        },
    )
    bindings.enum("role", {r.name.lower(): int(r) for r in Role})


# -- stateless input functions (math and geometry in behavior units) --------------------------------


def _clamp(value: float, lo: float, hi: float) -> float:
    return lo if value < lo else hi if value > hi else value


def _cos(angle: float) -> float:
    return math.cos(angle * RAD_PER_DEG)


def _sin(angle: float) -> float:
    return math.sin(angle * RAD_PER_DEG)


def _direction(from_x: float, from_y: float, to_x: float, to_y: float) -> float:
    return math.atan2(to_y - from_y, to_x - from_x) * DEG_PER_RAD


def _distance(from_x: float, from_y: float, to_x: float, to_y: float) -> float:
    return math.hypot(to_x - from_x, to_y - from_y)


def _angle_diff(a: float, b: float) -> float:
    return normalize_deg(a - b)


def _segment_distance(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> float:
    """Distance of point p from segment a-b."""
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 <= 0.0 else max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / length2))
    return math.hypot(px - ax - t * dx, py - ay - t * dy)


class SoccerSymbols:
    """The input symbols of one robot that need more than an attribute read.

    Holds the robot's world model and caches what several symbols share within one tick (the
    opponents in field coordinates, the team queries), keyed by ``WorldModel.time_ms``.
    """

    def __init__(self, perception: WorldModel) -> None:
        self.wm = perception
        self._opponents_at = -1
        self._opponents: list[tuple[float, float]] = []
        self._rank_at = -1
        self._rank_time = 0.0
        self._rank = 0.0
        self._team_at = -1
        self._pass_at = -1
        self.striker_known = False
        self.striker_x = self.striker_y = 0.0
        self.pass_available = False
        self.pass_x = self.pass_y = 0.0
        self.team_ball_known = False
        self.team_ball_x = self.team_ball_y = 0.0

    # -- the robot itself ----------------------------------------------------------------------

    def distance_to(self, x: float, y: float) -> float:
        """``distance_to(x, y)``: distance from the robot to a field point [mm]."""
        wm = self.wm
        return math.hypot(x - wm.x, y - wm.y)

    def angle_to(self, x: float, y: float) -> float:
        """``angle_to(x, y)``: direction of a field point relative to the heading [deg, ccw]."""
        wm = self.wm
        return normalize_deg(math.atan2(y - wm.y, x - wm.x) * DEG_PER_RAD - wm.rotation)

    # -- opponents -------------------------------------------------------------------------------

    def _field_opponents(self) -> list[tuple[float, float]]:
        wm = self.wm
        if self._opponents_at != wm.time_ms:
            # Built at most once per tick and only when a behavior asks: perception keeps the
            # opponents relative to the robot and builds even that list on demand.
            self._opponents_at = wm.time_ms
            r = wm.rotation * RAD_PER_DEG
            c, s = math.cos(r), math.sin(r)
            x0, y0 = wm.x, wm.y
            self._opponents = [(x0 + c * o.x - s * o.y, y0 + s * o.x + c * o.y) for o in wm.opponents]
        return self._opponents

    def opponent_near(self, x: float, y: float, radius: float) -> bool:
        """``opponent_near(x, y, radius)``: an opponent is seen within ``radius`` of a field point."""
        return any(math.hypot(ox - x, oy - y) < radius for ox, oy in self._field_opponents())

    def opponent_in_corridor(self, from_x: float, from_y: float, to_x: float, to_y: float, width: float) -> bool:
        """``opponent_in_corridor(...)``: an opponent is seen within ``width`` of the segment from-to."""
        return any(_segment_distance(ox, oy, from_x, from_y, to_x, to_y) < width for ox, oy in self._field_opponents())

    # -- teammates (team messages) ----------------------------------------------------------------

    def rank(self, time: float) -> float:
        """``team.rank(time)``: how many field-player teammates published a better time-to-ball.

        A teammate is better with a smaller published time, or the same time and a smaller
        number, so that exactly one robot gets rank 0 when all know the same values. Goalies and
        silent teammates (no message for ``MESSAGE_TIMEOUT_MS``) do not count. Behaviors ask
        several times per tick with the same time, so the last answer is cached.
        """
        wm = self.wm
        now = wm.time_ms
        if self._rank_at == now and self._rank_time == time:
            return self._rank
        oldest = now - MESSAGE_TIMEOUT_MS
        me = wm.number
        better = 0
        for message in wm.team_messages.values():
            if message.sent_ms < oldest or message.sender == GOALIE_NUMBER:
                continue
            other = message.payload.get("time_to_ball", NO_TIME_TO_BALL)
            if other < time or (other == time and message.sender < me):
                better += 1
        self._rank_at = now
        self._rank_time = time
        self._rank = float(better)
        return self._rank

    # The team queries are computed at most once per tick, on the first read, in two parts: the
    # striker and the team ball (a pass over the messages), and the pass target, which also
    # looks at opponents and is only read by the striker. Each getter checks the tick itself,
    # so a cached read is one Python call.

    def _team(self) -> None:
        """The striker and the team ball of this tick."""
        wm = self.wm
        now = wm.time_ms
        self._team_at = now
        oldest = now - MESSAGE_TIMEOUT_MS
        striker_time = NO_TIME_TO_BALL * 2
        # Unknown means 0, not the last value found: an answer must not depend on which ticks
        # someone asked in (a recorder reads every tick; a fork must read the same values).
        self.striker_known = self.team_ball_known = False
        self.striker_x = self.striker_y = self.team_ball_x = self.team_ball_y = 0.0
        best_ball_age = TEAM_BALL_TIMEOUT_MS
        striker = int(Role.STRIKER)
        for message in wm.team_messages.values():
            if message.sent_ms < oldest:
                continue
            p = message.payload
            if "x" not in p:
                continue
            if p.get("role") == striker and p.get("time_to_ball", NO_TIME_TO_BALL) < striker_time:
                striker_time = p["time_to_ball"]
                self.striker_known, self.striker_x, self.striker_y = True, p["x"], p["y"]
            age = p["ball_age"] + now - message.sent_ms
            if age < best_ball_age:
                best_ball_age = age
                self.team_ball_known, self.team_ball_x, self.team_ball_y = True, p["ball_x"], p["ball_y"]

    def _pass(self) -> None:
        """The pass target of this tick: the most advanced free field player ahead of the ball."""
        wm = self.wm
        now = wm.time_ms
        self._pass_at = now
        oldest = now - MESSAGE_TIMEOUT_MS
        self.pass_available = False
        self.pass_x = self.pass_y = 0.0
        best_pass_x = -1.0e9
        bx, by = wm.ball_x, wm.ball_y
        for message in wm.team_messages.values():
            if message.sent_ms < oldest:
                continue
            p = message.payload
            if "x" not in p:
                continue
            x, y = p["x"], p["y"]
            if message.sender == GOALIE_NUMBER or x < bx + 300.0 or x <= best_pass_x:
                continue
            d = math.hypot(x - bx, y - by)
            if (
                800.0 < d < 4000.0
                and not self.opponent_in_corridor(bx, by, x, y, 350.0)
                and not self.opponent_near(x, y, 500.0)
            ):
                best_pass_x = x
                self.pass_available, self.pass_x, self.pass_y = True, x, y

    def get_striker_known(self) -> bool:
        """Whether a teammate announced itself striker this tick."""
        if self._team_at != self.wm.time_ms:
            self._team()
        return self.striker_known

    def get_striker_x(self) -> float:
        """The announced striker's x (mm, field frame)."""
        if self._team_at != self.wm.time_ms:
            self._team()
        return self.striker_x

    def get_striker_y(self) -> float:
        """The announced striker's y (mm, field frame)."""
        if self._team_at != self.wm.time_ms:
            self._team()
        return self.striker_y

    def get_team_ball_known(self) -> bool:
        """Whether some teammate saw the ball recently."""
        if self._team_at != self.wm.time_ms:
            self._team()
        return self.team_ball_known

    def get_team_ball_x(self) -> float:
        """The team's freshest ball estimate, x (mm, field frame)."""
        if self._team_at != self.wm.time_ms:
            self._team()
        return self.team_ball_x

    def get_team_ball_y(self) -> float:
        """The team's freshest ball estimate, y (mm, field frame)."""
        if self._team_at != self.wm.time_ms:
            self._team()
        return self.team_ball_y

    def get_pass_available(self) -> bool:
        """Whether a teammate stands free to receive a pass."""
        if self._pass_at != self.wm.time_ms:
            self._pass()
        return self.pass_available

    def get_pass_x(self) -> float:
        """The pass target's x (mm, field frame)."""
        if self._pass_at != self.wm.time_ms:
            self._pass()
        return self.pass_x

    def get_pass_y(self) -> float:
        """The pass target's y (mm, field frame)."""
        if self._pass_at != self.wm.time_ms:
            self._pass()
        return self.pass_y


#: Input symbols that read one world-model attribute: symbol -> (kind, attribute). They are
#: registered with ``Bindings.input_attribute``, so generated code reads ``wm.<attribute>``
#: directly: these symbols are most of a behavior's ~14 input reads per tick.
ATTRIBUTE_INPUTS: dict[str, tuple[Kind, str]] = {
    "robot.number": (D, "number"),
    "robot.x": (D, "x"),
    "robot.y": (D, "y"),
    "robot.rotation": (D, "rotation"),
    "robot.kick_ready": (B, "kick_ready"),
    "ball.seen": (B, "ball_seen"),
    "ball.distance": (D, "ball_distance"),
    "ball.angle": (D, "ball_angle"),
    "ball.x": (D, "ball_x"),
    "ball.y": (D, "ball_y"),
    "ball.rel_y": (D, "ball_rel_y"),
    "ball.time_since_seen": (D, "ball_time_since_seen"),
    "game.own_kickoff": (B, "own_kickoff"),
    "game.kickoff_x": (D, "kickoff_x"),
    "game.kickoff_y": (D, "kickoff_y"),
    "game.half_time_left": (D, "half_time_left_ms"),
    "game.own_score": (D, "own_score"),
    "game.opponent_score": (D, "opponent_score"),
}


def make_bindings(perception: WorldModel, motion: MotionRequest) -> tuple[Bindings, SoccerSymbols]:
    """Bind every symbol and basic behavior of the soccer namespaces to one robot.

    Args:
        perception: the robot's world model (updated in place by the world every tick).
        motion: the robot's motion request (read by its legs after every tick).

    Returns:
        The bindings to build the robot's engine from, and the symbol object they close over.
    """
    b = Bindings()
    register_enums(b)
    s = SoccerSymbols(perception)
    wm = perception

    for name, (kind, attribute) in ATTRIBUTE_INPUTS.items():
        b.input_attribute(name, kind, wm, attribute)
    b.input_attribute("game.state", E, wm, "game_state", enum="game.state")

    # math and geometry
    b.input("abs", D, abs, params=[("value", D)])
    b.input("clamp", D, _clamp, params=[("value", D), ("lo", D), ("hi", D)])
    b.input("cos", D, _cos, params=[("angle", D)])
    b.input("sin", D, _sin, params=[("angle", D)])
    b.input("angle_diff", D, _angle_diff, params=[("a", D), ("b", D)])
    xyxy = [("from_x", D), ("from_y", D), ("to_x", D), ("to_y", D)]
    b.input("direction", D, _direction, params=xyxy)
    b.input("distance", D, _distance, params=xyxy)
    b.input("distance_to", D, s.distance_to, params=[("x", D), ("y", D)])
    b.input("angle_to", D, s.angle_to, params=[("x", D), ("y", D)])

    # opponents
    b.input("opponent_near", B, s.opponent_near, params=[("x", D), ("y", D), ("radius", D)])
    b.input("opponent_in_corridor", B, s.opponent_in_corridor, params=[*xyxy, ("width", D)])

    # teammates
    b.input("team.rank", D, s.rank, params=[("time", D)])
    b.input("team.striker.known", B, s.get_striker_known)
    b.input("team.striker.x", D, s.get_striker_x)
    b.input("team.striker.y", D, s.get_striker_y)
    b.input("team.pass.available", B, s.get_pass_available)
    b.input("team.pass.x", D, s.get_pass_x)
    b.input("team.pass.y", D, s.get_pass_y)
    b.input("team.ball.known", B, s.get_team_ball_known)
    b.input("team.ball.x", D, s.get_team_ball_x)
    b.input("team.ball.y", D, s.get_team_ball_y)

    # Output symbols live in the outgoing team message, so whatever the behavior decides this
    # tick is what teammates receive; the dict is updated in place, never rebuilt.
    out = wm.outgoing
    out.setdefault("role", int(Role.NONE))
    out.setdefault("time_to_ball", NO_TIME_TO_BALL)
    b.output(
        "team.role", E, enum="role", setter=partial(out.__setitem__, "role"), getter=partial(out.__getitem__, "role")
    )
    b.output(
        "team.time_to_ball",
        D,
        setter=partial(out.__setitem__, "time_to_ball"),
        getter=partial(out.__getitem__, "time_to_ball"),
    )

    for skill in SKILLS:
        b.behavior(skill(perception, motion))
    return b, s


class ActivationRecorder:
    """Counts, per option, the ticks it was active and in which state, and hashes the activation trace.

    After each tick it appends the engine's tick stamps and active states (its storage lists, as
    they are: ``array.fromlist`` and ``bytearray.extend`` copy them in C) and the tick; which
    options ran (a stamp equal to the tick, as ``Engine.ran_options()`` says), the counts (numpy)
    and the trace hash are computed from them on request, so a tick costs three appends.
    """

    __slots__ = ("_engine", "_stamps", "_states", "_ticks", "option_names")

    def __init__(self, engine: Engine) -> None:
        self._engine = engine
        self.option_names: list[str] = list(engine.option_names)
        self._stamps = array.array("q")
        self._states = bytearray()
        self._ticks = array.array("q")

    def record(self) -> None:
        """Count this tick's activations for the match report."""
        engine = self._engine
        loaded = engine.loaded
        self._stamps.fromlist(loaded.last_tick)
        self._states.extend(loaded.states)
        self._ticks.append(engine.tick)

    @property
    def _active(self) -> bytes:
        """Per tick and option: 1 if it ran (``Engine.ran_options()`` of every recorded tick)."""
        n = len(self.option_names)
        if not self._ticks or not n:
            return b""
        stamps = np.frombuffer(self._stamps, dtype=np.int64).reshape(-1, n)
        ticks = np.frombuffer(self._ticks, dtype=np.int64)
        ran: bytes = (stamps == ticks[:, None]).astype(np.uint8).tobytes()
        return ran

    @property
    def hash(self) -> hashlib.blake2b:
        """BLAKE2b (16 bytes) of the trace: per tick the active flags, then the active states."""
        digest = hashlib.blake2b(digest_size=16)
        n = len(self.option_names)
        if self._active and n:
            active = np.frombuffer(bytes(self._active), dtype=np.uint8).reshape(-1, n)
            states = np.frombuffer(bytes(self._states), dtype=np.uint8).reshape(-1, n)
            digest.update(np.hstack([active, states]).tobytes())
        return digest

    def counts(self) -> dict[str, int]:
        """Ticks each option was active (options that never ran are left out)."""
        n = len(self.option_names)
        if not self._active:
            return {}
        totals = np.frombuffer(bytes(self._active), dtype=np.uint8).reshape(-1, n).sum(axis=0, dtype=np.int64)
        return {name: int(c) for name, c in zip(self.option_names, totals, strict=True) if c}

    def state_counts(self) -> dict[tuple[str, int], tuple[int, int]]:
        """Per ``(option, state index)`` that ran: ticks active in it and how often it was entered.

        A state is *entered* in a tick where its option ran in it after running in another state
        (or not running) the tick before: the decisions the option took, as counts.
        """
        n = len(self.option_names)
        if not self._active:
            return {}
        ran = np.frombuffer(bytes(self._active), dtype=np.uint8).reshape(-1, n).astype(bool)
        states = np.frombuffer(bytes(self._states), dtype=np.uint8).reshape(-1, n).astype(np.int64)
        previous = np.vstack([np.full((1, n), -1, dtype=np.int64), np.where(ran, states, -1)[:-1]])
        entered = ran & (states != previous)
        width = int(states.max()) + 1
        keys = np.arange(n, dtype=np.int64)[None, :] * width + states
        ticks = np.bincount(keys[ran], minlength=n * width)
        entries = np.bincount(keys[entered], minlength=n * width)
        return {
            (self.option_names[k // width], int(k % width)): (int(ticks[k]), int(entries[k]))
            for k in np.flatnonzero(ticks)
        }


class XabslController:
    """The brain of one soccer robot: an XABSL engine on the robot's bindings.

    Implements ``xabsl_studio.engine.host.AgentController``. Each ``execute`` publishes the robot's pose and
    ball estimate in its team message, then runs one engine tick; the behavior's basic behaviors
    write the motion request and its output symbols the rest of the team message.

    Args:
        perception: the robot's world model.
        motion: the robot's motion request.
        program: the compiled behavior (``xabsl_studio.engine.lang.compile_file(...).program``), shared by
            every robot of a team; each controller generates and binds its own engine code.
        agent: the XABSL agent to run (default: the program's first agent).
        record: count option activations and hash the activation trace (statistics, tests).

    Raises:
        xabsl_studio.engine.runtime.LinkError: the program declares a symbol or behavior this module lacks.
    """

    __slots__ = ("_out", "engine", "motion", "recorder", "symbols", "wm")

    def __init__(
        self,
        perception: WorldModel,
        motion: MotionRequest,
        program: Program,
        *,
        agent: str | None = None,
        record: bool = False,
        name: str = "",
    ) -> None:
        self.wm = perception
        self.motion = motion
        bindings, self.symbols = make_bindings(perception, motion)
        self.engine = Engine(bindings, program, agent_name=name)
        if agent is not None:
            self.engine.root_actions.select_agent(agent)
        self._out = perception.outgoing
        self.recorder = ActivationRecorder(self.engine) if record else None

    @property
    def fault(self) -> Fault | None:
        """Why the behavior stopped (a basic behavior or input function raised), or None."""
        return self.engine.fault

    def execute(self, now_ms: int) -> None:
        """Copy the world model into the engine's inputs, tick the engine, send the team message."""
        wm, out = self.wm, self._out
        out["x"] = wm.x
        out["y"] = wm.y
        out["ball_x"] = wm.ball_x
        out["ball_y"] = wm.ball_y
        out["ball_age"] = wm.ball_time_since_seen
        engine = self.engine
        engine.execute(now_ms)
        if engine.fault is not None:
            # A stopped engine writes nothing: make the robot stand instead of walking on.
            self.motion.mode = MotionMode.STAND
            self.motion.kick_strength = 0.0
        if self.recorder is not None:
            self.recorder.record()
