"""A small goalkeeper behavior of our own whose names contain dots, for the dotted-name tests.

Every construct the original compiler accepts with dots: option parameters of all three types
(``@shift.y``, ``@use.hands``, ``@save.kind``) with ``@x`` and ``@robot.x`` in one option;
input functions with ``x`` and ``goal.x``; a basic behavior whose parameter names start with a
keyword (``state.fast``, ``target.hand``); dotted inputs, outputs, internal symbols, a constant,
external and internal enums, and enum elements where one element's name ends like another's
(``dive`` and ``dive.left``, and ``left`` of ``hand``), written short and in full.
"""

from __future__ import annotations

SYMBOLS = """namespace keeper_symbols("Keeper") {
  enum save.mode { none, dive, dive.left, dive.right };
  enum hand { left, right, both.hands };
  enum keeper.phase internal { set.up, react, recover.now };
  float input ball.rel.y "mm";
  bool input ball.close.now;
  float input goal.dist "mm" ( float x; float goal.x; );
  bool input shot.on.target ( float speed.min; bool rolling.only; enum hand hand.used; );
  enum save.mode input save.pick ( float angle.deg; );
  float output keeper.shift.y "mm";
  enum save.mode output keeper.save.out;
  enum hand output keeper.hand.out;
  float output dist.out;
  float internal keeper.memo.y;
  enum keeper.phase internal keeper.phase.now;
  float const goal.half.width = 750 "mm";
}
"""

BEHAVIORS = """namespace keeper_bbs("Keeper skills") {
  behavior keeper.dive.to {
    float x;
    float robot.x;
    bool state.fast;
    enum hand target.hand;
  }
}
"""

KEEPER = """option keeper {
  initial state play {
    action {
      guard(shift.y = ball.rel.y, use.hands = ball.close.now,
            save.kind = save.pick(angle.deg = ball.rel.y), x = goal.half.width, robot.x = ball.rel.y);
    }
  }
}
"""

GUARD = """option guard {
  float @shift.y [mm] "mm";
  bool @use.hands;
  enum save.mode @save.kind;
  float @x;
  float @robot.x;
  initial state watch {
    decision {
      if (@save.kind == dive.left || @save.kind == save.mode.dive) goto save;
      else if (@use.hands && @robot.x > @x) goto save;
      else stay;
    }
    action {
      keeper.shift.y = @shift.y;
      keeper.memo.y = @robot.x - @x;
      dist.out = goal.dist(x = @x, goal.x = @robot.x);
      keeper.phase.now = set.up;
    }
  }
  target state save {
    decision {
      if (shot.on.target(speed.min = @shift.y, rolling.only = false, hand.used = both.hands)) stay;
      else goto watch;
    }
    action {
      keeper.save.out = @save.kind == dive ? save.mode.dive.right : dive.left;
      keeper.hand.out = hand.left;
      keeper.phase.now = keeper.phase.react;
      keeper.dive.to(x = @x, robot.x = @robot.x, state.fast = @use.hands, target.hand = both.hands);
    }
  }
}
"""

AGENTS = """/*** Title: Keeper */
include "keeper_symbols.xabsl";
include "keeper_bbs.xabsl";
include "keeper.xabsl";
include "guard.xabsl";
agent goalie("Goalie", keeper);
"""


def sources(guard: str = GUARD, keeper: str = KEEPER) -> dict[str, str]:
    """The behavior's files (agents file first), with the two options replaceable."""
    return {
        "agents.xabsl": AGENTS,
        "keeper_symbols.xabsl": SYMBOLS,
        "keeper_bbs.xabsl": BEHAVIORS,
        "keeper.xabsl": keeper,
        "guard.xabsl": guard,
    }
