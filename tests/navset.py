"""A generator of team-shaped behavior sets for the navigation tests and the UI frame-rate bench.

Shaped like a RoboCup team's set (facts read from issue 31, no text taken from one): a couple of
hundred options in about fifteen nested source folders (``Options/Soccer/Striker/...``), names
with area prefixes, one root option whose state machine has a few dozen states and long
conditions, a few more large machines, else-if chains, dotted symbol names, an enum game state.
Every option is reachable from the root and every state switches on ``state_time`` as well, so
the activation path moves on the bench world (whose inputs stay 0) without anything set by hand.

Deterministic: the same arguments write the same bytes. ``write_set(folder)`` returns the agents
file; ``FOLDERS`` and ``option_names()`` say what it holds (the tests assert against them).
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field
from pathlib import Path

#: The option folders, each with the name prefix of its options.
FOLDERS: dict[str, str] = {
    "Options/Soccer": "soccer",
    "Options/Soccer/Striker": "striker",
    "Options/Soccer/Goalie": "goalie",
    "Options/Soccer/Defender": "defender",
    "Options/Soccer/Supporter": "supporter",
    "Options/Soccer/SetPieces": "setpiece",
    "Options/Search": "search",
    "Options/Kicks": "kick",
    "Options/Walk": "walk",
    "Options/GameControl": "game",
    "Options/Penalty": "penalty",
    "Options/Head": "head",
    "Options/Motion": "motion",
    "Options/Tools": "tool",
    "Options/Debug": "debug",
}

ROOT = "play_soccer"
#: states of the root option: one per situation, the big machine of the set
ROOT_STATES = 30
#: the root's state while the robot is fallen: it calls the basic behavior stand, nothing else
FALLEN = "fallen"
#: options (besides the root) with a large machine of their own
LARGE = ("striker_main", "goalie_main", "defender_main", "search_main")

_WORDS = [
    "approach", "ball", "align", "turn", "walk", "kick", "dribble", "pass", "guard", "clear", "wait",
    "look", "scan", "track", "position", "step", "return", "block", "dive", "stand", "recover", "sidestep",
    "shoot", "follow", "circle", "avoid", "support", "cover", "intercept", "decide",
]  # fmt: skip

SYMBOLS = """/** Symbols of the generated team set. */
namespace team_symbols("Team symbols") {
  /** Seen in the last frame. */
  bool input ball.was_seen;
  float input ball.distance [0..10000] "mm";
  float input ball.angle [-180..180] "deg";
  float input ball.position.x "mm";
  float input ball.position.y "mm";
  float input robot.pose.x "mm";
  float input robot.pose.rotation "deg";
  float input team.striker.distance_to_ball "mm";
  bool input robot.is_fallen;
  enum game.state { waiting, ready, set, playing, finished, penalized };
  enum game.state input game.state;
  enum team.role { striker, goalie, defender, supporter };
  enum team.role input team.role;
  float output head.pan [-120..120] "deg";
  float internal behavior.ticks;
}
"""

BEHAVIORS = """/** Basic behaviors of the generated team set. */
namespace team_skills("Skills") {
  behavior stand { }
  behavior walk_to { float x "mm"; float y "mm"; float rotation "deg"; }
  behavior kick { float direction "deg"; bool left_foot; }
  behavior look_at { float pan "deg"; float tilt "deg"; }
}
"""


@dataclass
class _Option:
    name: str
    folder: str
    states: int
    children: list[str] = field(default_factory=list)


def _plan(options: int, seed: int) -> list[_Option]:
    """The options in include order: the root, the large ones, then the rest, with their calls."""
    rnd = random.Random(seed)
    folders = list(FOLDERS)
    plan = [_Option(ROOT, "Options/Soccer", ROOT_STATES)]
    for name in LARGE:
        prefix = name.split("_")[0]
        folder = next(f for f, p in FOLDERS.items() if p == prefix)
        plan.append(_Option(name, folder, 14))
    taken = {o.name for o in plan}
    i = 0
    while len(plan) < options:
        folder = folders[i % len(folders)]
        prefix = FOLDERS[folder]
        words = "_".join(rnd.sample(_WORDS, 2))
        name = f"{prefix}_{words}"
        if name in taken:
            name = f"{name}_{i}"
        taken.add(name)
        plan.append(_Option(name, folder, rnd.randint(2, 6)))
        i += 1
    # Calls: every option but the root is called by one earlier option, preferring the same
    # folder (a team's area options call their own helpers) and sometimes a shared one.
    by_folder: dict[str, list[_Option]] = {}
    for index, option in enumerate(plan[1:], start=1):
        # one state calls one option: an option calls at most as many options as it has states
        free = [o for o in plan[:index] if len(o.children) < o.states]
        candidates = [o for o in by_folder.get(option.folder, []) if o in free]
        if option.name in LARGE or (option.folder not in by_folder and len(plan[0].children) < ROOT_STATES):
            parent = plan[0]
        elif not candidates or rnd.random() < 0.15:
            parent = rnd.choice(free[: max(1, len(free) // 4)])
        else:
            parent = rnd.choice(candidates)
        parent.children.append(option.name)
        by_folder.setdefault(option.folder, []).append(option)
    return plan


def _condition(rnd: random.Random, state: int, long: bool) -> str:
    parts = [f"state_time > {300 + 97 * ((state * 7) % 11)}"]
    extra = [
        "ball.distance >= 0",
        "!robot.is_fallen",
        "ball.angle > -180",
        "!(game.state == penalized)",
        "team.striker.distance_to_ball >= 0",
        "robot.pose.rotation < 360",
        "ball.position.x > -5000 && ball.position.y < 5000",
    ]
    for _ in range(rnd.randint(3, 5) if long else rnd.randint(0, 1)):
        parts.append(rnd.choice(extra))
    return " && ".join(parts)


def _action(rnd: random.Random, children: list[str], k: int) -> str:
    if children:
        return f"{children[k % len(children)]}();"
    return rnd.choice(
        [
            "walk_to(x = ball.position.x, y = ball.position.y, rotation = ball.angle);",
            "kick(direction = ball.angle, left_foot = ball.angle > 0);",
            "look_at(pan = ball.angle, tilt = -10);",
            "stand();",
        ]
    )


def _option_source(option: _Option, rnd: random.Random) -> str:
    names = [f"{w}_{k}" if option.states > len(_WORDS) // 2 else w for k, w in enumerate(_WORDS[: option.states])]
    if option.states > len(_WORDS):
        names = [f"situation_{k}" for k in range(option.states)]
    large = option.states > 8
    root = option.name == ROOT
    lines = [f"/** Generated option {option.name} ({option.folder}). */", f"option {option.name} {{"]
    if root:
        # A fallen robot (robot.is_fallen set by hand) only stands: its activation path differs
        # from the others' (the tests select robots by it).
        lines += ["  common decision {", "    if (robot.is_fallen)", f"      goto {FALLEN};", "  }"]
    for k, state in enumerate(names):
        head = "initial state" if k == 0 else "state"
        lines.append(f"  // state {state} of {option.name}")
        lines.append(f"  {head} {state} {{")
        lines.append("    decision {")
        # A large machine decides through an else-if chain over several states, in order; the
        # first branch always fires after a while, so the path moves.
        targets = [names[(k + 1) % len(names)]]
        if large:
            targets += [names[(k + j) % len(names)] for j in (3, 7, 11) if (k + j) % len(names) != k]
        for j, target in enumerate(targets):
            keyword = "else if" if j > 0 or root else "if"
            condition = _condition(rnd, k + j, long=large and j > 0)
            lines.append(f"      {keyword} ({condition})")
            lines.append(f"        goto {target};")
        lines.append("      else")
        lines.append("        stay;")
        lines.append("    }")
        lines.append("    action {")
        lines.append("      behavior.ticks = behavior.ticks + 1;")
        lines.append(f"      {_action(rnd, option.children, k)}")
        lines.append("    }")
        lines.append("  }")
    if root:
        lines += [
            f"  state {FALLEN} {{",
            "    decision {",
            f"      else if (!robot.is_fallen)\n        goto {names[0]};",
            "      else\n        stay;",
            "    }",
            "    action {\n      stand();\n    }",
            "  }",
        ]
    lines.append("}")
    return "\n".join(lines) + "\n"


def option_names(options: int = 200, seed: int = 31) -> dict[str, str]:
    """Option name -> its folder, for a set written with the same arguments."""
    return {o.name: o.folder for o in _plan(options, seed)}


def sensor_symbols(inputs: int, outputs: int) -> str:
    """A symbols file of ``inputs`` more input and ``outputs`` more output symbols (floats, booleans, enums).

    A team's set declares a couple of hundred (naoth-2018: 195 inputs, 71 outputs) of which a
    tick reads a few: what the studio samples per robot and tick.
    """
    lines = ["/** Sensors and actuators of the generated team set. */", 'namespace team_sensors("Sensors") {']
    lines.append("  enum sensor.level { low, medium, high };")
    kinds = ("float", "bool", "float", "enum sensor.level", "float")
    for i in range(inputs):
        kind = kinds[i % len(kinds)]
        lines.append(f"  {kind} input sensor.{_WORDS[i % len(_WORDS)]}.s{i};")
    for i in range(outputs):
        kind = kinds[i % len(kinds)]
        lines.append(f"  {kind} output actuator.{_WORDS[i % len(_WORDS)]}.a{i};")
    lines.append("}")
    return "\n".join(lines) + "\n"


def write_set(
    folder: Path, options: int = 200, seed: int = 31, agent: str = "soccer", inputs: int = 0, outputs: int = 0
) -> Path:
    """Write the set into ``folder`` (created if missing) and return its agents file.

    ``inputs``/``outputs``: that many more symbols declared (:func:`sensor_symbols`), none read.
    """
    folder.mkdir(parents=True, exist_ok=True)
    rnd = random.Random(seed + 1)
    (folder / "Symbols").mkdir(exist_ok=True)
    (folder / "Symbols" / "team_symbols.xabsl").write_text(SYMBOLS)
    (folder / "Symbols" / "team_skills.xabsl").write_text(BEHAVIORS)
    includes = ['include "Symbols/team_symbols.xabsl";', 'include "Symbols/team_skills.xabsl";']
    if inputs or outputs:
        (folder / "Symbols" / "team_sensors.xabsl").write_text(sensor_symbols(inputs, outputs))
        includes.append('include "Symbols/team_sensors.xabsl";')
    for option in _plan(options, seed):
        path = folder / option.folder / f"{option.name}.xabsl"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(_option_source(option, rnd))
        includes.append(f'include "{option.folder}/{option.name}.xabsl";')
    agents = folder / "agents.xabsl"
    agents.write_text("\n".join(includes) + f'\nagent {agent}("Generated team", {ROOT});\n')
    return agents
