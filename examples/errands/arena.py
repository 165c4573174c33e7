"""The errands arena in pymunk: walls, obstacles, beacons, the book and the mug, the robot (doc §1.5).

This module owns the *ground truth* of the errands world and the only pymunk code of the
example: where the robot, the objects and the obstacles are, what the gripper holds, and the
robot's raw sensor readings computed from that truth. What the robot's behavior system makes of
the readings (activations, facts, the plan) lives elsewhere; nothing here knows about Dual
Dynamics, XABSL or GRAPHPLAN.

Geometry (the sketch arena of §1.5, SI units, x to the right, y up, angles CCW from +x):

* an 8 m × 8 m box with a 1.2 m × 1 m block in the middle and two small boxes away from the
  routes between the beacons, so that roaming meets corners without the errand routes being
  blocked;
* beacons a = (1.5, 1.5), b = (6.5, 1.5), c = (4, 6.5): floor markers the robot senses by
  bearing and proximity; they are not obstacles;
* the book at b and the mug at c (planning problem init), small objects the robot drives over
  (sensor shapes: detected, never pushed);
* a differential-drive disc robot (radius 0.2 m, axle 0.3 m, v_max 0.4 m/s) starting 0.3 m
  from a, facing c.

Sensors (§1.5 table, computed from truth without noise, all in [0, 1] or [-1, 1]):
``o_l``/``o_r`` are ``1 - d/R`` along rays at ±0.5 rad with R = 1 m measured from the robot's
rim (so touching a wall reads 1), from ``space.segment_query_first`` against obstacles only;
``φ_x`` bearing/π (positive to the left); ``δ_x`` distance < 0.6 m; ``γ_o`` the graded object
detector ``clip((0.8 - d)/0.5, 0, 1)`` for an object not held within ±0.6 rad; ``ψ_o`` its
bearing/π while visible; ``speed`` the measured body speed.

Actuators: wheel commands ``m_l``, ``m_r`` ∈ [-1, 1] (× v_max), grip ``g_o`` and drop ``d_o``.
The gripper takes o when ``g_o > 0.5`` and o is within 0.3 m and ±0.6 rad; it lets go when
``d_o > 0.5``. A held object rides at the gripper, 0.25 m ahead of the robot's centre.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import pymunk

#: Collision categories: rays and the robot see obstacles; beacons and objects are sensor shapes.
OBSTACLE = 0b001
ROBOT = 0b010
MARKER = 0b100

_RAY_FILTER = pymunk.ShapeFilter(mask=OBSTACLE)
_TWO_PI = 2.0 * math.pi


def wrap(angle: float) -> float:
    """Wrap an angle into [-π, π)."""
    return (angle + math.pi) % _TWO_PI - math.pi


@dataclass(frozen=True, slots=True)
class Box:
    """An axis-aligned rectangular obstacle given by its centre and size (m)."""

    x: float
    y: float
    w: float
    h: float

    def corners(self) -> list[tuple[float, float]]:
        """The rectangle's four corners (mm), counter-clockwise from the lower left."""
        hw, hh = self.w / 2.0, self.h / 2.0
        return [
            (self.x - hw, self.y - hh),
            (self.x + hw, self.y - hh),
            (self.x + hw, self.y + hh),
            (self.x - hw, self.y + hh),
        ]


@dataclass(frozen=True)
class ArenaLayout:
    """Where everything starts; change it to build other arenas (tests, the studio).

    Attributes:
        size: side of the square arena (m).
        obstacles: boxes inside the arena (the walls are implicit).
        beacons: location name -> position; the planning problem's locations.
        objects: item name -> starting position; the planning problem's items.
        robot: starting pose (x, y, heading in rad).
    """

    size: float = 8.0
    obstacles: tuple[Box, ...] = (Box(4.0, 4.0, 1.2, 1.0), Box(1.3, 5.3, 0.6, 0.6), Box(6.7, 5.4, 0.6, 0.6))
    beacons: Mapping[str, tuple[float, float]] = field(
        default_factory=lambda: {"a": (1.5, 1.5), "b": (6.5, 1.5), "c": (4.0, 6.5)}
    )
    objects: Mapping[str, tuple[float, float]] = field(default_factory=lambda: {"book": (6.5, 1.5), "mug": (4.0, 6.5)})
    robot: tuple[float, float, float] = (1.3, 1.3, math.atan2(6.5 - 1.3, 4.0 - 1.3))


@dataclass(frozen=True, slots=True)
class RobotGeometry:
    """The differential-drive robot and its sensors (§1.5)."""

    radius: float = 0.2
    axle: float = 0.3
    v_max: float = 0.4
    mass: float = 5.0
    ray_angle: float = 0.5
    ray_range: float = 1.0
    near: float = 0.6
    detect_angle: float = 0.6
    detect_far: float = 0.8
    detect_span: float = 0.5
    grab_distance: float = 0.3
    gripper_offset: float = 0.25


@dataclass(slots=True)
class Item:
    """One object (book or mug) as it really is: position and whether the gripper holds it."""

    name: str
    x: float
    y: float
    held: bool = False
    present: bool = True
    body: pymunk.Body | None = None


class Arena:
    """The pymunk space and ground truth of the errands world.

    Args:
        layout: where walls, obstacles, beacons, objects and the robot start.
        geometry: robot size, speed and sensor constants.
    """

    def __init__(self, layout: ArenaLayout | None = None, geometry: RobotGeometry | None = None) -> None:
        self.layout = layout or ArenaLayout()
        self.geom = geometry or RobotGeometry()
        self.space = pymunk.Space()
        self.space.gravity = (0.0, 0.0)
        self.walls: list[tuple[tuple[float, float], tuple[float, float]]] = []
        self.boxes: list[Box] = []
        self.blocks: list[Box] = []
        s = self.layout.size
        for a, b in (((0, 0), (s, 0)), ((s, 0), (s, s)), ((s, s), (0, s)), ((0, s), (0, 0))):
            self._add_segment(a, b)
        for box in self.layout.obstacles:
            self._add_box(box)
            self.boxes.append(box)
        self.beacons = {name: (float(x), float(y)) for name, (x, y) in self.layout.beacons.items()}
        for x, y in self.beacons.values():
            self._add_marker(x, y, 0.1, static=True)
        self.items: dict[str, Item] = {}
        for name, (x, y) in self.layout.objects.items():
            item = Item(name, float(x), float(y))
            item.body = self._add_marker(x, y, 0.06, static=False)
            self.items[name] = item
        g = self.geom
        self.robot = pymunk.Body(g.mass, pymunk.moment_for_circle(g.mass, 0.0, g.radius))
        rx, ry, rh = self.layout.robot
        self.robot.position = (rx, ry)
        self.robot.angle = rh
        shape = pymunk.Circle(self.robot, g.radius)
        shape.friction = 0.0  # slide along walls rather than sticking: the reactive layer copes better
        shape.elasticity = 0.0
        shape.filter = pymunk.ShapeFilter(categories=ROBOT, mask=OBSTACLE)
        self.space.add(self.robot, shape)
        self.v = 0.0
        self.omega = 0.0
        self.time = 0.0
        #: Bumped whenever an item is grabbed, released, teleported or removed: lets the truth
        #: of object facts be cached between such events instead of recomputed every tick.
        self.item_version = 0
        self._beacon_list = [(name, "φ_" + name, "δ_" + name, x, y) for name, (x, y) in self.beacons.items()]
        #: ("at-robot x", x position, y position) per beacon, for the truth of At(robot, x).
        self.beacon_facts = [(f"at-robot {name}", x, y) for name, (x, y) in self.beacons.items()]
        self._item_list = [("γ_" + name, "ψ_" + name, it) for name, it in self.items.items()]
        self._drive_pending = True

    # -- construction ---------------------------------------------------------------------------

    def _add_segment(self, a: tuple[float, float], b: tuple[float, float], radius: float = 0.02) -> pymunk.Segment:
        seg = pymunk.Segment(self.space.static_body, a, b, radius)
        seg.friction = 0.0
        seg.filter = pymunk.ShapeFilter(categories=OBSTACLE)
        self.space.add(seg)
        self.walls.append((a, b))
        return seg

    def _add_box(self, box: Box) -> pymunk.Poly:
        poly = pymunk.Poly(self.space.static_body, box.corners())
        poly.friction = 0.0
        poly.filter = pymunk.ShapeFilter(categories=OBSTACLE)
        self.space.add(poly)
        return poly

    def _add_marker(self, x: float, y: float, r: float, static: bool) -> pymunk.Body:
        body = self.space.static_body if static else pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        if static:
            shape = pymunk.Circle(body, r, (x, y))
            self.space.add(shape)
        else:
            body.position = (x, y)
            shape = pymunk.Circle(body, r)
            self.space.add(body, shape)
        shape.sensor = True
        shape.filter = pymunk.ShapeFilter(categories=MARKER, mask=0)
        return body

    # -- perturbations (tests and the studio) ----------------------------------------------------

    def teleport(self, item: str, x: float, y: float) -> None:
        """Put ``item`` at (x, y), out of the gripper if it was held."""
        it = self.items[item]
        it.x, it.y, it.held, it.present = float(x), float(y), False, True
        assert it.body is not None
        it.body.position = (x, y)
        self.item_version += 1

    def remove(self, item: str) -> None:
        """Take ``item`` out of the world (it can no longer be seen or grabbed)."""
        it = self.items[item]
        it.held = False
        it.present = False
        self.item_version += 1

    def block(self, box: Box) -> None:
        """Add an obstacle (for example across the path between two beacons)."""
        self._add_box(box)
        self.blocks.append(box)

    def place_robot(self, x: float, y: float, heading: float) -> None:
        """Move the robot (at rest) to a pose."""
        self.robot.position = (x, y)
        self.robot.angle = heading
        self.robot.velocity = (0.0, 0.0)
        self.robot.angular_velocity = 0.0
        self.space.reindex_shapes_for_body(self.robot)

    # -- truth ---------------------------------------------------------------------------------

    def pose(self) -> tuple[float, float, float]:
        """The robot's (x, y, heading)."""
        p = self.robot.position
        return p.x, p.y, self.robot.angle

    def gripper_point(self) -> tuple[float, float]:
        """Where the gripper closes, in the arena's frame (mm)."""
        x, y, h = self.pose()
        off = self.geom.gripper_offset
        return x + off * math.cos(h), y + off * math.sin(h)

    def distance_to_beacon(self, name: str) -> float:
        """Distance from the robot's centre to beacon ``name`` (mm)."""
        x, y, _ = self.pose()
        bx, by = self.beacons[name]
        return math.hypot(bx - x, by - y)

    # -- sensing -------------------------------------------------------------------------------

    def sense(self, out: dict[str, float]) -> dict[str, float]:
        """Fill ``out`` with this instant's sensor values (the DD model's sensor names)."""
        g = self.geom
        body = self.robot
        x, y = body.position
        h = body.angle
        query = self.space.segment_query_first
        r0, r1 = g.radius, g.radius + g.ray_range
        a = h + g.ray_angle
        ca, sa = math.cos(a), math.sin(a)
        hit = query((x + r0 * ca, y + r0 * sa), (x + r1 * ca, y + r1 * sa), 0.0, _RAY_FILTER)
        out["o_l"] = 0.0 if hit is None else 1.0 - hit.alpha
        a = h - g.ray_angle
        ca, sa = math.cos(a), math.sin(a)
        hit = query((x + r0 * ca, y + r0 * sa), (x + r1 * ca, y + r1 * sa), 0.0, _RAY_FILTER)
        out["o_r"] = 0.0 if hit is None else 1.0 - hit.alpha
        near2 = g.near * g.near
        atan2, pi = math.atan2, math.pi
        for _, phi, delta, bx, by in self._beacon_list:
            dx, dy = bx - x, by - y
            out[phi] = ((atan2(dy, dx) - h + pi) % _TWO_PI - pi) / pi
            out[delta] = 1.0 if dx * dx + dy * dy < near2 else 0.0
        far, cone = g.detect_far, g.detect_angle
        for gamma_key, psi_key, it in self._item_list:
            gamma = psi = 0.0
            if it.present and not it.held:
                dx, dy = it.x - x, it.y - y
                d2 = dx * dx + dy * dy
                if d2 < far * far:
                    bearing = (atan2(dy, dx) - h + pi) % _TWO_PI - pi
                    if -cone <= bearing <= cone:
                        gamma = min(1.0, (far - math.sqrt(d2)) / g.detect_span)
                        psi = bearing / pi
            out[gamma_key] = gamma
            out[psi_key] = psi
        vx, vy = body.velocity
        out["speed"] = min(1.0, math.hypot(vx, vy))
        return out

    # -- acting --------------------------------------------------------------------------------

    def drive(self, m_l: float, m_r: float) -> None:
        """Set the wheel commands (each in [-1, 1], scaled by v_max) until the next call."""
        g = self.geom
        vl, vr = m_l * g.v_max, m_r * g.v_max
        self.v = 0.5 * (vl + vr)
        self.omega = (vr - vl) / g.axle
        self._drive_pending = True

    def grip(self, name: str, grip: float, drop: float) -> str | None:
        """Apply one gripper's commands; return ``"grabbed"``, ``"released"`` or None."""
        it = self.items[name]
        if not it.present:
            return None
        if it.held:
            if drop > 0.5:
                it.held = False
                it.x, it.y = self.gripper_point()
                assert it.body is not None
                it.body.position = (it.x, it.y)
                self.item_version += 1
                return "released"
        elif grip > 0.5:
            g = self.geom
            x, y, h = self.pose()
            dx, dy = it.x - x, it.y - y
            if dx * dx + dy * dy <= g.grab_distance**2 and abs(wrap(math.atan2(dy, dx) - h)) <= g.detect_angle:
                it.held = True
                self.item_version += 1
                return "grabbed"
        return None

    def step(self, dt: float) -> None:
        """Advance physics by ``dt``: the wheels set the body's velocity, contacts correct it."""
        body = self.robot
        if self._drive_pending:
            # The wheels set the velocity once per command; within the tick's substeps contacts
            # may change it (sliding along a wall), which is what wheels on a floor do too.
            h = body.angle
            body.velocity = (self.v * math.cos(h), self.v * math.sin(h))
            body.angular_velocity = self.omega
            self._drive_pending = False
        self.space.step(dt)
        self.time += dt
        held = [it for it in self.items.values() if it.held] if self.item_version else ()
        if held:
            gx, gy = self.gripper_point()
            for it in held:
                it.x, it.y = gx, gy
                assert it.body is not None
                it.body.position = (gx, gy)

    # -- scenes ----------------------------------------------------------------------------------

    def static_scene(self) -> dict[str, object]:
        """Walls, obstacles and beacons in the scene vocabulary of ``xabsl_studio.engine.host.Scene``."""
        return {
            "size": [self.layout.size, self.layout.size],
            "walls": [[list(a), list(b)] for a, b in self.walls],
            "obstacles": [[b.x, b.y, b.w, b.h] for b in (*self.boxes, *self.blocks)],
            "beacons": {k: list(v) for k, v in self.beacons.items()},
            "robot": {
                "radius": self.geom.radius,
                "ray_angle": self.geom.ray_angle,
                "ray_range": self.geom.ray_range,
                "near": self.geom.near,
            },
        }

    def object_scene(self) -> dict[str, list[object]]:
        """The book, the mug and the robot as they are now, in the scene vocabulary."""
        return {n: [round(it.x, 4), round(it.y, 4), it.held, it.present] for n, it in self.items.items()}
