"""The world as a Foxglove 2D scene: ``foxglove.SceneUpdate`` messages built from a world's scenes.

Foxglove's 3D panel (switched to its 2D top-down view) draws ``foxglove.SceneUpdate`` messages. A
world whose scenes follow the planar convention below gets two such channels in a recording: the
static field once (:func:`static_update`) and the moving bodies every tick (:class:`SceneBuilder`).

The convention is the studio's scene vocabulary (``xabsl_studio.engine.host.Scene``; lengths in the static
scene's ``units.length``, ``mm`` by default, headings in degrees), plus the soccer field's keys:

* static: ``field`` (``{"x": [lo, hi], "y": [lo, hi]}``, or soccer's ``length``/``width``/
  ``border``), ``walls`` ``[[x1, y1, x2, y2], ...]``, ``shapes``, ``agents[].team``,
  ``teams[].color``, ``robot_radius``; soccer: ``lines``, ``circles`` ``[[x, y, r], ...]``,
  ``goals[].net`` (polylines), ``ball_radius``;
* dynamic: ``robots`` ``[[x, y, heading], ...]`` in agent order, ``shapes``, optional ``ball``
  ``[x, y]``.

``shapes`` (circles, rects, segments with ``fill``/``stroke`` colours, ``label``/``caption``
texts) become outlines, flat discs and boxes, and labels.

A world without ``robots`` in its dynamic scene gets no Foxglove channels (:func:`supports`).
Everything is written in metres in the frame ``field`` (x towards the right goal, z up). The
schema (:data:`SCENE_UPDATE_SCHEMA`) is written from Foxglove's documented field list and
covers the primitives used here.
"""

from __future__ import annotations

import math
from typing import Any

from xabsl_studio.engine.host import Scene

FRAME = "field"

_VEC3 = {
    "type": "object",
    "required": ["x", "y", "z"],
    "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}},
}
_QUAT = {
    "type": "object",
    "required": ["x", "y", "z", "w"],
    "properties": {k: {"type": "number"} for k in "xyzw"},
}
_POSE = {
    "type": "object",
    "required": ["position", "orientation"],
    "properties": {"position": _VEC3, "orientation": _QUAT},
}
_COLOR = {
    "type": "object",
    "required": ["r", "g", "b", "a"],
    "properties": {k: {"type": "number", "minimum": 0, "maximum": 1} for k in "rgba"},
}
_TIME = {
    "type": "object",
    "required": ["sec", "nsec"],
    "properties": {
        "sec": {"type": "integer", "minimum": 0},
        "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999},
    },
}


def _primitive(**fields: Any) -> dict[str, Any]:
    return {"type": "object", "required": list(fields), "properties": fields}


_ENTITY = {
    "title": "foxglove.SceneEntity",
    "type": "object",
    "required": ["timestamp", "frame_id", "id", "lifetime", "frame_locked"],
    "properties": {
        "timestamp": _TIME,
        "frame_id": {"type": "string"},
        "id": {"type": "string"},
        "lifetime": _TIME,
        "frame_locked": {"type": "boolean"},
        "metadata": {"type": "array", "items": _primitive(key={"type": "string"}, value={"type": "string"})},
        "arrows": {
            "type": "array",
            "items": _primitive(
                pose=_POSE,
                shaft_length={"type": "number"},
                shaft_diameter={"type": "number"},
                head_length={"type": "number"},
                head_diameter={"type": "number"},
                color=_COLOR,
            ),
        },
        "cubes": {"type": "array", "items": _primitive(pose=_POSE, size=_VEC3, color=_COLOR)},
        "spheres": {"type": "array", "items": _primitive(pose=_POSE, size=_VEC3, color=_COLOR)},
        "cylinders": {
            "type": "array",
            "items": _primitive(
                pose=_POSE, size=_VEC3, bottom_scale={"type": "number"}, top_scale={"type": "number"}, color=_COLOR
            ),
        },
        "lines": {
            "type": "array",
            "items": {
                "type": "object",
                "required": ["type", "pose", "thickness", "scale_invariant", "points", "color"],
                "properties": {
                    "type": {"enum": [0, 1, 2], "description": "LINE_STRIP, LINE_LOOP, LINE_LIST"},
                    "pose": _POSE,
                    "thickness": {"type": "number"},
                    "scale_invariant": {"type": "boolean"},
                    "points": {"type": "array", "items": _VEC3},
                    "color": _COLOR,
                    "colors": {"type": "array", "items": _COLOR},
                    "indices": {"type": "array", "items": {"type": "integer", "minimum": 0}},
                },
            },
        },
        "triangles": {"type": "array"},
        "texts": {
            "type": "array",
            "items": _primitive(
                pose=_POSE,
                billboard={"type": "boolean"},
                font_size={"type": "number"},
                scale_invariant={"type": "boolean"},
                color=_COLOR,
                text={"type": "string"},
            ),
        },
        "models": {"type": "array"},
    },
}

#: The JSON Schema of ``foxglove.SceneUpdate`` (the name Foxglove recognises).
SCENE_UPDATE_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "foxglove.SceneUpdate",
    "description": "An update to the entities displayed in a 3D scene",
    "type": "object",
    "required": ["deletions", "entities"],
    "properties": {
        "deletions": {
            "type": "array",
            "items": _primitive(timestamp=_TIME, type={"enum": [0, 1]}, id={"type": "string"}),
        },
        "entities": {"type": "array", "items": _ENTITY},
    },
}

_IDENTITY = {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}
_ORIGIN = {"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": _IDENTITY}
_ZERO = {"sec": 0, "nsec": 0}
_WHITE = {"r": 1.0, "g": 1.0, "b": 1.0, "a": 1.0}
_GREY = {"r": 0.6, "g": 0.6, "b": 0.6, "a": 1.0}
_BALL = {"r": 1.0, "g": 0.55, "b": 0.0, "a": 1.0}
_GREEN = {"r": 0.13, "g": 0.45, "b": 0.2, "a": 1.0}


def supports(static: Scene, dynamic: Scene) -> bool:
    """Whether the world's scenes follow the planar convention of this module."""
    robots = dynamic.get("robots")
    return isinstance(robots, list) and all(isinstance(r, list) and len(r) >= 3 for r in robots)


def _scale(static: Scene) -> float:
    unit = (static.get("units") or {}).get("length", "mm")
    return {"mm": 0.001, "cm": 0.01, "m": 1.0}.get(unit, 0.001)


def _color(hex_color: str) -> dict[str, float]:
    text = hex_color.lstrip("#")
    try:
        r, g, b = (int(text[i : i + 2], 16) / 255.0 for i in (0, 2, 4))
    except ValueError:
        return dict(_GREY)
    return {"r": round(r, 3), "g": round(g, 3), "b": round(b, 3), "a": 1.0}


def _stamp(ns: int) -> dict[str, int]:
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def _line(points: list[tuple[float, float]], kind: int, color: dict[str, float], width: float) -> dict[str, Any]:
    return {
        "type": kind,
        "pose": _ORIGIN,
        "thickness": width,
        "scale_invariant": False,
        "points": [{"x": x, "y": y, "z": 0.0} for x, y in points],
        "color": color,
    }


def static_update(static: Scene, time_ns: int) -> dict[str, Any]:
    """The static scene as one persistent entity ``field`` (lines, circles, walls, goal nets)."""
    k = _scale(static)
    width = float(static.get("field", {}).get("line_width", 50)) * k
    segments: list[tuple[float, float]] = []
    for x0, y0, x1, y1 in static.get("lines", []):
        segments += [(x0 * k, y0 * k), (x1 * k, y1 * k)]
    lines = [_line(segments, 2, _WHITE, width)] if segments else []
    for x, y, r in static.get("circles", []):
        loop = [
            (k * (x + r * math.cos(a * math.tau / 48)), k * (y + r * math.sin(a * math.tau / 48))) for a in range(48)
        ]
        lines.append(_line(loop, 1, _WHITE, width))
    walls: list[tuple[float, float]] = []
    for x0, y0, x1, y1 in static.get("walls", []):
        walls += [(x0 * k, y0 * k), (x1 * k, y1 * k)]
    if walls:
        lines.append(_line(walls, 2, _GREY, width))
    for goal in static.get("goals", []):
        net = goal.get("net")
        if net:
            lines.append(_line([(x * k, y * k) for x, y in net], 0, _GREY, width * 2))
    cubes = []
    field = static.get("field") or {}
    if "length" in field and "width" in field:
        border = float(field.get("border", 0))
        size = {"x": (field["length"] + 2 * border) * k, "y": (field["width"] + 2 * border) * k, "z": 0.001}
        cubes.append(
            {
                "pose": {"position": {"x": 0.0, "y": 0.0, "z": -0.002}, "orientation": _IDENTITY},
                "size": size,
                "color": _GREEN,
            }
        )
    elif "x" in field and "y" in field:
        (x0, x1), (y0, y1) = field["x"], field["y"]
        centre = {"x": (x0 + x1) / 2 * k, "y": (y0 + y1) / 2 * k, "z": -0.002}
        size = {"x": abs(x1 - x0) * k, "y": abs(y1 - y0) * k, "z": 0.001}
        cubes.append({"pose": {"position": centre, "orientation": _IDENTITY}, "size": size, "color": _GREEN})
    texts: list[dict[str, Any]] = []
    shapes(static.get("shapes", []), k, lines, cubes, texts)
    entity = {
        "timestamp": _stamp(time_ns),
        "frame_id": FRAME,
        "id": "field",
        "lifetime": _ZERO,
        "frame_locked": False,
        "metadata": [{"key": "kind", "value": str(static.get("kind", ""))}],
        "arrows": [],
        "cubes": cubes,
        "spheres": [],
        "cylinders": [],
        "lines": lines,
        "triangles": [],
        "texts": texts,
        "models": [],
    }
    return {"deletions": [], "entities": [entity]}


def _css(color: object, default: dict[str, float]) -> dict[str, float]:
    """A CSS colour of the scene vocabulary (``#rrggbb`` or ``rgba(r, g, b, a)``) as a Foxglove colour."""
    if not isinstance(color, str):
        return default
    text = color.strip()
    if text.startswith("#") and len(text) == 7:
        return _color(text)
    if text.startswith("rgb") and "(" in text and text.endswith(")"):
        try:
            parts = [float(p) for p in text[text.index("(") + 1 : -1].split(",")]
        except ValueError:
            return default
        if len(parts) < 3:
            return default
        alpha = min(max(parts[3], 0.0), 1.0) if len(parts) > 3 else 1.0
        r, g, b = (min(max(v / 255.0, 0.0), 1.0) for v in parts[:3])
        return {"r": r, "g": g, "b": b, "a": alpha}
    return default


def shapes(
    items: list[dict[str, Any]],
    k: float,
    lines: list[dict[str, Any]],
    cubes: list[dict[str, Any]],
    texts: list[dict[str, Any]],
) -> None:
    """Append the primitives of scene-vocabulary ``shapes`` to ``lines``, ``cubes`` and ``texts``.

    A circle is an outline (thick when filled), a rect a flat box in its fill colour, a segment a
    line; ``label`` and ``caption`` become texts at the shape.
    """
    for item in items:
        kind = item.get("shape")
        fill = item.get("fill")
        color = _css(item.get("stroke") or fill, _WHITE)
        if kind == "circle":
            x, y, r = item["x"] * k, item["y"] * k, item["r"] * k
            loop = [(x + r * math.cos(a * math.tau / 24), y + r * math.sin(a * math.tau / 24)) for a in range(24)]
            lines.append(_line(loop, 1, color, max(r * 0.3, 0.01) if fill else 0.02))
        elif kind == "rect":
            x, y = item["x"] * k, item["y"] * k
            size = {"x": item["w"] * k, "y": item["h"] * k, "z": 0.05}
            position = {"x": x, "y": y, "z": 0.025}
            cubes.append(
                {"pose": {"position": position, "orientation": _IDENTITY}, "size": size, "color": _css(fill, _GREY)}
            )
        elif kind == "segment":
            x, y = item["x1"] * k, item["y1"] * k
            lines.append(_line([(x, y), (item["x2"] * k, item["y2"] * k)], 2, color, 0.02))
        else:
            continue
        text = item.get("label") or item.get("caption")
        if text:
            texts.append(
                {
                    "pose": {"position": {"x": x, "y": y, "z": 0.2}, "orientation": _IDENTITY},
                    "billboard": True,
                    "font_size": 12.0,
                    "scale_invariant": True,
                    "color": _WHITE,
                    "text": str(text),
                }
            )


class SceneBuilder:
    """Turns each tick's dynamic scene into a ``foxglove.SceneUpdate`` (one entity ``bodies``).

    Robots are cylinders in their team's colour with an arrow for the heading and their name as a
    label; the ball is a sphere. Sizes and colours are computed once from the static scene, and
    the message's objects are built once and updated in place every tick (this runs on every
    recorded tick): the update :meth:`update` returns is only valid until the next call, so
    serialize it first.
    """

    __slots__ = (
        "_agents",
        "_ball",
        "_ball_size",
        "_colors",
        "_entity",
        "_k",
        "_robot_size",
        "_robots",
        "_shapes_shown",
        "_update",
    )

    def __init__(self, static: Scene) -> None:
        self._k = _scale(static)
        k = self._k
        team_colors = {t.get("name"): _color(str(t.get("color", ""))) for t in static.get("teams", [])}
        agents = static.get("agents", [])
        self._agents = [str(a.get("name", "")) for a in agents]
        self._colors = [team_colors.get(a.get("team"), _GREY) for a in agents]
        r = float(static.get("robot_radius", 130)) * k
        b = float(static.get("ball_radius", 50)) * k
        self._robot_size = {"x": 2 * r, "y": 2 * r, "z": 0.1}
        self._ball_size = {"x": 2 * b, "y": 2 * b, "z": 2 * b}
        #: per robot: (position, label position, heading quaternion) dicts shared by its primitives
        self._robots: list[tuple[dict[str, float], dict[str, float], dict[str, float]]] = []
        self._ball = {"x": 0.0, "y": 0.0, "z": b}
        self._entity: dict[str, Any] = {
            "timestamp": {"sec": 0, "nsec": 0},
            "frame_id": FRAME,
            "id": "bodies",
            "lifetime": _ZERO,
            "frame_locked": False,
            "metadata": [],
            "arrows": [],
            "cubes": [],
            "spheres": [],
            "cylinders": [],
            "lines": [],
            "triangles": [],
            "texts": [],
            "models": [],
        }
        self._update = {"deletions": [], "entities": [self._entity]}
        self._shapes_shown = False

    def _add_robot(self, i: int) -> None:
        position = {"x": 0.0, "y": 0.0, "z": 0.05}
        label = {"x": 0.0, "y": 0.0, "z": 0.3}
        heading = {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}
        self._robots.append((position, label, heading))
        color = self._colors[i] if i < len(self._colors) else _GREY
        length = self._robot_size["x"] * 1.2
        entity = self._entity
        entity["cylinders"].append(
            {
                "pose": {"position": position, "orientation": _IDENTITY},
                "size": self._robot_size,
                "bottom_scale": 1.0,
                "top_scale": 1.0,
                "color": color,
            }
        )
        entity["arrows"].append(
            {
                "pose": {"position": position, "orientation": heading},
                "shaft_length": length * 0.7,
                "shaft_diameter": 0.03,
                "head_length": length * 0.3,
                "head_diameter": 0.08,
                "color": _WHITE,
            }
        )
        entity["texts"].append(
            {
                "pose": {"position": label, "orientation": _IDENTITY},
                "billboard": True,
                "font_size": 12.0,
                "scale_invariant": True,
                "color": _WHITE,
                "text": self._agents[i] if i < len(self._agents) else f"robot {i}",
            }
        )

    def update(self, dynamic: Scene, time_ns: int) -> dict[str, Any]:
        """The SceneUpdate of one tick (valid until the next call)."""
        k = self._k
        robots = dynamic.get("robots", [])
        while len(self._robots) < len(robots):
            self._add_robot(len(self._robots))
        if len(self._robots) > len(robots):  # fewer robots than before: drop the extra primitives
            del self._robots[len(robots) :]
            for name in ("cylinders", "arrows", "texts"):
                del self._entity[name][len(robots) :]
        sin, cos = math.sin, math.cos
        for (position, label, heading), robot in zip(self._robots, robots, strict=True):
            x = robot[0] * k
            y = robot[1] * k
            half = robot[2] * (math.pi / 360.0)  # half the heading, degrees -> radians
            position["x"] = label["x"] = x
            position["y"] = label["y"] = y
            heading["z"] = sin(half)
            heading["w"] = cos(half)
        ball = dynamic.get("ball")
        entity = self._entity
        if ball is not None:
            self._ball["x"] = ball[0] * k
            self._ball["y"] = ball[1] * k
            if not entity["spheres"]:
                entity["spheres"].append(
                    {
                        "pose": {"position": self._ball, "orientation": _IDENTITY},
                        "size": self._ball_size,
                        "color": _BALL,
                    }
                )
        elif entity["spheres"]:
            entity["spheres"].clear()
        stamp = entity["timestamp"]
        stamp["sec"], stamp["nsec"] = divmod(time_ns, 1_000_000_000)
        items = dynamic.get("shapes")
        if items or self._shapes_shown:
            # The world's moving shapes (objects, sensor rays): few, rebuilt every tick; an empty
            # entity once they are gone replaces the last ones.
            lines: list[dict[str, Any]] = []
            cubes: list[dict[str, Any]] = []
            texts: list[dict[str, Any]] = []
            shapes(items or [], k, lines, cubes, texts)
            self._shapes_shown = bool(items)
            moving = {**entity, "id": "shapes", "arrows": [], "spheres": [], "cylinders": []}
            moving.update({"lines": lines, "cubes": cubes, "texts": texts})
            return {"deletions": [], "entities": [entity, moving]}
        return self._update
