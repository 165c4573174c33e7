"""The generations a live session keeps by number: the behavior sources each ran, what changed, diffs.

A generation (``xabsl_studio.server.session.frames.Generation``) starts at every start, hot reload and reset of the
simulation. The ring buffer's ticks keep theirs, so the timeline can read a tick of any
generation still in the ring; this module keeps, beside that, the source texts of each
generation's running behaviors (``Compilation.sources``) so that a reload mark in the timeline
can show what changed (:meth:`Generations.diff`, ``GET /api/generations/{number}/diff``).

Memory is bounded: a text that did not change since the previous generation is the same string
object (kept once), generations older than the ring's oldest tick (but the one before it, which a
diff of the oldest needs) are dropped, and at most :data:`MAX_GENERATIONS` generations and about
:data:`MAX_SOURCE_CHARS` characters of distinct text are kept.
"""

from __future__ import annotations

import difflib
from collections.abc import Mapping
from typing import Literal

from xabsl_studio.server.protocol.errors import ServerError
from xabsl_studio.server.protocol.rest import ChangedFile, GenerationDiff
from xabsl_studio.server.session.frames import Generation, Ring

#: The most generations kept (a reload every second for two minutes stays well inside).
MAX_GENERATIONS = 200
#: About this many characters of distinct source text are kept over all generations.
MAX_SOURCE_CHARS = 32_000_000
#: A diff longer than this many characters is cut (with a note saying so).
MAX_DIFF_CHARS = 200_000

Sources = Mapping[str, Mapping[str, str]]


class GenerationGone(ServerError, LookupError):
    """A generation (or the one before it) that is no longer kept."""


class Generations:
    """The kept generations, oldest first, each with its sources and changed files."""

    def __init__(self) -> None:
        self._by_number: dict[int, Generation] = {}

    def __len__(self) -> int:
        return len(self._by_number)

    def get(self, number: int) -> Generation | None:
        """Generation ``number``, or None when it is not kept."""
        return self._by_number.get(number)

    def add(self, gen: Generation, sources: Sources, ring: Ring | None = None) -> None:
        """Keep ``gen`` with the ``sources`` (per behavior key: name -> text) its behaviors ran.

        Sets ``gen.sources`` (sharing texts unchanged since the previous generation) and
        ``gen.changed`` (per behavior key: the files added, removed or edited since then), then
        drops what the bounds say (``ring``: its oldest tick's generation is the oldest needed).
        """
        previous = self._by_number.get(gen.number - 1)
        before = previous.sources if previous is not None else {}
        kept: dict[str, dict[str, str]] = {}
        for key, texts in sources.items():
            old = before.get(key, {})
            kept[key] = {name: _shared(old.get(name), text) for name, text in texts.items()}
        gen.sources = kept
        gen.changed = changed_files(before, kept) if previous is not None else {}
        self._by_number[gen.number] = gen
        self._prune(gen.number, ring)

    def _prune(self, newest: int, ring: Ring | None) -> None:
        oldest_needed = -1  # without a ring (or an empty one) only the bounds drop generations
        if ring is not None:
            entries = ring.snapshot()
            if entries:
                oldest_needed = entries[0].gen.number - 1
        for number in sorted(self._by_number):
            if number < oldest_needed and number != newest:
                del self._by_number[number]
        numbers = sorted(self._by_number)
        while len(numbers) > MAX_GENERATIONS or (len(numbers) > 1 and self._chars() > MAX_SOURCE_CHARS):
            del self._by_number[numbers.pop(0)]

    def _chars(self) -> int:
        seen: dict[int, int] = {}
        for gen in self._by_number.values():
            for texts in gen.sources.values():
                for text in texts.values():
                    seen[id(text)] = len(text)
        return sum(seen.values())

    def diff(self, number: int) -> GenerationDiff:
        """What changed from generation ``number - 1`` to ``number``: per file a unified diff.

        Raises:
            GenerationGone: either generation is no longer kept.
        """
        gen = self._by_number.get(number)
        if gen is None:
            raise GenerationGone(f"generation {number} is not kept (any more)")
        previous = self._by_number.get(number - 1)
        if previous is None:
            raise GenerationGone(f"generation {number - 1}, the one before {number}, is not kept (any more)")
        files: list[ChangedFile] = []
        for key, names in sorted(gen.changed.items()):
            old, new = previous.sources.get(key, {}), gen.sources.get(key, {})
            for name in names:
                change: Literal["changed", "added", "removed"] = (
                    "added" if name not in old else "removed" if name not in new else "changed"
                )
                files.append(
                    {
                        "program": key,
                        "path": name,
                        "change": change,
                        "diff": unified_diff(name, old.get(name, ""), new.get(name, ""), number),
                    }
                )
        return {"number": number, "reason": gen.reason, "previous": number - 1, "files": files}


def _shared(old: str | None, text: str) -> str:
    """``old`` when it equals ``text`` (one string kept for both generations), else ``text``."""
    return old if old is not None and old == text else text


def changed_files(before: Sources, after: Sources) -> dict[str, list[str]]:
    """Per behavior key: the files whose text differs between two generations (added and removed too)."""
    changed: dict[str, list[str]] = {}
    for key in sorted(set(before) | set(after)):
        old, new = before.get(key, {}), after.get(key, {})
        names = sorted(name for name in set(old) | set(new) if old.get(name) != new.get(name))
        if names:
            changed[key] = names
    return changed


def unified_diff(name: str, before: str, after: str, number: int) -> str:
    """The unified diff of one file from generation ``number - 1`` to ``number`` (cut when huge)."""
    lines = difflib.unified_diff(
        before.splitlines(),
        after.splitlines(),
        fromfile=f"{name} (generation {number - 1})",
        tofile=f"{name} (generation {number})",
        lineterm="",
    )
    text = "\n".join(lines)
    if len(text) > MAX_DIFF_CHARS:
        text = text[:MAX_DIFF_CHARS] + f"\n... (cut: the diff has {len(text)} characters)"
    return text
