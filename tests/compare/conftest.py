"""A small behavior set written for these tests (never a team's), and edits of it by text."""

from __future__ import annotations

from pathlib import Path

import pytest

from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.lang import compile_file

#: ``patrol`` walks between two posts and chases a seen ball; ``rest`` is called from its state
#: ``wait``; every file is one that an edit below changes.
FILES = {
    "symbols.xabsl": """namespace symbols("Symbols") {
  enum mode { idle, walk, kick };
  float input ball.distance [0..10000] "mm";
  bool input ball.seen;
  float input battery "%";
  enum mode output motion.mode;
  float output motion.speed "mm/s";
  float internal laps;
  float const near = 300 "mm";
}
""",
    "behaviors.xabsl": """namespace skills("Basic behaviors") {
  behavior walk { float speed "mm/s"; float direction "deg"; }
  behavior stand { }
}
""",
    "options/rest.xabsl": """/** Stands still for a while. */
option rest {
  float @seconds [0..60] "s";
  initial state stand_still {
    decision {
      if (state_time > @seconds * 1000)
        goto done;
      else
        stay;
    }
    action {
      motion.mode = idle;
      stand();
    }
  }
  target state done {
    action { stand(); }
  }
}
""",
    "options/patrol.xabsl": """/** Walks between two posts; chases the ball when it sees it. */
option patrol {
  float @speed [0..500] "mm/s";
  common decision {
    /** A seen ball comes first. */
    if (ball.seen && ball.distance < near)
      goto chase;
  }
  initial state to_post_a {
    decision {
      else if (state_time > 4000)
        goto to_post_b;
      else if (battery < 10)
        goto wait;
      else
        stay;
    }
    action {
      motion.mode = walk;
      walk(speed = @speed, direction = 0);
    }
  }
  state to_post_b {
    decision {
      else if (state_time > 4000)
        goto to_post_a;
      else
        stay;
    }
    action {
      motion.mode = walk;
      walk(speed = @speed, direction = 180);
    }
  }
  state chase {
    decision {
      else if (!ball.seen)
        goto to_post_a;
      else
        stay;
    }
    action {
      motion.mode = kick;
      walk(speed = 400, direction = 0);
    }
  }
  state wait {
    decision {
      else if (action_done)
        goto to_post_a;
      else
        stay;
    }
    action {
      laps = laps + 1;
      rest(seconds = 5);
    }
  }
}
""",
    "options/play.xabsl": """option play {
  initial state patrolling {
    action { patrol(speed = 200); }
  }
}
""",
    "agents.xabsl": """/*** Title: Patrol */
include "symbols.xabsl";
include "behaviors.xabsl";
include "options/rest.xabsl";
include "options/patrol.xabsl";
include "options/play.xabsl";
agent patroller("Patroller", play);
""",
}


def write_set(folder: Path, files: dict[str, str] | None = None) -> Path:
    """Write the behavior set (or ``files``) into ``folder``; returns the agents file."""
    for name, text in (files or FILES).items():
        path = folder / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return folder / "agents.xabsl"


def edited(**replacements: tuple[str, str] | None) -> dict[str, str]:
    """FILES with one text replaced per file (``name=(old, new)``; ``None`` deletes the file).

    Keyword names use ``__`` for ``/`` and ``_dot_`` for ``.``: ``options__patrol_dot_xabsl``.
    """
    files = dict(FILES)
    for key, edit in replacements.items():
        name = key.replace("__", "/").replace("_dot_", ".")
        assert name in files, name
        if edit is None:
            del files[name]
            continue
        old, new = edit
        assert files[name].count(old) == 1, (name, old)
        files[name] = files[name].replace(old, new)
    return files


def compile_set(folder: Path, files: dict[str, str] | None = None) -> Program:
    """Write and compile the set; fails the test on a compile error."""
    agents = write_set(folder, files)
    compilation = compile_file(str(agents), base=str(folder))
    assert compilation.program is not None, [d.format() for d in compilation.errors]
    return compilation.program


@pytest.fixture
def original(tmp_path: Path) -> Program:
    """The unedited set, compiled."""
    return compile_set(tmp_path / "old")
