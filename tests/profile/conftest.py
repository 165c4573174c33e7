"""Tiny recordings whose counts are known by hand (a scripted behavior on the bench world)."""

from __future__ import annotations

from pathlib import Path

import pytest

from xabsl_studio.engine.host import BehaviorLoop
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.engine.record import Recorder
from xabsl_studio.engine.worlds.bench import BenchController, BenchWorld

#: Root ``cycle``: state ``a`` for 4 ticks (calls ``sub``), ``b`` for 2, again (a 6-tick period at
#: 40 Hz); ``sub``: ``x`` for its first tick, then ``y``; ``z`` and the option ``unused`` are never
#: reached. Only ``state_time`` decides, so the run is the same in any world.
FILES = {
    "bb.xabsl": """
namespace bb("basic behaviors") {
  behavior stand { }
}
""",
    "sub.xabsl": """
option sub {
  initial state x {
    decision { if (state_time >= 25) goto y; else stay; }
    action { stand(); }
  }
  state y {
    decision { stay; }
    action { stand(); }
  }
  state z {
    decision { goto x; }
    action { stand(); }
  }
}
""",
    "unused.xabsl": """
option unused {
  initial state only {
    decision { stay; }
    action { stand(); }
  }
}
""",
    "cycle.xabsl": """
option cycle {
  initial state a {
    decision { if (state_time >= 100) goto b; else stay; }
    action { sub(); }
  }
  state b {
    decision { if (state_time >= 50) goto a; else stay; }
    action { stand(); }
  }
}
""",
    "agents.xabsl": """
include "bb.xabsl";
include "sub.xabsl";
include "unused.xabsl";
include "cycle.xabsl";
agent cycler("Cycler", cycle);
agent spare("Spare", unused);
""",
}
TICKS = 60


def record(path: Path, ticks: int = TICKS, robots: int = 1) -> Path:
    """Record ``ticks`` ticks of BEHAVIOR on ``robots`` bench robots into ``path``."""
    for name, text in FILES.items():
        (path.parent / name).write_text(text)
    source = path.parent / "agents.xabsl"
    compilation = compile_file(str(source))
    assert compilation.program is not None and not compilation.errors, [d.format() for d in compilation.errors]
    program = compilation.program
    world = BenchWorld(1, robots)
    for agent in world.agents:
        agent.controller = BenchController(agent, program)
    loop = BehaviorLoop(world)
    recorder = Recorder(path, world, {"cycler": program}, example="bench", behavior_hz=40, physics_hz=120)
    for _ in range(ticks):
        now = loop.now_ms
        loop.tick()
        recorder.tick(now)
    recorder.close()
    return path


@pytest.fixture(scope="package")
def cycle_recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """60 ticks of one robot (10 whole periods)."""
    return record(tmp_path_factory.mktemp("cycle") / "cycle.mcap")


@pytest.fixture(scope="package")
def team_recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """60 ticks of two robots."""
    return record(tmp_path_factory.mktemp("team") / "team.mcap", robots=2)
