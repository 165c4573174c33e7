"""The errands world's own commands (``xabsl_studio.engine.host.CommandableWorld``): intervene and query.

The studio forwards them with the op ``world_command`` (docs/protocol.md) and renders them from
:func:`describe` without knowing the world:

* **perturb**: ``teleport`` an object to a beacon, ``remove`` an object, ``block`` the straight
  path between two beacons (the perturbations of ``xabsl run examples/errands --perturb``); the
  robot is not told, it finds out through its sensors and derived facts;
* **monitor**: ``force_operator`` (the DD layer runs that operator's couplings whatever the plan
  monitor selects; ``none`` releases), ``replan`` (GRAPHPLAN from the derived facts now; the
  monitor goes on with its running operator, then selects from the new plan) and ``set_fact``
  (a derived fact set or cleared by hand; the fact rules may change it again);
* **query** (no side effects): ``plan`` (every plan version with its reason, done and failed
  operators), ``plan_stats`` (the planning-graph table of one version, what ``xabsl plan
  --stats`` prints), ``fact_events`` (the derived facts' changes with their causes), ``model``
  (the Dual Dynamics model: behaviors, actuators, operator couplings).

:class:`StudioErrandsWorld` is the errands world with these commands, as the studio runs it
(``studio.py``); headless runs take the plain world.
"""

from __future__ import annotations

from dataclasses import asdict
from typing import Any

from xabsl_studio.engine.host import Scene, WorldCommandError
from xabsl_studio.engine.planning.facts import FactEvent
from xabsl_studio.engine.planning.graphplan import format_stats
from xabsl_studio.examples.errands import model_edit
from xabsl_studio.examples.errands.world import ErrandsWorld

BEACONS = ("a", "b", "c")
OBJECTS = ("book", "mug")


def _enum(name: str, choices: tuple[str, ...] | list[str], default: str) -> dict[str, Any]:
    return {"name": name, "type": "enum", "choices": list(choices), "default": default}


def describe(world: ErrandsWorld) -> list[dict[str, Any]]:
    """The command list (``CommandableWorld.commands``)."""
    operators = ["none", *(a.name for a in world.task.actions)]
    return [
        {
            "name": "teleport",
            "label": "Teleport",
            "group": "perturb",
            "doc": "Put an object next to a beacon; the robot is not told.",
            "args": [_enum("object", OBJECTS, "mug"), _enum("to", BEACONS, "b")],
        },
        {
            "name": "remove",
            "label": "Remove",
            "group": "perturb",
            "doc": "Take an object out of the world; the robot is not told.",
            "args": [_enum("object", OBJECTS, "book")],
        },
        {
            "name": "block",
            "label": "Block",
            "group": "perturb",
            "doc": "Put a wall across the straight path between two beacons, halfway.",
            "args": [_enum("from", BEACONS, "c"), _enum("to", BEACONS, "b")],
        },
        {
            "name": "force_operator",
            "label": "Force operator",
            "group": "monitor",
            "doc": "The behaviors run this operator's couplings whatever the monitor selects (none: release).",
            "args": [_enum("operator", operators, "none")],
        },
        {
            "name": "replan",
            "label": "Replan",
            "group": "monitor",
            "doc": "GRAPHPLAN from the derived facts now; the monitor selects from the new plan.",
            "args": [],
        },
        {
            "name": "set_fact",
            "label": "Set fact",
            "group": "monitor",
            "doc": "Set or clear a derived fact by hand (the fact rules may change it again).",
            "args": [
                _enum("fact", list(world.task.facts), world.task.facts[0]),
                {"name": "value", "type": "bool", "default": True},
            ],
        },
        {
            "name": "plan",
            "label": "Plan versions",
            "group": "query",
            "doc": "Every plan with its reason, and the interventions by hand.",
            "args": [],
        },
        {
            "name": "plan_stats",
            "label": "Planning graph",
            "group": "query",
            "doc": "The planning-graph levels of a plan version (xabsl plan --stats).",
            "args": [{"name": "version", "type": "number", "default": -1}],
        },
        {
            "name": "fact_events",
            "label": "Fact events",
            "group": "query",
            "doc": "Changes of the derived facts with their causes, from index `since` on.",
            "args": [{"name": "since", "type": "number", "default": 0}],
        },
        {"name": "model", "label": "DD model", "group": "query", "doc": "The Dual Dynamics model.", "args": []},
        {
            "name": "model_source",
            "label": "Model file",
            "group": "model",
            "doc": "The model file's text and version.",
            "args": [],
        },
        {
            "name": "model_check",
            "label": "Check model",
            "group": "model",
            "doc": "Diagnostics (file, key, line, column) for model text; nothing is saved.",
            "args": [{"name": "text", "type": "string", "default": ""}],
        },
        {
            "name": "model_save",
            "label": "Save model",
            "group": "model",
            "doc": "Save the model text atomically (refused if the file changed since `version`); "
            "hot reload when clean.",
            "args": [
                {"name": "text", "type": "string", "default": ""},
                {"name": "version", "type": "string", "default": ""},
            ],
        },
    ]


def _choice(args: dict[str, Any], name: str, choices: tuple[str, ...] | list[str]) -> str:
    value = args.get(name)
    if value not in choices:
        raise WorldCommandError(f"{name} must be one of {', '.join(choices)}, got {value!r}")
    return str(value)


def _index(args: dict[str, Any], name: str, default: int) -> int:
    value = args.get(name, default)
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, int):
        raise WorldCommandError(f"{name} must be an integer, got {value!r}")
    return value


def run(world: ErrandsWorld, name: str, args: dict[str, Any]) -> Any:
    """Carry out command ``name`` (``CommandableWorld.command``).

    Raises:
        WorldCommandError: unknown command or bad arguments; the world is unchanged.
    """
    if name == "teleport":
        item = _choice(args, "object", OBJECTS)
        to = _choice(args, "to", BEACONS)
        if not world.arena.items[item].present:
            raise WorldCommandError(f"the {item} was removed")
        world.teleport(item, to)
        return world.note_intervention(f"teleported the {item} to {to}")
    if name == "remove":
        item = _choice(args, "object", OBJECTS)
        if not world.arena.items[item].present:
            raise WorldCommandError(f"the {item} is already removed")
        world.remove(item)
        return world.note_intervention(f"removed the {item}")
    if name == "block":
        frm, to = _choice(args, "from", BEACONS), _choice(args, "to", BEACONS)
        if frm == to:
            raise WorldCommandError("from and to must be different beacons")
        world.block_path(frm, to)
        return world.note_intervention(f"blocked {frm}-{to}")
    if name == "force_operator":
        op = _choice(args, "operator", ["none", *(a.name for a in world.task.actions)])
        world.force_operator(None if op == "none" else op)
        return world.note_intervention(f"forced operator {op}" if op != "none" else "released the operator")
    if name == "replan":
        world.plan_from_facts("by_hand")
        return world.note_intervention("replanned by hand") | {"version": len(world.versions)}
    if name == "set_fact":
        fact = _choice(args, "fact", list(world.task.facts))
        value = args.get("value", True)
        if not isinstance(value, bool):
            raise WorldCommandError(f"value must be true or false, got {value!r}")
        world.set_fact(fact, value)
        return world.note_intervention(f"{'set' if value else 'cleared'} {fact}")
    if name == "plan":
        return plan_versions(world)
    if name == "plan_stats":
        return plan_stats(world, _index(args, "version", -1))
    if name == "fact_events":
        since = _index(args, "since", 0)
        if since < 0:
            raise WorldCommandError("since must be >= 0")
        events = world.deriver.events
        return {"total": len(events), "events": [event_json(i, e) for i, e in enumerate(events[since:], since)]}
    if name == "model":
        return model_json(world)
    if name in ("model_source", "model_check", "model_save"):
        if name == "model_source":
            return model_edit.source(world)
        if name == "model_check":
            text = args.get("text")
            if not isinstance(text, str):
                raise WorldCommandError("text (the model file's text) is required")
            diagnostics, _ = model_edit.check(world, text)
            return {"ok": not diagnostics, "diagnostics": diagnostics}
        result = model_edit.save(world, args.get("text"), args.get("version"))
        world.note_intervention(f"saved {world.model_name}" + (" and hot-reloaded it" if result["reloaded"] else ""))
        return result
    raise WorldCommandError(
        f"unknown world command {name!r} (expected one of: {', '.join(c['name'] for c in describe(world))})"
    )


def event_json(index: int, e: FactEvent) -> dict[str, Any]:
    """A fact event as plain data, numbered by its place in the deriver's log."""
    return {"i": index, "t": round(e.t * 1000), "fact": e.fact, "value": e.value, "cause": _plain(dict(e.cause))}


def _plain(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, float):
        return round(value, 4)
    return value


def plan_versions(world: ErrandsWorld) -> dict[str, Any]:
    """Every plan version (first plan and replans) with reason, layers, done and failed operators."""
    board = world.board
    versions = []
    for v in world.versions:
        current = v is world.versions[-1]
        versions.append(
            {k: v[k] for k in ("version", "t", "reason", "kind", "detail", "layers", "dropped", "solved", "failed")}
            | {"done": sorted(board.done) if current else list(v["done"]), "current": current}
        )
    interventions = [{"t": round(t * 1000), "what": what} for t, what in world.interventions]
    return {"versions": versions, "replans": board.replans, "reason": board.reason, "interventions": interventions}


def plan_stats(world: ErrandsWorld, version: int) -> dict[str, Any]:
    """The planning-graph table(s) of plan ``version`` (1-based; -1: the newest)."""
    versions = world.versions
    if not versions:
        raise WorldCommandError("no plan has been made yet")
    if version == -1:
        version = len(versions)
    if not 1 <= version <= len(versions):
        raise WorldCommandError(f"version must be in 1..{len(versions)} or -1")
    v = versions[version - 1]
    lo, hi = v["results"]
    runs = []
    for result in world.board.results[lo:hi]:
        runs.append(
            {
                "solved": result.solved,
                "reason": result.reason,
                "leveled_off_at": result.leveled_off_at,
                "seconds": round(result.seconds, 6),
                "levels": [asdict(s) for s in result.stats],
                "text": format_stats(result.stats),
            }
        )
    return {"version": version, "runs": runs}


def model_json(world: ErrandsWorld) -> dict[str, Any]:
    """The DD model as the dynamics panel needs it: names, rates, thresholds, operator couplings."""
    m = world.dd.model
    return {
        "name": m.name,
        "source": m.source,
        "dt": m.dt,
        "behaviors": list(m.behaviors),
        "levels": [int(x) for x in m.levels.tolist()],
        "lambda": [round(x, 6) for x in m.lam.tolist()],
        "k": [round(x, 6) for x in m.k.tolist()],
        "theta": [round(x, 6) for x in m.theta.tolist()],
        "sigma": [round(x, 6) for x in m.sigma.tolist()],
        "actuators": list(m.actuators),
        "slow": list(m.slow),
        "sensors": list(m.sensors),
        "lambda_s": m.lambda_s,
        "oct": {
            schema: {
                "params": list(o.params),
                "couplings": [{"pattern": c.pattern, "z": c.z, "c": c.c} for c in o.couplings],
            }
            for schema, o in m.oct.items()
        },
    }


class StudioErrandsWorld(ErrandsWorld):
    """The errands world as the studio runs it: with its world commands (``CommandableWorld``)."""

    def commands(self) -> list[dict[str, Any]]:
        """The world's commands: perturb, monitor, query (see the module docstring)."""
        return describe(self)

    def command(self, name: str, args: dict[str, Any]) -> Any:
        """Carry out one world command between two ticks."""
        return run(self, name, args)

    def static_scene(self) -> Scene:
        """The world's scene, with the commands it offers (op ``world_command``)."""
        return {**super().static_scene(), "commands": self.commands()}
