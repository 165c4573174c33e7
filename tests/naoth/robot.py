"""A NaoTH-like robot for the tests: our engine behind NaoTH's debug port and game-log format.

It is the other end of ``xabsl attach naoth://`` and ``xabsl import naoth``, written from the
wire facts of docs/naoth.md and independent of the studio's client code: its own socket loop
and framing, its own log writer, and its own *engine indices*, chosen to differ from our
compiler's order so that a join by position would fail (options in reverse name order, each
typed symbol array in reverse declaration order, enum host values 10*i+7, basic behaviors in
registration order). Messages are encoded by protobuf from the project's message definitions
(``xabsl_studio.engine.naoth.messages``, protobuf's own encoder).

Frames are deterministic: the robot advances ``--step`` frames of 33 ms per sparse request
(``--step 3`` leaves gaps of two frames between answers) until frame ``--frames``, then
answers with that frame again (as a robot polled faster than it runs does); an agent switch or
a reload grants ``--frames`` more. Tests need no timing. Every frame
it served (and, with ``--log``, every frame of the log) goes as the truth to ``--truth FILE``,
one JSON line per frame with names and values as the engine had them::

    python tests/naoth/robot.py serve --port 0 --truth truth.jsonl
    python tests/naoth/robot.py log game.log --frames 120 --truth truth.jsonl

``serve`` prints ``listening on PORT`` once it listens.
"""

from __future__ import annotations

import argparse
import math
import socket
import struct
import sys
from pathlib import Path
from typing import IO, Any

import orjson

from xabsl_studio.engine.ir.ic_reader import read_ic
from xabsl_studio.engine.ir.model import Assignment, Program
from xabsl_studio.engine.lang import compile_file
from xabsl_studio.engine.naoth import messages as M
from xabsl_studio.engine.runtime import BasicBehavior, Bindings, Engine
from xabsl_studio.engine.types import Kind

BEHAVIOR = Path(__file__).resolve().parent / "behavior" / "agents.xabsl"
FRAME_MS = 33
_KINDS = {Kind.DECIMAL: "decimal", Kind.BOOLEAN: "boolean", Kind.ENUM: "enumerated"}
_TYPES = {Kind.DECIMAL: M.SymbolType.DECIMAL, Kind.BOOLEAN: M.SymbolType.BOOLEAN, Kind.ENUM: M.SymbolType.ENUM}


class Robot:
    """The body, the engine and the robot's own indices of the loaded behavior."""

    def __init__(self, program: Program, agent: str) -> None:
        self.frame = 0
        #: the frame the robot stops at, and how many more an agent switch or a reload grants
        self.limit = 10**9
        self.frames = 0
        self.last: Any = None
        self.declarations = program
        self.ball = 1400.0
        self.kicks = 0
        self.load(program, agent)

    # -- the world ------------------------------------------------------------------------------

    def bindings(self, program: Program) -> Bindings:
        b = Bindings()
        for name, enum in program.enums.items():
            b.enum(name, {element: 10 * i + 7 for i, element in enumerate(enum.elements)})
        reads = {
            "game.state": lambda: self.engine.enum_value("game.state." + ("ready" if self.frame < 5 else "playing")),
            "ball.was_seen": lambda: (self.frame // 40) % 3 != 2,
            "ball.distance": lambda: self.ball,
            "ball.angle": lambda: round(20.0 * math.sin(self.frame / 7.0), 6),
        }
        for symbol in program.inputs.values():
            b.input(symbol.name, symbol.kind, reads[symbol.name], enum=symbol.enum)
        for symbol in program.outputs.values():
            if not symbol.internal:
                initial = {Kind.DECIMAL: 0.0, Kind.BOOLEAN: False}.get(symbol.kind)
                b.output(symbol.name, symbol.kind, enum=symbol.enum, initial=initial)
        robot = self

        class KickBall(BasicBehavior):
            name = "kick_ball"
            parameters = (("strength", Kind.DECIMAL), ("fallback", Kind.ENUM))

            def execute(self) -> None:
                robot.kicks += 1
                robot.ball = 1400.0

        if "kick_ball" in program.behaviors:
            b.behavior(KickBall)
        return b

    def load(self, program: Program, agent: str) -> None:
        self.program = program
        self.engine = Engine(self.bindings(program), program)
        self.engine.root_actions.select_agent(agent)
        self.agent = agent
        # The robot engine's own arrays (see the module docstring).
        self.options = sorted(program.options, reverse=True)
        self.inputs = {k: [s for s in program.inputs.values() if s.kind is k and not s.params][::-1] for k in _KINDS}
        self.outputs = {k: [s for s in program.outputs.values() if s.kind is k][::-1] for k in _KINDS}
        self.enums = list(program.enums)
        self.complete_frame = self.frame
        self.load_values = (self.values(self.inputs, True), self.values(self.outputs, False))
        self.complete = self.build_complete()

    def step(self) -> None:
        self.frame += 1
        if self.engine.output("motion.type") == self.engine.enum_value("motion.type.walk"):
            self.ball = max(0.0, self.ball - 60.0)
        self.engine.execute(self.frame * FRAME_MS)

    # -- messages -------------------------------------------------------------------------------

    def values(self, table: dict[Kind, list[Any]], inputs: bool) -> dict[Kind, list[Any]]:
        read = (lambda s: self.engine.input_reads[s.name]()) if inputs else (lambda s: self.engine.output(s.name))
        return {kind: [read(s) for s in symbols] for kind, symbols in table.items()}

    def fill_list(self, target: Any, table: dict[Kind, list[Any]], values: dict[Kind, list[Any]], only: Any) -> None:
        for kind, symbols in table.items():
            for i, symbol in enumerate(symbols):
                value = values[kind][i]
                if only is not None and only[kind][i] == value:
                    continue
                entry = getattr(target, _KINDS[kind]).add(id=i, value=value)
                if only is None:
                    entry.name = symbol.name
                    if kind is Kind.ENUM:
                        entry.typeId = self.enums.index(symbol.enum)

    def build_complete(self) -> Any:
        m = M.new("BehaviorStateComplete", frameNumber=self.complete_frame)
        for name in self.enums:
            enum = m.enumerations.add(name=name)
            for element in self.program.enums[name].elements:
                enum.elements.add(value=self.engine.enum_value(element), name=element)
        for name in self.options:
            option = self.program.options[name]
            entry = m.options.add(name=name)
            for state in option.states:
                entry.states.add(name=state.name, target=state.target)
            for kind in _KINDS:  # per type, in declaration order (the engine's parameter arrays)
                typed = [p for p in option.params if p.kind is kind]
                for j, parameter in enumerate(typed):
                    p = entry.parameters.add(id=j, type=_TYPES[kind], name=parameter.name)
                    if kind is Kind.ENUM:
                        p.enumTypeId = self.enums.index(parameter.enum or "")
        for agent in self.program.agents:
            m.agents.add(name=agent.name, rootOption=agent.root)
        self.fill_list(m.inputSymbolList, self.inputs, self.load_values[0], None)
        self.fill_list(m.outputSymbolList, self.outputs, self.load_values[1], None)
        return m

    def build_sparse(self) -> tuple[Any, dict[str, Any]]:
        """This frame's sparse message and its truth (names and values as the engine has them)."""
        m = M.new("BehaviorStateSparse", agent=self.agent, frameNumber=self.frame)
        nodes = self.engine.path()
        truth_path: list[list[Any]] = []
        position = [0]

        def params_of(node_params: list[Any], declared: Any, body: Any) -> list[Any]:
            shown = []
            for parameter, value in zip(declared, node_params, strict=True):
                {Kind.DECIMAL: body.decimalParameters, Kind.BOOLEAN: body.booleanParameters}.get(
                    parameter.kind, body.enumeratedParameters
                ).append(value)
                shown.append(self.engine.enum_element(parameter.enum, value) if parameter.kind is Kind.ENUM else value)
            return shown

        def emit(parent: Any) -> None:
            node = nodes[position[0]]
            position[0] += 1
            action = parent.add()
            if node[0] == 1:
                behavior = list(self.program.behaviors.values())[node[2]]
                action.type = M.ActionType.BASIC_BEHAVIOR
                action.option.id = list(self.program.behaviors).index(behavior.name)
                action.option.timeOfExecution = node[3]
                shown = params_of(node[4], behavior.params, action.option)
                truth_path.append(["behavior", node[1], behavior.name, node[3], shown])
                return
            option = next(o for o in self.program.options.values() if o.index == node[2])
            state = option.states[node[3]]
            action.type = M.ActionType.OPTION
            body = action.option
            body.id = self.options.index(option.name)
            body.timeOfExecution, body.activeState, body.stateTime = node[4], node[3], node[5]
            shown = params_of(node[8], option.params, body)
            truth_path.append(["option", node[1], option.name, state.name, node[4], node[5], shown])
            for child in state.actions:
                if isinstance(child, Assignment):
                    symbol = self.program.outputs[child.symbol]
                    a = body.activeSubActions.add(type=M.ActionType.SYMBOL_ASSIGNMENT)
                    a.symbol.type = _TYPES[symbol.kind]
                    a.symbol.id = self.outputs[symbol.kind].index(symbol)
                    value = self.engine.output(symbol.name)
                    if symbol.kind is Kind.DECIMAL:
                        a.symbol.decimalValue = value
                    elif symbol.kind is Kind.BOOLEAN:
                        a.symbol.boolValue = value
                    else:
                        a.symbol.enumValue = value
                        a.symbol.enumTypeId = self.enums.index(symbol.enum or "")
                else:
                    emit(body.activeSubActions)

        while position[0] < len(nodes):
            emit(m.activeRootActions)
        ins, outs = self.values(self.inputs, True), self.values(self.outputs, False)
        self.fill_list(m.inputSymbolList, self.inputs, ins, self.load_values[0])
        self.fill_list(m.outputSymbolList, self.outputs, outs, self.load_values[1])
        truth = {"frame": self.frame, "agent": self.agent, "path": truth_path}
        for name, table, values in (("inputs", self.inputs, ins), ("outputs", self.outputs, outs)):
            truth[name] = {
                s.name: self.engine.enum_element(s.enum, values[k][i]) if k is Kind.ENUM else values[k][i]
                for k, symbols in table.items()
                for i, s in enumerate(symbols)
            }
        return m, truth


# -- the debug port -----------------------------------------------------------------------------


def read_exactly(sock: socket.socket, size: int) -> bytes:
    data = b""
    while len(data) < size:
        chunk = sock.recv(size - len(data))
        if not chunk:
            raise ConnectionError("client closed")
        data += chunk
    return data


def answer(robot: Robot, command: Any, config: Path, step: int, truth: IO[bytes] | None) -> bytes:
    args = {a.name: a.bytes for a in command.args}
    name = command.name
    if name == "Cognition:representation:get":
        if "BehaviorStateComplete" in args:
            return bytes(robot.complete.SerializeToString())
        if "BehaviorStateSparse" in args:
            if robot.frame + step > robot.limit and robot.last is not None:
                return bytes(robot.last.SerializeToString())  # no new frame yet
            for _ in range(step):
                robot.step()
            sparse, shown = robot.build_sparse()
            robot.last = sparse
            if truth is not None:
                truth.write(orjson.dumps(shown) + b"\n")
                truth.flush()
            return bytes(sparse.SerializeToString())
        return b"unknown representation"
    if name == "Cognition:behavior:list_agents":
        return "\n".join(a.name for a in robot.program.agents).encode()
    if name == "Cognition:behavior:get_agent":
        return robot.agent.encode()
    if name == "Cognition:behavior:set_agent":
        agent = args.get("agent", b"").decode()
        if agent not in {a.name for a in robot.program.agents}:
            return f'agent not found:  "{agent}"'.encode()
        robot.agent = agent
        robot.engine.root_actions.select_agent(agent)
        robot.limit += robot.frames
        return f'resetted agent to "{agent}"'.encode()
    if name == "Cognition:file::write":
        path = config / Path(args.get("path", b"").decode()).name
        path.write_bytes(args.get("content", b""))
        return b"written"
    if name == "Cognition:behavior:reload":
        try:
            # the host's own declarations (every enum element its symbol code registers) stay
            ic = (config / "behavior-ic.dat").read_text(encoding="latin-1")
            program = read_ic(ic, robot.declarations)
            robot.load(program, robot.agent)
            robot.limit += robot.frames
        except Exception as error:  # the robot answers with the error text, as NaoTH's does
            return f"XABSL error: {error}".encode()
        return b"behavior reloaded"
    return f"unknown command {name}".encode()


def serve(args: argparse.Namespace) -> int:
    program = compile_file(args.behavior).program
    assert program is not None
    robot = Robot(program, args.agent)
    robot.declarations = program
    robot.frames = robot.limit = args.frames
    config = Path(args.config)
    config.mkdir(parents=True, exist_ok=True)
    truth = open(args.truth, "ab") if args.truth else None  # noqa: SIM115 -- open for the process's life
    server = socket.create_server(("127.0.0.1", args.port))
    print(f"listening on {server.getsockname()[1]}", flush=True)
    while True:
        client, _ = server.accept()  # one client at a time, as the robot's debug server
        client.settimeout(5.0)  # a client silent for 5 s is dropped, as a robot drops it
        try:
            while True:
                (ident,) = struct.unpack("<i", read_exactly(client, 4))
                if ident == -1:
                    continue  # heartbeat
                (size,) = struct.unpack("<i", read_exactly(client, 4))
                command = M.parse("CMD", read_exactly(client, size))
                payload = answer(robot, command, config, args.step, truth)
                client.sendall(struct.pack("<iI", ident, len(payload)) + payload)
        except (ConnectionError, OSError):
            client.close()


# -- game logs ----------------------------------------------------------------------------------


def record(out: IO[bytes], frame: int, name: str, message: Any) -> None:
    data = message.SerializeToString()
    out.write(struct.pack("<i", frame) + name.encode() + b"\0" + struct.pack("<i", len(data)) + data)


def write_log(args: argparse.Namespace) -> int:
    program = compile_file(args.behavior).program
    assert program is not None
    robot = Robot(program, args.agent)
    truth = open(args.truth, "wb") if args.truth else None  # noqa: SIM115
    with open(args.log, "wb") as out:
        for i in range(args.frames):
            if i and args.agent_switch and i == args.agent_switch:
                robot.agent = "looker"
                robot.engine.root_actions.select_agent("looker")
            robot.step()
            record(
                out, robot.frame, "FrameInfo", M.new("FrameInfo", frameNumber=robot.frame, time=robot.frame * FRAME_MS)
            )
            if i == 0:
                robot.complete.frameNumber = robot.frame
                record(out, robot.frame, "BehaviorStateComplete", robot.complete)
            sparse, shown = robot.build_sparse()
            record(out, robot.frame, "BehaviorStateSparse", sparse)
            if truth is not None:
                truth.write(orjson.dumps(shown) + b"\n")
            if args.gap and i % args.gap == args.gap - 1:
                robot.frame += 1  # a frame the logger skipped
    if truth is not None:
        truth.close()
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = parser.add_subparsers(dest="mode", required=True)
    s = sub.add_parser("serve")
    s.add_argument("--port", type=int, default=0)
    s.add_argument("--step", type=int, default=1)
    s.add_argument("--frames", type=int, default=10**9, help="stop running at this frame (more per switch/reload)")
    s.add_argument("--config", default="Config")
    l = sub.add_parser("log")  # noqa: E741
    l.add_argument("log")
    l.add_argument("--frames", type=int, default=100)
    l.add_argument("--gap", type=int, default=0, help="skip one frame after every this many")
    l.add_argument("--agent-switch", type=int, default=0, help="switch to the looker agent at this frame")
    for p in (s, l):
        p.add_argument("--behavior", default=str(BEHAVIOR))
        p.add_argument("--agent", default="soccer")
        p.add_argument("--truth", default=None)
    args = parser.parse_args(argv)
    return serve(args) if args.mode == "serve" else write_log(args)


if __name__ == "__main__":
    sys.exit(main())
