"""The protocol's shared vocabulary: value, id and time types, the activation-path node layout.

Used by every message module (``commands``, ``replies``, ``host``); the strictness rules that
validate client messages live here once. The activation-path node layout is the engine's
(``xabsl_studio.engine.runtime.activation.compact_path``): :data:`OptionNode` and :data:`BehaviorNode`
describe it and the ``*_INDEX`` constants name its positions, so no other module indexes a node
by a bare number.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BeforeValidator, ConfigDict, Field

from xabsl_studio.server.protocol.errors import ServerError

#: Client messages are strict: a string is not a number, a float is not an integer, a bool is
#: neither; JSON numbers must be finite; a field the message type does not have is an error (a
#: typo must not be ignored).
STRICT = ConfigDict(strict=True, allow_inf_nan=False, extra="forbid")

#: Server messages are never validated in production; tests validate real ones against these
#: dataclasses, and a key the server sends that a dataclass does not declare must fail them.
SCHEMA = ConfigDict(extra="forbid")


def _integral(value: object) -> object:
    """``3.0`` -> ``3``: JSON (and JSON Schema's ``integer``) does not tell 3.0 from 3; 3.5 stays a float."""
    return int(value) if isinstance(value, float) and value.is_integer() else value


# Integer arguments take an integral JSON number: ``3`` or ``3.0``, not ``3.5``, ``"3"`` or ``true``
# (the bounds come before the validator so that they stay in the JSON Schema).
INTEGRAL = BeforeValidator(_integral)
#: The largest integer a command accepts (64-bit, as the engine's integers and JSON readers).
MAX_INT = 2**63 - 1
Int64 = Annotated[int, Field(ge=-MAX_INT - 1, le=MAX_INT)]
#: A number in a command: finite (``allow_inf_nan``), an integer within 64 bits.
Number = Int64 | float
#: A parameter or input value in a command: a number, a boolean, or an enum element (its index is
#: a number; its qualified name, ``"game.state.playing"``, a string).
CommandValue = bool | Int64 | float | str


def _not_integer(value: object) -> object:
    """An integer is no float id: one beyond 64 bits would come back rounded, not as it was sent."""
    if isinstance(value, int) and not isinstance(value, bool):
        raise ValueError("an integer id must fit in 64 bits")
    return value


#: A command's client-chosen id, echoed in its reply.
CommandId = Int64 | Annotated[float, BeforeValidator(_not_integer)] | str
#: A robot id: its index in ``hello.structure.robots``.
RobotId = Annotated[int, Field(ge=0, le=2**31), INTEGRAL]
#: An option, basic behavior or symbol by id (the program JSON's) or by name.
Ref = Annotated[int, Field(ge=0, le=2**31), INTEGRAL] | str
#: Behavior time in ms.
Ms = Annotated[int, Field(ge=0, le=2**62), INTEGRAL]

#: ``host_gone`` / ``host_back``: a host of an attached session went away / attached again (docs/attach.md)
HelloReason = Literal["connect", "reload", "reset", "resync", "fork", "host_gone", "host_back"]


class ProtocolError(ServerError, ValueError):
    """A client message that cannot be carried out; its text goes into the error reply."""


#: A symbol or parameter value in a frame: decimals rounded, enums as element indices (-1: none),
#: null when the host value cannot be shown (NaN).
WireValue = bool | int | float | None

#: ``[0, depth, option_id, state_id, option_time, state_time, decided_in_state_id, leaf_id, [params]]``
OptionNode = tuple[Literal[0], int, int, int, int, int, int, int, list[WireValue]]
#: ``[1, depth, behavior_id, time_of_execution, [params]]``
BehaviorNode = tuple[Literal[1], int, int, int, list[WireValue]]
PathNode = OptionNode | BehaviorNode
#: Positions in a node (both kinds): kind, depth, option or basic behavior id.
KIND_INDEX, DEPTH_INDEX, ID_INDEX = 0, 1, 2
#: Position of the parameter values in an option node and in a basic behavior node.
OPTION_PARAMS_INDEX, BEHAVIOR_PARAMS_INDEX = 8, 4
