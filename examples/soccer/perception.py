"""Perception: each robot's world model, what its behavior reads as input symbols.

A :class:`WorldModel` holds plain attributes in behavior units (mm, degrees, ms; positions in
the robot's *team frame*, own goal at negative x, see ``field``), so XABSL input symbols bind to
them directly. It is refreshed once per behavior tick by :func:`perceive` from a
:class:`Snapshot` of the physics that the world reads once per tick for all robots.

What a robot perceives:

* Its own pose (self-localisation), with optional Gaussian noise.
* The ball, when it is within the field of view (+-``fov`` degrees of the heading) and
  ``max_distance``: distance, angle and position relative to the robot, with optional noise.
  The field position of the last sighting is kept, and the relative ball values always describe
  that estimate seen from the current pose, so a behavior can walk back to a ball it lost.
  ``ball_time_since_seen`` says how old the estimate is.
* Opponents within the same field of view and range (relative positions).
* Teammates' messages, delivered by a :class:`TeamChannel` after a fixed latency. The behavior
  fills ``WorldModel.outgoing`` (role, ball distance, position, ...); the world sends a copy at
  the message rate.
* Game information from the referee: state, kick-off, score, time left, own kick-off position.

Occlusion, false positives and a filtered ball velocity are not modelled.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from xabsl_studio.examples.soccer.units import DEG_PER_RAD, MM_PER_M

#: ``ball_time_since_seen`` before the first sighting: large, like a ball seen long ago.
NEVER_SEEN_MS = 1_000_000_000


@dataclass(frozen=True, slots=True)
class SensorModel:
    """Field of view, range and noise of a robot's perception (behavior units).

    Noise standard deviations are per measurement and per tick; set them to zero (see
    :meth:`exact`) for a perfect world model.
    """

    fov: float = 60.0  # deg either side of the heading
    max_distance: float = 5000.0  # mm
    pose_xy_noise: float = 20.0  # mm
    pose_rot_noise: float = 1.0  # deg
    ball_distance_noise: float = 0.05  # fraction of the distance
    ball_angle_noise: float = 2.0  # deg
    message_latency_ms: int = 200
    message_interval_ms: int = 100

    @classmethod
    def exact(cls, **overrides: Any) -> SensorModel:
        """Return a sensor model without noise (other fields as given)."""
        values: dict[str, Any] = {
            "pose_xy_noise": 0.0,
            "pose_rot_noise": 0.0,
            "ball_distance_noise": 0.0,
            "ball_angle_noise": 0.0,
        }
        values.update(overrides)
        return cls(**values)


@dataclass(slots=True)
class SeenRobot:
    """A robot seen in the image: relative to the seeing robot [mm, deg]."""

    distance: float
    angle: float
    x: float
    y: float


@dataclass(slots=True)
class TeamMessage:
    """A teammate's message as received: who sent it, when, and the behavior's payload."""

    sender: int
    sent_ms: int
    received_ms: int
    payload: dict[str, Any]


@dataclass(slots=True)
class WorldModel:
    """What one robot believes, in behavior units; the source of its input symbols.

    Positions and headings are in the team frame [mm, deg]; relative values are in the robot
    frame (x forward, y left) [mm, deg, counter-clockwise]. Times are engine ms.
    """

    number: int = 0
    time_ms: int = 0
    # self-localisation
    x: float = 0.0
    y: float = 0.0
    rotation: float = 0.0
    # ball
    ball_seen: bool = False
    ball_distance: float = 0.0
    ball_angle: float = 0.0
    ball_rel_x: float = 0.0
    ball_rel_y: float = 0.0
    ball_x: float = 0.0
    ball_y: float = 0.0
    ball_last_seen_ms: int = -NEVER_SEEN_MS
    ball_time_since_seen: int = NEVER_SEEN_MS
    # referee
    game_state: int = 0
    half: int = 1
    own_kickoff: bool = False
    own_score: int = 0
    opponent_score: int = 0
    half_time_left_ms: int = 0
    kickoff_x: float = 0.0
    kickoff_y: float = 0.0
    # motion feedback
    kick_ready: bool = True
    # team communication
    team_messages: dict[int, TeamMessage] = field(default_factory=dict)
    outgoing: dict[str, Any] = field(default_factory=dict)
    # What ``opponents`` needs, kept by ``perceive`` so that the list is only built for
    # behaviors that ask for it (most ticks of most options never look at opponents).
    _view: tuple[Snapshot, range, float, float, float, float, float, float] | None = field(
        default=None, init=False, repr=False
    )
    _opponents: list[SeenRobot] | None = field(default=None, init=False, repr=False)

    @property
    def opponents(self) -> list[SeenRobot]:
        """Opponents in the field of view and range this tick, relative to the robot [mm, deg]."""
        seen = self._opponents
        if seen is None:
            seen = self._opponents = _see_robots(self._view) if self._view is not None else []
        return seen


def _see_robots(view: tuple[Snapshot, range, float, float, float, float, float, float]) -> list[SeenRobot]:
    snap, indices, px, py, cos_t, sin_t, fov, max_d = view
    seen = []
    xs, ys = snap.x, snap.y
    for j in indices:
        ox = xs[j] * MM_PER_M - px
        oy = ys[j] * MM_PER_M - py
        d = math.hypot(ox, oy)
        if d > max_d:
            continue
        rx, ry = cos_t * ox + sin_t * oy, -sin_t * ox + cos_t * oy
        a = math.atan2(ry, rx) * DEG_PER_RAD
        if -fov <= a <= fov:
            seen.append(SeenRobot(d, a, rx, ry))
    return seen


class Snapshot:
    """The physics state that perception needs, read once per tick for all robots [m, rad].

    Reading a pymunk body property crosses into C; reading each body once per tick and letting
    every robot's perception use these floats is what keeps perception cheap.
    """

    __slots__ = ("ball_x", "ball_y", "theta", "x", "y")

    def __init__(self, n_robots: int) -> None:
        self.x = [0.0] * n_robots
        self.y = [0.0] * n_robots
        self.theta = [0.0] * n_robots
        self.ball_x = 0.0
        self.ball_y = 0.0


class GaussianNoise:
    """Standard normal samples drawn once from the world's generator, then read in turn.

    ``random.gauss`` costs about half a microsecond per draw and a numpy scalar draw more; a
    precomputed table read by index costs a list access, which matters at five draws per robot
    per tick. The table repeats after ``size`` draws (about a minute of a 5 vs 5 match), far
    longer than any correlation a behavior could notice.
    """

    __slots__ = ("_index", "_mask", "_values")

    def __init__(self, rng: np.random.Generator, size: int = 1 << 17) -> None:
        assert size & (size - 1) == 0, "size must be a power of two"
        self._values: list[float] = rng.standard_normal(size).tolist()
        self._mask = size - 1
        self._index = 0

    def normal(self, sigma: float) -> float:
        """One sample of N(0, sigma^2)."""
        i = self._index
        self._index = (i + 1) & self._mask
        return self._values[i] * sigma


def perceive(
    wm: WorldModel,
    snap: Snapshot,
    me: int,
    side: int,
    opponents: range,
    sensor: SensorModel,
    noise: GaussianNoise,
    now_ms: int,
) -> None:
    """Refresh one robot's world model from a snapshot.

    Args:
        wm: the world model to update in place.
        snap: the physics state of this tick.
        me: the robot's index in the snapshot.
        side: the direction the robot's team attacks (+1/-1), which defines its team frame.
        opponents: snapshot indices of the other team's robots.
        sensor: field of view, range and noise.
        noise: samples from the world's random generator (the only source of noise).
        now_ms: the tick's time.
    """
    # Runs for every robot every tick: noise samples are read from the table inline (a method
    # call per sample cost as much as the rest of a line) in the same order ``normal`` would,
    # and angles are wrapped inline (``units.normalize_deg``).
    wm.time_ms = now_ms
    fov = sensor.fov
    max_d = sensor.max_distance
    samples, mask, k = noise._values, noise._mask, noise._index

    # True pose in the world frame, in mm/deg.
    px = snap.x[me] * MM_PER_M
    py = snap.y[me] * MM_PER_M
    pth = snap.theta[me]
    cos_t, sin_t = math.cos(pth), math.sin(pth)

    # Self-localisation in team frame (a team attacking -x sees the world turned by 180 deg).
    sx, sy = px * side, py * side
    srot = pth * DEG_PER_RAD + (0.0 if side > 0 else 180.0)
    sigma = sensor.pose_xy_noise
    if sigma > 0.0:
        sx += samples[k] * sigma
        k = (k + 1) & mask
        sy += samples[k] * sigma
        k = (k + 1) & mask
    sigma = sensor.pose_rot_noise
    if sigma > 0.0:
        srot += samples[k] * sigma
        k = (k + 1) & mask
    srot = (srot + 180.0) % 360.0 - 180.0
    wm.x, wm.y, wm.rotation = sx, sy, srot

    # Ball relative to the true pose: what the camera measures.
    dx = snap.ball_x * MM_PER_M - px
    dy = snap.ball_y * MM_PER_M - py
    dist = math.hypot(dx, dy)
    angle = math.atan2(-sin_t * dx + cos_t * dy, cos_t * dx + sin_t * dy) * DEG_PER_RAD
    if dist <= max_d and -fov <= angle <= fov:
        sigma = sensor.ball_distance_noise
        if sigma > 0.0:
            dist = max(0.0, dist * (1.0 + samples[k] * sigma))
            k = (k + 1) & mask
        sigma = sensor.ball_angle_noise
        if sigma > 0.0:
            angle += samples[k] * sigma
            k = (k + 1) & mask
        a = angle / DEG_PER_RAD
        rel_x, rel_y = dist * math.cos(a), dist * math.sin(a)
        # The field estimate combines the measurement with the (noisy) self-localisation.
        sr = srot / DEG_PER_RAD
        cs, ss = math.cos(sr), math.sin(sr)
        wm.ball_x = sx + cs * rel_x - ss * rel_y
        wm.ball_y = sy + ss * rel_x + cs * rel_y
        wm.ball_seen = True
        wm.ball_last_seen_ms = now_ms
        wm.ball_distance, wm.ball_angle = dist, (angle + 180.0) % 360.0 - 180.0
        wm.ball_rel_x, wm.ball_rel_y = rel_x, rel_y
    else:
        wm.ball_seen = False
        if wm.ball_last_seen_ms > -NEVER_SEEN_MS:
            # Keep the last estimate in the field and re-express it from the current pose.
            bx, by = wm.ball_x - sx, wm.ball_y - sy
            sr = srot / DEG_PER_RAD
            cs, ss = math.cos(sr), math.sin(sr)
            rel_x, rel_y = cs * bx + ss * by, -ss * bx + cs * by
            wm.ball_rel_x, wm.ball_rel_y = rel_x, rel_y
            wm.ball_distance = math.hypot(rel_x, rel_y)
            wm.ball_angle = math.atan2(rel_y, rel_x) * DEG_PER_RAD
    wm.ball_time_since_seen = now_ms - wm.ball_last_seen_ms
    noise._index = k

    # Opponents are seen from the true pose, on demand (see ``WorldModel.opponents``). The
    # snapshot is reused in place, so ``_view`` must be consumed within the tick; the next
    # ``perceive`` replaces it.
    wm._view = (snap, opponents, px, py, cos_t, sin_t, fov, max_d)
    wm._opponents = None


class TeamChannel:
    """One team's radio: messages arrive ``latency_ms`` after they were sent.

    Messages are kept in send order in a deque; since the latency is fixed, that is also their
    delivery order, so delivering is popping from the left.
    """

    __slots__ = ("_queue", "latency_ms")

    def __init__(self, latency_ms: int) -> None:
        self.latency_ms = latency_ms
        self._queue: deque[tuple[int, int, int, dict[str, Any]]] = deque()

    def send(self, now_ms: int, sender: int, payload: dict[str, Any]) -> None:
        """Queue a copy of ``payload`` (later changes by the sender do not travel)."""
        self._queue.append((now_ms + self.latency_ms, sender, now_ms, dict(payload)))

    def deliver(self, now_ms: int, receivers: list[WorldModel]) -> int:
        """Hand every message due by ``now_ms`` to every receiver but its sender; return the count."""
        queue = self._queue
        count = 0
        while queue and queue[0][0] <= now_ms:
            _, sender, sent_ms, payload = queue.popleft()
            count += 1
            # One message object for all receivers (they only read it), as the payload already is.
            message = TeamMessage(sender, sent_ms, now_ms, payload)
            for wm in receivers:
                if wm.number != sender:
                    wm.team_messages[sender] = message
        return count

    def __len__(self) -> int:
        return len(self._queue)
