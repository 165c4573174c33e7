"""Which behavior a tournament side plays: the engine's version specs (``xabsl_studio.engine.cli.versions``).

The loader moved to the engine so that ``xabsl diff`` and the studio's Compare view read
``git:REV:PATH`` exactly as the tournament does; the tournament keeps its names here.
"""

from __future__ import annotations

from xabsl_studio.engine.cli.versions import GIT_PREFIX, Version, resolve

__all__ = ["GIT_PREFIX", "Version", "resolve"]
