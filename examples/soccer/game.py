"""The referee: game states, halves, score, kick-off, goals and balls out of bounds.

SPL-like rules, simplified where the simplification does not change what a behavior must decide:

* States (values as in the SPL GameController, usable as an XABSL enumeration): INITIAL ->
  READY -> SET -> PLAYING, and FINISHED after the last half. Robots may walk in READY and
  PLAYING only, and kick in PLAYING only.
* Timing: INITIAL, READY and SET last fixed times (:class:`GameRules`). The half clock runs in
  PLAYING only, so every half has exactly ``half_duration_s`` of play.
* Kick-off: the first half is kicked off by team 0, the second by team 1, and after a goal by
  the team that conceded. In READY the robots may walk to their kick-off positions
  (:func:`kickoff_position`, in team frame); entering SET, the referee places every robot that is
  not within ``placement_tolerance`` of its position there (SPL "manual placement") and puts the
  ball on the centre spot. Kick-off rules on the centre circle are not enforced.
* Goal: the ball has wholly crossed the goal line (its centre is more than a ball radius plus
  half a line width beyond the line centre) between the posts. The scoring team is the one
  attacking that goal; the game goes to READY.
* Ball out (PLAYING): over a side line, the ball is put on the nearest point of the *throw-in
  line* ``throw_in_inset`` (0.4 m) inside the side line; over a goal line without a goal, on the
  throw-in line ``goal_line_out_distance`` (1 m) in front of that goal line, on the side where it
  left. Pre-2015 SPL rules also moved the ball 1 m towards the team that touched it last; this
  world does not track touches, so that penalty is not applied. Play continues at once.
* Half time: teams swap halves (each team's frame follows, so behaviors see no difference), all
  robots are placed at their kick-off positions and the game restarts from INITIAL.
* No penalties (pushing, illegal defender, leaving the field) and no penalty shoot-out.

The controller is pure logic: it reads the ball position it is given and asks a
:class:`Referee` (the world) to move things, so it can be tested without physics.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Protocol

from xabsl_studio.examples.soccer.field import FieldDimensions


class GameState(enum.IntEnum):
    """The game states of the SPL GameController, with its numbering."""

    INITIAL = 0
    READY = 1
    SET = 2
    PLAYING = 3
    FINISHED = 4


# The members as module constants: queries and ``step`` run every physics step and for every
# robot every tick, and an IntEnum member lookup (``GameState.PLAYING``) costs ~80 ns in 3.11.
_READY = GameState.READY
_PLAYING = GameState.PLAYING
_FINISHED = GameState.FINISHED


@dataclass(frozen=True, slots=True)
class GameRules:
    """Durations and placement rules (seconds and metres)."""

    half_duration_s: float = 600.0
    halves: int = 2
    initial_s: float = 1.0
    ready_s: float = 5.0
    set_s: float = 2.0
    placement_tolerance: float = 0.3
    throw_in_inset: float = 0.4
    goal_line_out_distance: float = 1.0


class Referee(Protocol):
    """What the game controller asks of the world (implemented by ``SoccerWorld``)."""

    def place_ball(self, x: float, y: float) -> None:
        """Put the ball at rest at a world point [m]."""
        ...

    def place_for_kickoff(self, only_misplaced: bool) -> None:
        """Put robots on their kick-off positions: all, or only those too far from them."""
        ...


# Kick-off positions by player slot (0 = number 1, the goalie), in team frame [m]: own half,
# facing the opponent goal. The kicking team's striker stands behind the ball; the defending
# team keeps out of the centre circle.
_KICKING = [(-4.2, 0.0), (-0.35, 0.0), (-1.5, -1.2), (-2.6, 1.0), (-2.6, -1.0), (-1.2, 1.8), (-3.3, 0.0)]
_DEFENDING = [(-4.2, 0.0), (-1.0, 0.0), (-1.5, -1.2), (-2.6, 1.0), (-2.6, -1.0), (-1.2, 1.8), (-3.3, 0.0)]

MAX_PLAYERS = len(_KICKING)


def kickoff_position(number: int, kicking: bool) -> tuple[float, float, float]:
    """Return the kick-off pose (x, y, heading) in team frame [m, rad] of player ``number`` (1..7)."""
    x, y = (_KICKING if kicking else _DEFENDING)[number - 1]
    return x, y, 0.0


class GameController:
    """The referee's state machine for one match between team 0 and team 1.

    ``side[t]`` is the direction team ``t`` attacks (+1: towards +x), ``score[t]`` its goals.
    Times are kept in integer nanoseconds (the physics step of 1/120 s is not a whole number of
    microseconds), so a match is exactly reproducible and its clock does not drift measurably.
    """

    def __init__(self, dims: FieldDimensions, rules: GameRules, ball_radius: float) -> None:
        self.dims = dims
        self.rules = rules
        self.state = GameState.INITIAL
        self.half = 1
        self.score = [0, 0]
        self.side = [1, -1]
        self.kickoff_team = 0
        self.time_ns = 0
        self.state_ns = 0
        self.play_ns = 0
        self.goals_log: list[tuple[int, int]] = []  # (time_ms, scoring team)
        self.outs = 0
        self._durations_ns = {
            GameState.INITIAL: round(rules.initial_s * 1e9),
            GameState.READY: round(rules.ready_s * 1e9),
            GameState.SET: round(rules.set_s * 1e9),
        }
        self._half_ns = round(rules.half_duration_s * 1e9)
        half_line = dims.line_width / 2.0
        self._goal_x = dims.half_length + half_line + ball_radius
        self._out_y = dims.half_width + half_line + ball_radius
        self._goal_y = dims.goal_width / 2.0

    # ---------------------------------------------------------------------------- queries

    @property
    def may_move(self) -> bool:
        """Whether robots may walk in the current game state."""
        return self.state in (_READY, _PLAYING)

    @property
    def may_kick(self) -> bool:
        """Whether robots may kick in the current game state."""
        return self.state == _PLAYING

    @property
    def finished(self) -> bool:
        """Whether the match is over."""
        return self.state == _FINISHED

    @property
    def time_ms(self) -> int:
        """Time since the start of the match, rounded to the millisecond."""
        return round(self.time_ns / 1e6)

    @property
    def half_time_left_ms(self) -> int:
        """Milliseconds left in the current half."""
        return round(max(0, self._half_ns - self.play_ns) / 1e6)

    # ---------------------------------------------------------------------------- progress

    def step(self, dt: float, ball_x: float, ball_y: float, referee: Referee) -> None:
        """Advance the referee by ``dt`` seconds, given the ball's world position [m]."""
        dt_ns = round(dt * 1e9)
        self.time_ns += dt_ns
        self.state_ns += dt_ns
        state = self.state
        if state == _PLAYING:
            self.play_ns += dt_ns
            if self.play_ns >= self._half_ns:
                self._end_half(referee)
                return
            self._check_ball(ball_x, ball_y, referee)
        elif state != _FINISHED and self.state_ns >= self._durations_ns[state]:
            # Carry the overshoot into the next state, so state changes do not lose time.
            self._enter(GameState(state + 1), referee, self.state_ns - self._durations_ns[state])

    def set_state(self, state: GameState, kickoff_team: int | None = None) -> None:
        """Put the game into ``state`` now (a test's setup, the studio): no placement, the clocks go on.

        ``kickoff_team`` (0 or 1) also says who kicks off next.
        """
        self.state = GameState(state)
        self.state_ns = 0
        if kickoff_team is not None:
            if kickoff_team not in (0, 1):
                raise ValueError(f"kickoff_team must be 0 or 1, got {kickoff_team!r}")
            self.kickoff_team = kickoff_team

    def _enter(self, state: GameState, referee: Referee, carry_ns: int = 0) -> None:
        self.state = state
        self.state_ns = carry_ns
        if state == GameState.PLAYING:
            self.play_ns += carry_ns
        if state == GameState.SET:
            referee.place_for_kickoff(only_misplaced=True)
            referee.place_ball(0.0, 0.0)

    def _end_half(self, referee: Referee) -> None:
        if self.half >= self.rules.halves:
            self.state = GameState.FINISHED
            self.state_ns = 0
            return
        self.half += 1
        self.play_ns = 0
        self.side = [-self.side[0], -self.side[1]]
        self.kickoff_team = (self.half - 1) % 2
        self.state = GameState.INITIAL
        self.state_ns = 0
        referee.place_for_kickoff(only_misplaced=False)
        referee.place_ball(0.0, 0.0)

    def _check_ball(self, x: float, y: float, referee: Referee) -> None:
        ax = abs(x)
        if ax > self._goal_x:
            if abs(y) < self._goal_y:
                goal_side = 1 if x > 0.0 else -1
                scorer = 0 if self.side[0] == goal_side else 1
                self.score[scorer] += 1
                self.goals_log.append((self.time_ms, scorer))
                self.kickoff_team = 1 - scorer
                self.state = GameState.READY
                self.state_ns = 0
                return
            self.outs += 1
            referee.place_ball(*self.throw_in_point(x, y))
        elif abs(y) > self._out_y:
            self.outs += 1
            referee.place_ball(*self.throw_in_point(x, y))

    def throw_in_point(self, x: float, y: float) -> tuple[float, float]:
        """Where a ball that left the field at world point (x, y) is put back [m]."""
        dims, rules = self.dims, self.rules
        line_y = dims.half_width - rules.throw_in_inset
        py = line_y if y >= 0.0 else -line_y
        if abs(x) > self._goal_x:
            limit = dims.half_length - rules.goal_line_out_distance
            return (limit if x > 0.0 else -limit), py
        limit = dims.half_length - rules.throw_in_inset
        return max(-limit, min(limit, x)), py
