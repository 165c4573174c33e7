"""The errands world: the host contract (``xabsl_studio.engine.host.World``) over the arena, DD, facts and the plan.

``build_world(seed)`` makes the errands robot of dual-dynamics.md §1.5: one agent whose
behavior is two layers,

* the **Dual Dynamics** behavior system (:class:`xabsl_studio.engine.dynamics.system.DDSystem` on
  ``model/errands_dd.json``): roam, approach_{a,b,c}, gather_{book,mug}, dump_{book,mug}, fused
  into wheel and gripper commands by superposition; and
* the **plan monitor** written in XABSL (``behavior/execute_plan.xabsl``), the agent's
  controller (:class:`xabsl_studio.engine.runtime.Engine`). It reads derived facts and plan data as input
  symbols and selects the current operator as output symbols; the host turns that into σ_OP,
  so the operator's switch variable s_OP ramps up and its operator-coupling terms bias the
  activations. The plan never commands an actuator.

One behavior tick follows doc §4.1 inside the host loop's sense / execute / act / step frame::

    sense    1 sensors S_t from the arena            2 facts F_t ← FactDeriver(S_t, α_{t−1}, g/d_{t−1})
    execute  3 XABSL: fact.*, plan.* → plan.op, plan.op.*, plan.status (may call GRAPHPLAN)
    act      4 σ_OP from plan.op; 5–6 DDSystem.step (s ramps, Δα, Δm, commit)  7 actuators → arena
             8 the tick's record stays available: dynamic_scene(), debug_frame()
    step     0 pymunk physics (2 × 10 ms per 20 ms tick by default)

``plan=False`` selects the XABSL agent ``reactive`` (no operator ever), for the no-plan claims.
``program=None`` builds the world without a controller (the studio attaches the program it
compiled with :meth:`ErrandsWorld.attach`; until then the robot roams with no operator).
The monitor's symbols and basic behaviors are bound in :mod:`xabsl_studio.examples.errands.bindings`; the
host side of the plan (queue, next executable operator, replanning) is an
:class:`xabsl_studio.engine.planning.monitor.PlanBoard` with the errands' partial-plan rule
(:func:`xabsl_studio.examples.errands.plan.errands_board`).

Ground truth (the arena) and what the robot believes (derived facts) are kept apart; the world
compares them every tick (:class:`xabsl_studio.examples.errands.facts.Agreement`) and counts what the §4.4
claims need (:class:`RunRecord`). Perturbation hooks for tests and the studio: ``teleport``,
``remove``, ``block_path``, ``place_robot``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path
from time import perf_counter
from typing import Any

import numpy as np

from xabsl_studio.engine.dynamics.model import DDModel, load_model
from xabsl_studio.engine.dynamics.system import DDSystem, TickRecord
from xabsl_studio.engine.host import AgentController, RunStats, Scene, run_headless
from xabsl_studio.engine.ir.model import Program
from xabsl_studio.engine.planning.facts import FactDeriver, FactEvent
from xabsl_studio.engine.planning.strips import Fact, Task, load_task
from xabsl_studio.engine.runtime import Engine
from xabsl_studio.engine.types import Ms
from xabsl_studio.examples.errands.arena import Arena, ArenaLayout, Box, wrap
from xabsl_studio.examples.errands.bindings import (
    ITEMS,
    LOCATIONS,
    PDDL_SCHEMA,
    REASONS,
    SCHEMAS,
    STATUSES,
    monitor_bindings,
)
from xabsl_studio.examples.errands.facts import Agreement, Truth, evidence_signals, fact_rules, truth_facts
from xabsl_studio.examples.errands.plan import errands_board

HERE = Path(__file__).resolve().parent
MODEL_PATH = HERE / "model" / "errands_dd.json"
DOMAIN_PATH = HERE / "pddl" / "domain.pddl"
PROBLEM_PATH = HERE / "pddl" / "problem.pddl"
AGENTS_PATH = HERE / "behavior" / "agents.xabsl"

#: Where objects count as delivered for claim 15: released within this distance of beacon a.
DELIVERY_RADIUS = 0.9


@cache
def _program(path: str) -> Program:
    """Compile the behavior once per process (every world of a test session shares it)."""
    from xabsl_studio.engine.lang import compile_file

    compilation = compile_file(path)
    if compilation.program is None:
        raise RuntimeError("errands behavior does not compile:\n" + "\n".join(d.format() for d in compilation.errors))
    return compilation.program


@cache
def _model(path: str, dt: float) -> DDModel:
    return load_model(path, dt=dt)


@cache
def _task(domain: str, problem: str) -> Task:
    return load_task(domain, problem)


@dataclass(frozen=True, slots=True)
class _SparseRows:
    """The model's B and W as sparse Python rows, for the studio's per-tick drive decomposition."""

    b: list[list[tuple[int, float]]]
    w_self: list[float]
    w_others: list[list[tuple[int, float]]]
    bias: list[float]
    pair_behavior: list[int]
    pair_actuator: list[int]


_SPARSE: dict[int, tuple[DDModel, _SparseRows]] = {}


def _sparse_rows(m: DDModel) -> _SparseRows:
    hit = _SPARSE.get(id(m))
    if hit is None or hit[0] is not m:
        B, W = m.B.tolist(), m.W.tolist()
        rows = _SparseRows(
            b=[[(j, v) for j, v in enumerate(row) if v] for row in B],
            w_self=[W[i][i] for i in range(m.n)],
            w_others=[[(j, v) for j, v in enumerate(row) if v and j != i] for i, row in enumerate(W)],
            bias=[round(v, 5) for v in m.bias.tolist()],
            pair_behavior=[int(v) for v in m.pair_behavior.tolist()],
            pair_actuator=[int(v) for v in m.pair_actuator.tolist()],
        )
        hit = _SPARSE[id(m)] = (m, rows)
    return hit[1]


@dataclass
class RunRecord:
    """What happened during a run, counted per tick for the §4.4 claims.

    Attributes:
        started: operators in the order the monitor started them (``"goto a c"``).
        completed: operators in the order the monitor marked them done.
        max_switches_on: the largest number of s_OP ≥ 0.5 seen on one tick (claim 17).
        dominant_switches: changes of the behavior with the largest α (claim 12).
        roam_dominant_ticks: ticks on which roam had the largest α (claim 13).
        arrivals: beacon name per arrival (truth At(robot, x) rising edge) (claim 11).
        ever_held: whether the gripper ever held an object (claim 10).
        positions: robot (t, x, y) once per simulated second (claim 14).
        completed_at: first time both objects lay released within 0.9 m of a (claim 15).
        monitor: (t, plan.status, plan.op, plan.last_failure) whenever one of them changed.
        false_has_robot: confirmed Has-Robot events while the object was not held (claim 20).
    """

    started: list[str] = field(default_factory=list)
    completed: list[str] = field(default_factory=list)
    max_switches_on: int = 0
    dominant_switches: int = 0
    roam_dominant_ticks: int = 0
    ticks: int = 0
    arrivals: list[str] = field(default_factory=list)
    ever_held: bool = False
    positions: list[tuple[float, float, float]] = field(default_factory=list)
    completed_at: float | None = None
    monitor: list[tuple[float, str, str | None, str]] = field(default_factory=list)
    false_has_robot: list[tuple[float, str]] = field(default_factory=list)


class ErrandsAgent:
    """The errands robot as the host loop sees it; its controller is the XABSL engine."""

    __slots__ = ("_world", "controller", "name", "number", "team")

    def __init__(self, world: ErrandsWorld, controller: Engine | None) -> None:
        self._world = world
        self.name = "robot"
        self.team = "errands"
        self.number = 1
        self.controller: AgentController | None = controller

    @property
    def world(self) -> ErrandsWorld:
        """The world this robot lives in."""
        return self._world

    def sense(self, now_ms: Ms) -> None:
        """§4.1 steps 1–2: sensors from the arena, facts from the signal history (host hook)."""
        self._world._sense()

    def act(self, now_ms: Ms) -> None:
        """§4.1 steps 4–7: σ_OP from plan.op, one DD tick, actuators to the arena (host hook)."""
        self._world._act()


class ErrandsWorld:
    """The errands robot in its arena; implements ``xabsl_studio.engine.host.World``.

    Args:
        seed: seeds the DD noise (the arena itself is deterministic).
        plan: run the plan monitor (agent ``planner``) or the reactive robot (agent ``reactive``).
        dt: the behavior tick in seconds (DD, facts and XABSL all run at this rate).
        noise: multiplies every σ of the DD model (0: deterministic dynamics).
        layout: the arena; defaults to the §1.5 sketch arena.
        model_path, domain_path, problem_path, agents_path: the example's files, replaceable.
        program: the plan monitor's compiled behavior; ``None`` compiles ``agents_path``.
        controller: False builds the robot without an engine (see :meth:`attach`).
    """

    def __init__(
        self,
        seed: int = 1,
        *,
        plan: bool = True,
        dt: float = 0.02,
        noise: float = 1.0,
        layout: ArenaLayout | None = None,
        model_path: Path = MODEL_PATH,
        domain_path: Path = DOMAIN_PATH,
        problem_path: Path = PROBLEM_PATH,
        agents_path: Path = AGENTS_PATH,
        program: Program | None = None,
        controller: bool = True,
    ) -> None:
        self.seed = int(seed)
        self.with_plan = plan
        self.dt = float(dt)
        physics_rate(self.dt)  # reject a tick the loop cannot run before building anything
        self.arena = Arena(layout)
        self.model_path = Path(model_path)
        #: the model file's name as the studio shows it (relative to the example folder)
        self.model_name = f"{self.model_path.parent.name}/{self.model_path.name}"
        self.dd = DDSystem(_model(str(model_path), self.dt), seed=self.seed, dt=self.dt, noise=noise)
        self.behaviors = self.dd.model.behaviors
        self._roam = self.behaviors.index("roam") if "roam" in self.behaviors else -1
        self.task = _task(str(domain_path), str(problem_path))
        self.board = errands_board(self.task)
        self.deriver = FactDeriver(fact_rules(LOCATIONS, ITEMS))
        self.deriver.reset(self.task.init)
        self.facts: frozenset[Fact] = self.deriver.facts
        self.truth: frozenset[Fact] = truth_facts(self.arena)
        self.agreement = Agreement()
        self.record = RunRecord()
        self.tick_events: list[FactEvent] = []
        self.sensors: dict[str, float] = {}
        self.signals: dict[str, float] = {}
        self.ticks = 0
        self.t = 0.0
        self._next: tuple[int, int, int, int] | None = None
        # Output symbols of the monitor, written through by the engine (host values).
        self.out = {
            "plan.op": 0,
            "plan.op.from": 0,
            "plan.op.loc": 0,
            "plan.op.obj": 0,
            "plan.status": 0,
            "plan.last_failure": 0,
        }
        self.operator: str | None = None
        self._op_key: tuple[int, int, int, int] = (0, 0, 0, 0)
        self._truth = Truth(self.arena)
        self._truth_before: frozenset[Fact] = frozenset()
        self._items_seen = 0
        x0, y0, _ = self.arena.pose()
        self.record.positions.append((0.0, x0, y0))
        self._last_sample = 0.0
        self._dominant = -1
        self._held_before: set[str] = set()
        self._at_before: set[str] = set()
        self._monitor_seen: tuple[int, str | None, int] = (-1, None, -1)
        self.engine: Engine | None = None
        self._agents = (ErrandsAgent(self, None),)
        self.sense_hooks: list[Callable[[ErrandsWorld], None]] = []
        # The studio's view of the plan and the interventions (commands.py); cheap per change.
        self.versions: list[dict[str, Any]] = []
        self.forced_op: str | None = None
        self.interventions: list[tuple[float, str]] = []
        self._last_op: str | None = None
        self._op_since = 0.0
        self._prev_tick: TickRecord | None = None
        if controller:
            self.attach(program if program is not None else _program(str(agents_path)))

    def attach(self, program: Program) -> Engine:
        """Make an engine for ``program`` on the monitor's bindings the robot's controller.

        Selects the XABSL agent ``planner`` (``reactive`` without a plan) when the program has it.

        Raises:
            xabsl_studio.engine.runtime.LinkError: the program declares a symbol or behavior the bindings lack.
        """
        engine = Engine(monitor_bindings(self), program, agent_name="robot")
        wanted = "planner" if self.with_plan else "reactive"
        if any(agent.name == wanted for agent in program.agents):
            engine.root_actions.select_agent(wanted)
        self.engine = engine
        self._agents[0].controller = engine
        return engine

    # -- XABSL bindings -----------------------------------------------------------------------------

    def next_op(self) -> tuple[int, int, int, int]:
        """plan.next.* as host enum values, computed once per tick (and after plan changes)."""
        if self._next is None:
            a = self.board.next_executable(self.facts)
            if a is None:
                self._next = (0, 0, 0, 0)
            else:
                args = a.args
                if a.schema == "goto":
                    self._next = (1, LOCATIONS.index(args[0]), LOCATIONS.index(args[1]), 0)
                else:
                    self._next = (SCHEMAS.index(a.schema), 0, LOCATIONS.index(args[1]), ITEMS.index(args[0]))
        return self._next

    def _operator(self) -> str | None:
        """The ground operator named by the monitor's outputs (``"goto a c"``), or None."""
        out = self.out
        schema = SCHEMAS[out["plan.op"]]
        if schema == "none":
            return None
        loc = LOCATIONS[out["plan.op.loc"]]
        if schema == "go_to":
            return f"goto {LOCATIONS[out['plan.op.from']]} {loc}"
        return f"{PDDL_SCHEMA[schema]} {ITEMS[out['plan.op.obj']]} {loc}"

    def plan_from_facts(self, reason: str) -> None:
        """Run GRAPHPLAN from the derived facts (the basic behavior plan_from_facts)."""
        board = self.board
        first = len(board.results)
        if self.versions:
            self.versions[-1]["done"] = sorted(board.done)
        board.plan_from(self.facts, self.t, reason)
        self._next = None
        event = board.events[-1]
        self.versions.append(
            {
                "version": len(self.versions) + 1,
                "t": round(self.t * 1000),
                "reason": reason,
                "kind": event.kind,
                "detail": event.detail,
                "layers": board.plan.names() if board.solved and board.plan is not None else [],
                "dropped": sorted(board.dropped),
                "solved": board.solved,
                "failed": {},
                "done": [],
                "results": (first, len(board.results)),
            }
        )

    def complete_operator(self) -> None:
        """Mark the monitor's operator done (the basic behavior complete_operator)."""
        op = self._operator()
        if op is not None:
            if op not in self.board.done:
                self.record.completed.append(op)
            self.board.complete(op, self.t)
        self._next = None

    # -- host contract ----------------------------------------------------------------------------

    @property
    def agents(self) -> tuple[ErrandsAgent, ...]:
        """The one robot of the arena."""
        return self._agents

    @property
    def plan_status(self) -> str:
        """``plan.status`` of the monitor: idle, executing, replanning, done or failed."""
        return STATUSES[self.out["plan.status"]]

    @property
    def finished(self) -> bool:
        """With a plan: the monitor reached done or failed. Without: never."""
        if self.engine is not None and self.engine.fault is not None:
            return True  # a faulted controller does nothing more: stop rather than run on blind
        return self.with_plan and self.out["plan.status"] in (3, 4)

    @property
    def completed(self) -> bool:
        """Ground truth: both objects lie released within 0.9 m of beacon a."""
        return self.record.completed_at is not None

    def _sense(self) -> None:
        t = self.t = self.ticks * self.dt
        for hook in self.sense_hooks:
            hook(self)
        sensors = self.arena.sense(self.sensors)
        signals = self.dd.signals(sensors)
        evidence_signals(signals, ITEMS)
        self.signals = signals
        events = self.tick_events = self.deriver.update(t, signals)
        facts = self.facts = self.deriver.facts
        self._next = None
        truth = self.truth = self._truth()
        self.agreement.update(t, facts, truth)
        if events:
            for ev in events:
                if ev.value and ev.fact.startswith("has-robot ") and ev.fact not in truth:
                    self.record.false_has_robot.append((t, ev.fact))

    def _act(self) -> None:
        rec = self.record
        out = self.out
        key = (out["plan.op"], out["plan.op.from"], out["plan.op.loc"], out["plan.op.obj"])
        if key != self._op_key:
            self._op_key = key
            op = self._operator() if self.forced_op is None else self.forced_op
            if op != self.operator:
                self.dd.set_current_operator(op)
                self.operator = op
                self._op_since = self.t
                if op is not None:
                    rec.started.append(op)
                    self._last_op = op
        op = self.operator
        mon = (out["plan.status"], op, out["plan.last_failure"])
        if mon != self._monitor_seen:
            self._monitor_seen = mon
            rec.monitor.append((round(self.t, 3), STATUSES[mon[0]], op, REASONS[mon[2]]))
            failure = REASONS[mon[2]]
            if mon[0] == 2 and failure in ("op_timeout", "precondition_lost") and self._last_op and self.versions:
                self.versions[-1]["failed"][self._last_op] = failure  # the operator that was running
        self._prev_tick = self.dd.last
        tick = self.dd.step(self.sensors)
        a = self.dd.actuators
        arena = self.arena
        arena.drive(a["m_l"], a["m_r"])
        for o in ITEMS:
            if arena.grip(o, a["g_" + o], a["d_" + o]) == "grabbed":
                rec.ever_held = True
        # Bookkeeping for the claims: cheap scalar work only.
        if tick.switches:
            on = sum(1 for v in tick.switches.values() if v >= 0.5)
            if on > rec.max_switches_on:
                rec.max_switches_on = on
        dom = tick.dominant_index()
        if dom != self._dominant:
            if self._dominant >= 0:
                rec.dominant_switches += 1
            self._dominant = dom
        if dom == self._roam:
            rec.roam_dominant_ticks += 1
        rec.ticks += 1
        truth = self.truth
        if truth is not self._truth_before:
            at_now = {f[9:] for f in truth if f.startswith("at-robot ")}
            rec.arrivals.extend(sorted(at_now - self._at_before))
            self._at_before = at_now
            self._truth_before = truth
        self.ticks += 1

    def step(self, dt: float) -> None:
        """Advance physics by ``dt`` seconds (the loop calls this after act)."""
        arena = self.arena
        arena.step(dt)
        rec = self.record
        if arena.item_version != self._items_seen:
            # Objects only come to rest somewhere through a release or a teleport.
            self._items_seen = arena.item_version
            if rec.completed_at is None and self._delivered():
                rec.completed_at = round(arena.time, 6)
        if arena.time - self._last_sample >= 1.0 - 1e-9:
            self._last_sample = arena.time
            x, y, _ = arena.pose()
            rec.positions.append((round(arena.time, 6), x, y))

    def _delivered(self) -> bool:
        ax, ay = self.arena.beacons["a"]
        r2 = DELIVERY_RADIUS**2
        return all(
            it.present and not it.held and (it.x - ax) ** 2 + (it.y - ay) ** 2 <= r2 for it in self.arena.items.values()
        )

    # -- interventions (the studio's world commands are commands.py's, on this state) ----------------

    def note_intervention(self, what: str) -> dict[str, Any]:
        """Log an intervention by hand (shown in the plan panel) and return it as a reply."""
        self.interventions.append((self.t, what))
        return {"t": round(self.t * 1000), "done": what}

    def force_operator(self, op: str | None) -> None:
        """Run ``op``'s couplings whatever the monitor selects; None gives the monitor back the say."""
        if op is not None:
            self.dd.set_current_operator(op)  # validates before anything changes
        self.forced_op = op
        self._op_key = (-1, -1, -1, -1)  # re-read the monitor's choice (or the force) next tick

    def swap_model(self, model: DDModel) -> str | None:
        """Run ``model`` from now on, keeping α, actuators, slow variables, switches and the noise stream.

        Returns:
            None when swapped; else why not (other behavior, actuator or slow-variable names: the
            model runs after a reset).
        """
        old = self.dd
        om = old.model
        if (model.behaviors, model.actuators, model.slow) != (om.behaviors, om.actuators, om.slow):
            return "saved; the model names other behaviors, actuators or slow variables: Reset to run it"
        new = DDSystem(model, seed=self.seed, dt=self.dt, noise=old.noise)
        new.alpha, new.act, new.slow = old.alpha, old.act, old.slow
        new.rng, new.t, new.s, new.sigma_op, new.pinned = old.rng, old.t, old.s, old.sigma_op, old.pinned
        new.last = old.last
        self.dd = new
        _model.cache_clear()  # a reset builds from the file, which now holds this model
        return None

    def set_fact(self, fact: Fact, value: bool) -> None:
        """Set or clear a derived fact by hand; logged as a fact event with the cause ``by hand``."""
        deriver = self.deriver
        facts = set(deriver.facts)
        if value:
            facts.add(fact)
        else:
            facts.discard(fact)
        deriver.facts = self.facts = frozenset(facts)
        deriver.events.append(FactEvent(self.t, fact, value, {"rule": "by hand", "phase": "forced"}))
        self._next = None

    # -- perturbations ---------------------------------------------------------------------------

    def teleport(self, item: str, where: str | tuple[float, float], offset: tuple[float, float] = (0.0, 0.3)) -> None:
        """Put ``item`` at a beacon (plus ``offset``) or at (x, y); the robot is not told."""
        if isinstance(where, str):
            bx, by = self.arena.beacons[where]
            where = (bx + offset[0], by + offset[1])
        self.arena.teleport(item, *where)

    def remove(self, item: str) -> None:
        """Take ``item`` out of the world; the robot is not told."""
        self.arena.remove(item)

    def block_path(self, frm: str, to: str, width: float = 1.6, thickness: float = 0.2) -> Box:
        """Put a wall across the straight path between two beacons, halfway, and return it."""
        (x0, y0), (x1, y1) = self.arena.beacons[frm], self.arena.beacons[to]
        mx, my = (x0 + x1) / 2.0, (y0 + y1) / 2.0
        # An axis-aligned wall across the dominant direction of the path.
        box = Box(mx, my, thickness, width) if abs(x1 - x0) >= abs(y1 - y0) else Box(mx, my, width, thickness)
        self.arena.block(box)
        return box

    def place_robot(self, x: float, y: float, heading: float) -> None:
        """Move the robot; derived facts keep what they believed (they catch up from the sensors)."""
        self.arena.place_robot(x, y, heading)

    # -- scenes and debugging ----------------------------------------------------------------------

    def static_scene(self) -> Scene:
        """The arena in the studio's scene vocabulary (``xabsl_studio.engine.host``), in mm and degrees.

        Walls, obstacles (``rect`` shapes), beacons (a marker and the dashed circle within which
        the robot counts as at it), the robot's size and sensor geometry, the DD behaviors, the
        planning facts and the goal.
        """
        arena = self.arena
        g = arena.geom
        size = _mm(arena.layout.size)
        shapes: list[dict[str, Any]] = [_rect(b, "#6b5a4a") for b in arena.boxes]
        for name, (x, y) in arena.beacons.items():
            shapes.append(
                {"shape": "circle", "x": _mm(x), "y": _mm(y), "r": _mm(g.near), "stroke": BEACON, "dash": True}
            )
            shapes.append({"shape": "circle", "x": _mm(x), "y": _mm(y), "r": 150, "fill": BEACON, "label": name})
        return {
            "kind": "errands",
            "units": {"length": "mm", "angle": "deg", "time": "ms"},
            "field": {"x": [0, size], "y": [0, size]},
            "walls": [[_mm(a[0]), _mm(a[1]), _mm(b[0]), _mm(b[1])] for a, b in arena.walls],
            "shapes": shapes,
            "teams": [{"name": "errands", "color": "#1f6fd1"}],
            "agents": [{"name": a.name, "team": a.team, "number": a.number} for a in self._agents],
            "robot_radius": _mm(g.radius),
            "robot": {
                "radius": _mm(g.radius),
                "ray_angle": round(math.degrees(g.ray_angle), 3),
                "ray_range": _mm(g.ray_range),
                "near": _mm(g.near),
                "gripper_offset": _mm(g.gripper_offset),
            },
            "beacons": {k: [_mm(x), _mm(y)] for k, (x, y) in arena.beacons.items()},
            "behaviors": list(self.behaviors),
            "facts": list(self.task.facts),
            "goal": sorted(self.task.goal),
            # What the studio shows for this world beyond the field (generic panel names, see
            # docs/studio.md); the studio's world adds the commands it offers (commands.py).
            "panels": ["dynamics", "plan", "facts"],
            "dd": {
                "behaviors": list(self.behaviors),
                "actuators": list(self.dd.model.actuators),
                "theta": [round(v, 4) for v in self.dd.model.theta.tolist()],
                "terms": list(ALPHA_TERMS),
            },
        }

    def dynamic_scene(self) -> Scene:
        """What moves, in mm and degrees, plus what the robot's two layers are doing.

        ``robots``: the robot's pose; ``shapes``: obstacles added by a perturbation, the book and
        the mug (outlined while held), the two range-sensor rays up to what they hit and the
        gripper (filled while closing); ``objects``: name -> [x, y, held, present]; ``alpha``
        per DD behavior, ``s`` per operator, ``op``, ``plan_status``, derived ``facts`` and the
        simulator's ``truth``.
        """
        arena = self.arena
        g = arena.geom
        x, y, h = arena.pose()
        shapes: list[dict[str, Any]] = [_rect(b, "#8a3b2e") for b in arena.blocks]
        objects: dict[str, list[object]] = {}
        for name, item in arena.items.items():
            objects[name] = [_mm(item.x), _mm(item.y), item.held, item.present]
            if item.present:
                shape = {
                    "shape": "circle",
                    "x": _mm(item.x),
                    "y": _mm(item.y),
                    "r": 90,
                    "fill": ITEM_COLORS.get(name, "#ccc"),
                }
                shape["caption"] = name
                if item.held:
                    shape["stroke"] = "#ffffff"
                shapes.append(shape)
        sensors = self.sensors
        for side, sign in (("o_l", 1.0), ("o_r", -1.0)):
            reading = sensors.get(side, 0.0)
            angle = h + sign * g.ray_angle
            start = g.radius
            end = g.radius + g.ray_range * (1.0 - reading)
            cos, sin = math.cos(angle), math.sin(angle)
            shapes.append(
                {
                    "shape": "segment",
                    "x1": _mm(x + start * cos),
                    "y1": _mm(y + start * sin),
                    "x2": _mm(x + end * cos),
                    "y2": _mm(y + end * sin),
                    "stroke": "#ff5a4a" if reading > 0.0 else "rgba(255,255,255,0.35)",
                    "dash": reading <= 0.0,
                }
            )
        gx, gy = arena.gripper_point()
        actuators = self.dd.actuators
        closing = any(actuators.get("g_" + o, 0.0) > 0.5 for o in ITEMS)
        shapes.append(
            {
                "shape": "segment",
                "x1": _mm(x + g.radius * math.cos(h)),
                "y1": _mm(y + g.radius * math.sin(h)),
                "x2": _mm(gx),
                "y2": _mm(gy),
                "stroke": "#f0f0f0",
            }
        )
        shapes.append(
            {"shape": "circle", "x": _mm(gx), "y": _mm(gy), "r": 35, "stroke": "#f0f0f0"}
            | ({"fill": "#f0f0f0"} if closing else {})
        )
        return {
            "t": round(self.t * 1000),
            "robots": [[_mm(x), _mm(y), round(math.degrees(wrap(h)), 1)]],
            "shapes": shapes,
            "objects": objects,
            "alpha": [round(v, 4) for v in self.dd.alpha.tolist()],
            "s": {k: round(v, 4) for k, v in self.dd.s.items()},
            "op": self.operator,
            "plan_status": self.plan_status,
            "facts": sorted(self.facts),
            "truth": sorted(self.truth),
            "tentative": sorted(self.deriver.tentative),
            "fact_events": len(self.deriver.events),
            "plan_version": len(self.versions),
            "done": sorted(self.board.done),
            "forced_op": self.forced_op,
            "op_since": round(self._op_since * 1000),
            "op_timeout": self._op_timeout(),
            "interventions": len(self.interventions),
        } | self._dd_scene()

    def _op_timeout(self) -> int | None:
        """The monitor's timeout (ms) for the running operator's schema (its XABSL constant)."""
        op = self.operator
        if op is None or self.engine is None:
            return None
        const = self.engine.program.constants.get(op.split(" ", 1)[0] + "_timeout")
        return round(const.value) if const is not None else None

    def _dd_scene(self) -> Scene:
        """The last DD tick for the dynamics panel: Δα by term, drive u by source, actuator fusion.

        ``terms``: per term of :data:`ALPHA_TERMS`, one value per behavior: the increments of the
        tick (``relax`` = dt·λ(T − α), ``plan`` = Σ OCT dt·s·c·(Z − α), ``noise``) and the parts
        of the drive u = sensors + self + others + bias whose sigmoid is the target T.
        ``fusion``: per actuator, each behavior's α·λ·(m* − m) (1/s), ``decay`` and the value.
        """
        tick = self.dd.last
        if tick is None:
            return {}
        m = self.dd.model
        rows = _sparse_rows(m)
        prev = self._prev_tick
        # The record's own lists (no arrays: this runs for every sampled tick of the studio).
        now = tick.lists()
        alpha0: list[float] = prev.lists().alpha if prev is not None else m.alpha_init.tolist()
        feats = now.features
        n = m.n
        sensors = [sum(b * feats[j] for j, b in rows.b[i]) for i in range(n)]
        self_ex = [rows.w_self[i] * alpha0[i] for i in range(n)]
        others = [sum(w * alpha0[j] for j, w in rows.w_others[i]) for i in range(n)]
        plan = [0.0] * n
        for d in now.d_oct.values():
            plan = [a + b for a, b in zip(plan, d, strict=True)]
        parts = {
            "relax": now.d_relax,
            "plan": plan,
            "noise": now.d_noise,
            "T": now.T,
            "u": now.u,
            "sensors": sensors,
            "self": self_ex,
            "others": others,
            "bias": rows.bias,
        }
        shares = [[0.0] * n for _ in m.actuators]
        for p, c in enumerate(now.pair_contributions):
            shares[rows.pair_actuator[p]][rows.pair_behavior[p]] = c
        # One numpy rounding for all numbers (a hundred round() calls cost more than the rest).
        values = np.round(np.array(list(parts.values())), 5).tolist()
        fused = np.round(np.array(shares), 4).tolist()
        decay, acts = np.round(np.array([now.decay, now.actuators]), 4).tolist()
        return {
            "terms": dict(zip(parts, values, strict=True)),
            "fusion": {a: {"value": acts[j], "decay": decay[j], "shares": fused[j]} for j, a in enumerate(m.actuators)},
        }

    def status(self) -> Scene:
        """Plan progress, the delivered goals and the time, for the studio's top bar."""
        return {
            "time_ms": round(self.t * 1000),
            "finished": self.finished,
            "completed": self.completed,
            "completed_at": self.record.completed_at,
            "plan_status": self.plan_status,
            "reason": self.failure_reason(),
            "operators": list(self.record.completed),
            "replans": self.board.replans,
            "fact_agreement": self.agreement.to_json(),
        }

    def failure_reason(self) -> str:
        """Why the monitor failed, in words ("" unless plan.status is failed)."""
        if self.plan_status != "failed":
            return ""
        last = REASONS[self.out["plan.last_failure"]]
        if last == "no_plan":
            return self.board.reason or "no plan"
        causes = [f"{m[2] or '-'}: {m[3]}" for m in self.record.monitor if m[1] == "replanning"]
        return f"gave up after {self.board.replans} replans ({'; '.join(causes[-3:])})"

    def debug_frame(self) -> dict[str, Any]:
        """Everything about the last tick, as plain data (doc §4.3): the studio's debugger frame."""
        tick = self.dd.last
        m = self.dd.model
        frame: dict[str, Any] = {
            "t": round(self.t, 4),
            "sensors": {k: round(v, 4) for k, v in self.sensors.items()},
            "slow": dict(zip(m.slow, [round(v, 4) for v in self.dd.slow.tolist()], strict=True)),
            "alpha": dict(zip(m.behaviors, [round(v, 4) for v in self.dd.alpha.tolist()], strict=True)),
            "switches": {k: round(v, 4) for k, v in self.dd.s.items()},
            "actuators": {k: round(v, 4) for k, v in self.dd.actuators.items()},
            "facts": sorted(self.facts),
            "tentative": sorted(self.deriver.tentative),
            "truth": sorted(self.truth),
            "fact_events": [_event_json(e) for e in self.tick_events],
            "plan": self.board.to_json(),
            "monitor": {
                "status": self.plan_status,
                "op": self.operator,
                "last_failure": REASONS[self.out["plan.last_failure"]],
                "activation": self.engine.activation_dict() if self.engine is not None else [],
            },
            "ground_truth": {"robot": list(self.arena.pose()), "objects": self.arena.object_scene()},
        }
        if tick is not None:
            frame["activation_terms"] = {
                "T": _round(tick.T),
                "relax": _round(tick.d_relax),
                "noise": _round(tick.d_noise),
                "oct": {op: _round(v) for op, v in tick.d_oct.items()},
            }
            frame["fusion"] = {
                act: {
                    b: round(float(tick.contributions[i, j]), 4)
                    for i, b in enumerate(m.behaviors)
                    if tick.contributions[i, j] != 0.0
                }
                | {"decay": round(float(tick.decay[j]), 4)}
                for j, act in enumerate(m.actuators)
            }
        return frame


#: The per-behavior terms of a DD tick in the dynamic scene (see ``ErrandsWorld._dd_scene``).
ALPHA_TERMS = ("relax", "plan", "noise", "T", "u", "sensors", "self", "others", "bias")

#: Colours of the scene's shapes (the studio draws them as given).
BEACON = "#ffd54a"
ITEM_COLORS = {"book": "#b06ad9", "mug": "#36c3c9"}


def _mm(metres: float) -> int:
    return round(metres * 1000.0)


def _rect(box: Box, fill: str) -> dict[str, Any]:
    return {"shape": "rect", "x": _mm(box.x), "y": _mm(box.y), "w": _mm(box.w), "h": _mm(box.h), "fill": fill}


def _round(a: np.ndarray) -> list[float]:
    return [round(v, 5) for v in a.tolist()]


def _event_json(e: FactEvent) -> dict[str, Any]:
    return {"t": round(e.t, 3), "fact": e.fact, "value": e.value, "cause": dict(e.cause)}


def build_world(
    seed: int = 1, *, plan: bool = True, dt: float = 0.02, noise: float = 1.0, layout: ArenaLayout | None = None
) -> ErrandsWorld:
    """Build the errands world of doc §1.5 (robot near a, book at b, mug at c).

    Args:
        seed: DD noise seed; the same seed gives the same run.
        plan: with the XABSL plan monitor (True) or the reactive robot only.
        dt: behavior tick (s); the model's stability check must accept it.
        noise: multiplies the DD model's σ (0 = deterministic).
        layout: another arena.
    """
    return ErrandsWorld(seed, plan=plan, dt=dt, noise=noise, layout=layout)


def physics_rate(dt: float) -> tuple[int, int]:
    """The behavior rate for tick ``dt`` and the smallest physics rate ≥ 100 Hz it divides."""
    behavior_hz = round(1.0 / dt)
    if not math.isclose(behavior_hz * dt, 1.0, rel_tol=1e-9):
        raise ValueError(f"the behavior tick must divide one second, got dt={dt}")
    substeps = max(1, -(-100 // behavior_hz))
    return behavior_hz, behavior_hz * substeps


def run_world(
    world: ErrandsWorld,
    duration_s: float,
    on_tick: Callable[[Ms], bool | None] | None = None,
    stop_when_finished: bool = True,
) -> RunStats:
    """Run ``world`` headless for at most ``duration_s`` at its own tick.

    Rates the host loop accepts (30–50 Hz behavior, physics ≥ 100 Hz) go through
    :func:`xabsl_studio.engine.host.run_headless`; other ticks (dt = 10 ms for the numerics claims) use the
    same sense / execute / act / physics order in a local loop.
    """
    behavior_hz, physics_hz = physics_rate(world.dt)
    if 30 <= behavior_hz <= 50:
        return run_headless(world, duration_s, physics_hz, behavior_hz, on_tick, stop_when_finished)
    substeps = physics_hz // behavior_hz
    h = 1.0 / physics_hz
    agent = world.agents[0]
    ticks = max(0, -(-round(duration_s * behavior_hz * 1000) // 1000))
    stats = RunStats()
    wall = perf_counter()
    for k in range(ticks):
        if stop_when_finished and world.finished:
            break
        now = round(k * 1000 / behavior_hz)
        agent.sense(now)
        assert agent.controller is not None
        agent.controller.execute(now)
        agent.act(now)
        for _ in range(substeps):
            world.step(h)
        stats.ticks += 1
        stats.physics_steps += substeps
        if on_tick is not None and on_tick(now):
            break
    stats.sim_seconds = stats.physics_steps * h
    stats.wall_seconds = perf_counter() - wall
    return stats


def summary(world: ErrandsWorld) -> dict[str, Any]:
    """The run's outcome as plain data (what ``xabsl run examples/errands --json`` prints)."""
    rec = world.record
    return {
        "seed": world.seed,
        "plan": world.with_plan,
        "completed": world.completed,
        "time_s": rec.completed_at if rec.completed_at is not None else round(world.arena.time, 3),
        "sim_s": round(world.arena.time, 3),
        "plan_status": world.plan_status,
        "reason": world.failure_reason(),
        "operators": list(rec.started),
        "plans": [str(p) for p in world.board.plans],
        "replans": world.board.replans,
        "fact_agreement": round(world.agreement.fraction, 5),
        "fact_agreement_outside_lag": round(world.agreement.fraction_outside_lag, 5),
        "max_switches_on": rec.max_switches_on,
        "dominant_switches": rec.dominant_switches,
        "roam_share": round(rec.roam_dominant_ticks / rec.ticks, 4) if rec.ticks else 0.0,
        "beacon_arrivals": len(rec.arrivals),
        "beacons_visited": sorted(set(rec.arrivals)),
        "ever_held": rec.ever_held,
    }
