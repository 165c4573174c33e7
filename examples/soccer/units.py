"""Units: the one place where behavior units meet physics units.

Everything a behavior sees or commands is in **millimetres, degrees and milliseconds** (the
convention of XABSL soccer behaviors, e.g. ``ball.distance`` in mm, ``ball.angle`` in degrees),
with angles counter-clockwise positive and normalised to [-180, 180). pymunk works in **metres,
radians and seconds**. Every conversion between the two goes through this module; modules that
talk to pymunk (``physics``, ``robot``) keep SI internally, and the boundaries (``perception``,
the motion request, the scenes) convert here.
"""

from __future__ import annotations

import math

MM_PER_M = 1000.0
M_PER_MM = 1.0 / MM_PER_M
DEG_PER_RAD = 180.0 / math.pi
RAD_PER_DEG = math.pi / 180.0

_TWO_PI = 2.0 * math.pi


def to_mm(metres: float) -> float:
    """Convert metres (physics) to millimetres (behaviors)."""
    return metres * MM_PER_M


def to_m(millimetres: float) -> float:
    """Convert millimetres (behaviors) to metres (physics)."""
    return millimetres * M_PER_MM


def to_deg(radians: float) -> float:
    """Convert radians to degrees, normalised to [-180, 180)."""
    return normalize_deg(radians * DEG_PER_RAD)


def to_rad(degrees: float) -> float:
    """Convert degrees to radians, normalised to [-pi, pi)."""
    return normalize_rad(degrees * RAD_PER_DEG)


def normalize_rad(angle: float) -> float:
    """Wrap an angle in radians into [-pi, pi)."""
    return (angle + math.pi) % _TWO_PI - math.pi


def normalize_deg(angle: float) -> float:
    """Wrap an angle in degrees into [-180, 180)."""
    return (angle + 180.0) % 360.0 - 180.0
