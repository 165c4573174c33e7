"""The NaoTH message definitions against the wire facts, byte by byte, and the debug-port framing.

The expected bytes are written here by a small protobuf encoder of the test's own (tags, varints,
fixed64 doubles, length-delimited fields) from the field numbers and types of NaoTH's published
``Messages.proto``, not by the definitions under test; protobuf's own decoder must read them back
and protobuf's own encoder must produce them.
"""

from __future__ import annotations

import struct

import pytest

from xabsl_studio.engine.naoth import messages as M
from xabsl_studio.server.protocol.attach import WireError
from xabsl_studio.server.protocol.naoth import (
    HEARTBEAT,
    MAX_ID,
    ReplyReader,
    encode_command,
    next_id,
    parse_naoth_address,
)


def varint(value: int) -> bytes:
    if value < 0:
        value += 1 << 64  # int32/int64 negatives: ten bytes, two's complement
    out = bytearray()
    while True:
        byte = value & 0x7F
        value >>= 7
        if value:
            out.append(byte | 0x80)
        else:
            out.append(byte)
            return bytes(out)


def key(number: int, wire: int) -> bytes:
    return varint(number << 3 | wire)


def vint(number: int, value: int) -> bytes:
    return key(number, 0) + varint(value)


def double(number: int, value: float) -> bytes:
    return key(number, 1) + struct.pack("<d", value)


def nested(number: int, payload: bytes) -> bytes:
    return key(number, 2) + varint(len(payload)) + payload


def text(number: int, value: str) -> bytes:
    return nested(number, value.encode())


def test_a_sparse_frame_decodes_and_encodes_as_the_published_fields_say() -> None:
    # XABSLActiveOptionSparse{id=1, timeOfExecution=3, activeState=4, stateTime=5, decimal=6,
    # boolean=7, enumerated=8, activeSubActions=9}; XABSLActionSparse{type=2, symbol=3, option=4}
    assignment = vint(2, 2) + nested(3, vint(1, 1) + vint(2, 2) + vint(13, 17) + vint(14, 0))
    behavior = vint(2, 1) + nested(4, vint(1, 0) + vint(3, 99) + double(6, 1.0) + vint(8, 7))
    option = vint(1, 4) + vint(3, 1815) + vint(4, 1) + vint(5, 99) + double(6, 150.0) + vint(7, 1) + vint(8, 27)
    option += nested(9, assignment) + nested(9, behavior)
    root = vint(2, 0) + nested(4, option)
    # SymbolValueList{decimal=1{id=1, value=3}, boolean=2{id=1, value=3}, enumerated=3{id=1, value=13}}
    inputs = nested(1, vint(1, 2) + double(3, -4.25)) + nested(2, vint(1, 0) + vint(3, 1))
    outputs = nested(3, vint(1, 1) + vint(13, 27))
    # BehaviorStateSparse{agent=1, activeRootActions=2, inputSymbolList=10, outputSymbolList=11,
    # frameNumber=5, errorMessage=6}
    wire = text(1, "soccer") + nested(2, root) + vint(5, 4242) + nested(10, inputs) + nested(11, outputs)

    sparse = M.parse("BehaviorStateSparse", wire)
    assert sparse.agent == "soccer" and sparse.frameNumber == 4242
    body = sparse.activeRootActions[0].option
    assert (body.id, body.timeOfExecution, body.activeState, body.stateTime) == (4, 1815, 1, 99)
    assert list(body.decimalParameters) == [150.0] and list(body.booleanParameters) == [True]
    assert list(body.enumeratedParameters) == [27]
    kinds = [a.type for a in body.activeSubActions]
    assert kinds == [M.ActionType.SYMBOL_ASSIGNMENT, M.ActionType.BASIC_BEHAVIOR]
    assert body.activeSubActions[0].symbol.enumValue == 17
    assert body.activeSubActions[1].option.timeOfExecution == 99
    assert sparse.inputSymbolList.decimal[0].id == 2 and sparse.inputSymbolList.decimal[0].value == -4.25
    assert sparse.outputSymbolList.enumerated[0].value == 27

    built = M.new("BehaviorStateSparse", agent="soccer")
    built.activeRootActions.add().CopyFrom(sparse.activeRootActions[0])
    built.frameNumber = 4242
    built.inputSymbolList.CopyFrom(sparse.inputSymbolList)
    built.outputSymbolList.CopyFrom(sparse.outputSymbolList)
    assert built.SerializeToString() == wire  # protobuf writes fields in number order, as here


def test_a_complete_message_carries_names_states_parameters_agents_and_load_values() -> None:
    # BehaviorStateComplete{enumerations=10{name=1, elements=2{value=1, name=2}}, options=11{name=1,
    # parameters=2 (XABSLSymbol{id=1, type=2, name=3, enumTypeId=14}), states=3{name=1, target=2}},
    # agents=12{name=1, rootOption=2}, inputSymbolList=13, outputSymbolList=14, frameNumber=15}
    enum = text(1, "motion.type") + nested(2, vint(1, 7) + text(2, "motion.type.stand"))
    option = text(1, "go_to_ball") + nested(2, vint(1, 0) + vint(2, 2) + text(3, "go_to_ball.head") + vint(14, 0))
    option += nested(3, text(1, "approach") + vint(2, 0)) + nested(3, text(1, "kick") + vint(2, 1))
    agent = text(1, "soccer") + text(2, "play_soccer")
    inputs = nested(1, vint(1, 0) + text(2, "ball.distance") + double(3, 1400.0))
    wire = nested(10, enum) + nested(11, option) + nested(12, agent) + nested(13, inputs) + vint(15, 12)
    complete = M.parse("BehaviorStateComplete", wire)
    assert complete.enumerations[0].elements[0].value == 7
    assert [(s.name, s.target) for s in complete.options[0].states] == [("approach", False), ("kick", True)]
    assert complete.options[0].parameters[0].type == M.SymbolType.ENUM
    assert (complete.agents[0].name, complete.agents[0].rootOption) == ("soccer", "play_soccer")
    assert complete.inputSymbolList.decimal[0].name == "ball.distance" and complete.frameNumber == 12
    assert complete.SerializeToString() == wire


def test_commands_are_framed_as_the_robot_reads_them() -> None:
    data = encode_command(7, "Cognition:behavior:set_agent", {"agent": "goalie"})
    # CMD{name=1, args=2 (CMDArg{name=1, bytes=3})}
    payload = text(1, "Cognition:behavior:set_agent") + nested(2, text(1, "agent") + nested(3, b"goalie"))
    assert data == struct.pack("<ii", 7, len(payload)) + payload
    assert HEARTBEAT == b"\xff\xff\xff\xff"
    assert next_id(MAX_ID) == 1 and next_id(41) == 42
    with pytest.raises(ValueError, match="not in 1"):
        encode_command(0, "x")


def test_answers_are_cut_at_their_size_and_bounded() -> None:
    reader = ReplyReader(limit=100)
    stream = struct.pack("<iI", 3, 5) + b"hello" + struct.pack("<iI", 4, 0) + struct.pack("<iI", 5, 3) + b"ab"
    assert reader.feed(stream[:6]) == []
    assert reader.feed(stream[6:]) == [(3, b"hello"), (4, b"")]
    assert reader.feed(b"c") == [(5, b"abc")]
    with pytest.raises(WireError, match="answer of 101 bytes"):
        ReplyReader(limit=100).feed(struct.pack("<iI", 1, 101))


@pytest.mark.parametrize(
    ("text", "address"),
    [
        ("naoth://10.0.4.91", ("10.0.4.91", 5401)),
        ("naoth://nao91:5402", ("nao91", 5402)),
        ("naoth://[::1]", ("::1", 5401)),
        ("naoth://[::1]:7000/", ("::1", 7000)),
    ],
)
def test_addresses(text: str, address: tuple[str, int]) -> None:
    assert parse_naoth_address(text) == address


@pytest.mark.parametrize("text", ["10.0.4.91:5401", "naoth://", "naoth://a:", "naoth://a:99999", "naoth://a:x"])
def test_bad_addresses(text: str) -> None:
    with pytest.raises(ValueError, match=r"naoth://|port"):
        parse_naoth_address(text)


def test_the_definitions_print_as_proto_source() -> None:
    source = M.proto_text()
    assert "message BehaviorStateSparse {" in source
    assert "optional SymbolValueList inputSymbolList = 10;" in source
    assert "repeated XABSLActionSparse activeSubActions = 9;" in source
