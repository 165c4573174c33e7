"""Field geometry: SPL-like dimensions, the team frames and the static scene.

Dimensions follow the RoboCup Standard Platform League rule book (2023): a 9 m x 6 m field
measured between line centres, 50 mm lines, a 0.7 m carpet border closed by walls, goals with
1.5 m between the inner sides of 100 mm posts and a 0.5 m deep net, goal areas 0.6 m x 2.2 m,
penalty areas 1.65 m x 4 m, penalty marks 1.3 m from the goal line, a 1.5 m centre circle.

Frames. The *world frame* has its origin at the centre spot, x along the long axis and y to
the left of +x. A *team frame* is the frame a team's behavior sees: its own goal is always at
negative x and the opponent goal at (+length/2, 0), whichever half the team defends (teams swap
halves at half time). A team attacking -x sees the world rotated by 180 degrees.

All geometry here is in metres (physics units); ``static_scene`` converts to millimetres for
the UI through ``units``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from xabsl_studio.examples.soccer.units import to_mm


@dataclass(frozen=True, slots=True)
class FieldDimensions:
    """Sizes of the field and its furniture, in metres (SPL 2023 defaults)."""

    length: float = 9.0
    width: float = 6.0
    line_width: float = 0.05
    border: float = 0.7
    goal_width: float = 1.5  # between the inner sides of the posts
    goal_depth: float = 0.5
    post_radius: float = 0.05
    goal_area_length: float = 0.6
    goal_area_width: float = 2.2
    penalty_area_length: float = 1.65
    penalty_area_width: float = 4.0
    penalty_mark_distance: float = 1.3
    centre_circle_radius: float = 0.75

    @property
    def half_length(self) -> float:
        """Half the field's length (mm)."""
        return self.length / 2.0

    @property
    def half_width(self) -> float:
        """Half the field's width (mm)."""
        return self.width / 2.0

    @property
    def post_y(self) -> float:
        """|y| of a post centre: the goal's inner half width plus one post radius."""
        return self.goal_width / 2.0 + self.post_radius

    @property
    def wall_x(self) -> float:
        """The x of the walls behind the goals (mm)."""
        return self.half_length + self.border

    @property
    def wall_y(self) -> float:
        """The y of the side walls (mm)."""
        return self.half_width + self.border

    def posts(self) -> list[tuple[float, float]]:
        """Centres of the four goal posts (world frame)."""
        hx, py = self.half_length, self.post_y
        return [(-hx, -py), (-hx, py), (hx, -py), (hx, py)]

    def net(self, side: int) -> list[tuple[float, float]]:
        """Return the net of the goal at ``side * half_length`` as a polyline post -> back -> post."""
        x0 = side * self.half_length
        x1 = side * (self.half_length + self.goal_depth)
        py = self.post_y
        return [(x0, -py), (x1, -py), (x1, py), (x0, py)]

    def walls(self) -> list[tuple[float, float, float, float]]:
        """Return the four border walls as segments (x1, y1, x2, y2)."""
        wx, wy = self.wall_x, self.wall_y
        return [(-wx, -wy, wx, -wy), (wx, -wy, wx, wy), (wx, wy, -wx, wy), (-wx, wy, -wx, -wy)]

    def lines(self) -> list[tuple[float, float, float, float]]:
        """Every straight field line as a segment (x1, y1, x2, y2) along its centre."""
        hx, hy = self.half_length, self.half_width
        segments = [(-hx, -hy, hx, -hy), (hx, -hy, hx, hy), (hx, hy, -hx, hy), (-hx, hy, -hx, -hy), (0.0, -hy, 0.0, hy)]
        for side in (-1, 1):
            for depth, half in (
                (self.goal_area_length, self.goal_area_width / 2.0),
                (self.penalty_area_length, self.penalty_area_width / 2.0),
            ):
                x0 = side * hx
                x1 = side * (hx - depth)
                segments += [(x0, -half, x1, -half), (x1, -half, x1, half), (x1, half, x0, half)]
        return segments

    def marks(self) -> list[tuple[float, float]]:
        """Return the centre spot and the two penalty marks."""
        d = self.half_length - self.penalty_mark_distance
        return [(0.0, 0.0), (-d, 0.0), (d, 0.0)]


def to_team_frame(x: float, y: float, side: int) -> tuple[float, float]:
    """Map a world point into the frame of a team attacking towards ``side`` (+1 or -1)."""
    return x * side, y * side


def from_team_frame(x: float, y: float, side: int) -> tuple[float, float]:
    """Map a point of a team's frame into the world frame (the map is its own inverse)."""
    return x * side, y * side


def heading_to_team_frame(theta: float, side: int) -> float:
    """Map a world heading (radians) into the frame of a team attacking towards ``side``."""
    return theta if side > 0 else theta + math.pi


def static_scene(dims: FieldDimensions) -> dict[str, Any]:
    """Return the field for the UI in millimetres (world frame): lines, marks, goals, walls.

    Keys: ``field`` (length, width, border, line_width), ``lines`` ([x1, y1, x2, y2] each),
    ``circles`` ([x, y, r]), ``marks`` ([x, y]), ``goals`` (per goal: ``side``, ``posts`` as
    [x, y, r], ``net`` as a polyline of [x, y]) and ``walls`` ([x1, y1, x2, y2]).
    """

    def mm(values: tuple[float, ...]) -> list[int]:
        return [round(to_mm(v)) for v in values]

    return {
        "field": {
            "length": round(to_mm(dims.length)),
            "width": round(to_mm(dims.width)),
            "border": round(to_mm(dims.border)),
            "line_width": round(to_mm(dims.line_width)),
        },
        "lines": [mm(s) for s in dims.lines()],
        "circles": [mm((0.0, 0.0, dims.centre_circle_radius))],
        "marks": [mm(p) for p in dims.marks()],
        "goals": [
            {
                "side": side,
                "posts": [mm((x, y, dims.post_radius)) for x, y in dims.posts() if x * side > 0],
                "net": [mm(p) for p in dims.net(side)],
            }
            for side in (-1, 1)
        ],
        "walls": [mm(w) for w in dims.walls()],
    }
