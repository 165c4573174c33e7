"""What a query answers: the intervals of consecutive ticks in which the condition is true, per robot."""

from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["Interval", "QueryResult"]


@dataclass(frozen=True, slots=True)
class Interval:
    """Ticks ``first_seq`` .. ``last_seq`` (both included) of ``robot``, all of them matching.

    ``first_t_ms`` / ``last_t_ms`` are the world clock of the first and the last tick (ms).
    """

    robot: str
    first_seq: int
    last_seq: int
    first_t_ms: int
    last_t_ms: int

    @property
    def ticks(self) -> int:
        """How many ticks the interval spans."""
        return self.last_seq - self.first_seq + 1

    def to_json(self) -> dict[str, object]:
        """JSON-ready fields (``ticks`` included)."""
        return {
            "robot": self.robot,
            "first_seq": self.first_seq,
            "last_seq": self.last_seq,
            "first_t_ms": self.first_t_ms,
            "last_t_ms": self.last_t_ms,
            "ticks": self.ticks,
        }


@dataclass(frozen=True)
class QueryResult:
    """The answer to one query over the ticks of some robots.

    ``intervals`` are ordered by first tick, then robot. ``ticks`` counts the robot-ticks
    evaluated, ``matched`` those where the condition is true, ``unknown`` those where it cannot
    be known from what was recorded (they never match). ``skipped`` names, per robot, why the
    condition was not evaluated for it (its behavior lacks a name the condition uses).
    """

    condition: str
    robots: list[str]
    intervals: list[Interval]
    ticks: int = 0
    matched: int = 0
    unknown: int = 0
    skipped: dict[str, str] = field(default_factory=dict)

    def to_json(self) -> dict[str, object]:
        """JSON-ready fields."""
        return {
            "condition": self.condition,
            "robots": list(self.robots),
            "intervals": [i.to_json() for i in self.intervals],
            "ticks": self.ticks,
            "matched": self.matched,
            "unknown": self.unknown,
            "skipped": dict(self.skipped),
        }
