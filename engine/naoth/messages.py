"""The NaoTH debug messages this project reads and writes, as protobuf classes built at import.

NaoTH (Berlin United) serves its XABSL behavior on the debug port as protobuf messages of the
package ``naothmessages`` (proto2). The field numbers and types below are the project's own
definitions, written from the facts of NaoTH's published ``Messages.proto`` and
``Framework-Representations.proto`` (Apache-2.0); no NaoTH file is copied or installed.

Why not a ``.proto`` file and ``protoc``: the build machine has neither ``protoc`` nor
``grpcio-tools``, and generated ``_pb2`` modules pin the protobuf runtime version they were
generated for. The same definitions as data (:data:`MESSAGES`, read like a ``.proto``) become a
``FileDescriptorProto`` (``google.protobuf.descriptor_pb2``) and message classes
(``message_factory.GetMessageClass``), so encoding and decoding are protobuf's own, wire
compatible with the C++ and Java ends. :func:`proto_text` prints the definitions as ``.proto``
source (docs/naoth.md shows it).

What each message holds (docs/naoth.md):

* ``CMD{name, args}``, ``CMDArg{name, bytes}``: a debug command and its arguments;
* ``BehaviorStateComplete``: once per loaded behavior: enumerations, options with their states
  (target flags) and typed parameters, agents with their root options, the symbol tables with
  their values at load time;
* ``BehaviorStateSparse``: per frame: the agent, the active root actions as a tree, the symbols
  whose values differ from those at load time, the frame number, an error message;
* ``FrameInfo``: per frame of a game log: frame number and time (ms).
"""

from __future__ import annotations

from typing import Any

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from google.protobuf.message import DecodeError, Message

__all__ = [
    "MESSAGES",
    "PACKAGE",
    "ActionType",
    "DecodeError",
    "Message",
    "SymbolType",
    "message_class",
    "proto_text",
]

#: The protobuf package of NaoTH's messages (the type names on the wire of reflection tools).
PACKAGE = "naothmessages"

_F = descriptor_pb2.FieldDescriptorProto
_OPTIONAL, _REQUIRED, _REPEATED = _F.LABEL_OPTIONAL, _F.LABEL_REQUIRED, _F.LABEL_REPEATED
_TYPES = {
    "int32": _F.TYPE_INT32,
    "int64": _F.TYPE_INT64,
    "uint32": _F.TYPE_UINT32,
    "double": _F.TYPE_DOUBLE,
    "bool": _F.TYPE_BOOL,
    "string": _F.TYPE_STRING,
    "bytes": _F.TYPE_BYTES,
}


class SymbolType:
    """``XABSLSymbol.SymbolType``: the type of a symbol or parameter."""

    DECIMAL = 0
    BOOLEAN = 1
    ENUM = 2
    UNKNOWN = 3


class ActionType:
    """``XABSLActionSparse.ActionType``: what an active action is."""

    OPTION = 0
    BASIC_BEHAVIOR = 1
    SYMBOL_ASSIGNMENT = 2
    UNKNOWN = 3


#: Enumerations: qualified name -> (value name, number) in declaration order.
ENUMS: dict[str, tuple[tuple[str, int], ...]] = {
    "XABSLSymbol.SymbolType": (("Decimal", 0), ("Boolean", 1), ("Enum", 2), ("Unknown", 3)),
    "XABSLActionSparse.ActionType": (("Option", 0), ("BasicBehavior", 1), ("SymbolAssignement", 2), ("Unknown", 3)),
}

#: A field: (label, type or message/enum name, name, number, default or None).
Field = tuple[str, str, str, int, str | None]

#: Messages: qualified name (nested with ``.``) -> fields, as a ``.proto`` would declare them.
MESSAGES: dict[str, tuple[Field, ...]] = {
    "CMDArg": (("required", "string", "name", 1, None), ("optional", "bytes", "bytes", 3, None)),
    "CMD": (("required", "string", "name", 1, None), ("repeated", "CMDArg", "args", 2, None)),
    "FrameInfo": (("required", "uint32", "frameNumber", 1, None), ("required", "uint32", "time", 2, None)),
    "XABSLSymbol": (
        ("required", "int32", "id", 1, "-1"),
        ("required", "XABSLSymbol.SymbolType", "type", 2, "Unknown"),
        ("optional", "string", "name", 3, None),
        ("optional", "double", "decimalValue", 11, None),
        ("optional", "bool", "boolValue", 12, None),
        ("optional", "int32", "enumValue", 13, None),
        ("optional", "int32", "enumTypeId", 14, None),
    ),
    "XABSLActiveOptionSparse": (
        ("required", "int32", "id", 1, "-1"),
        ("optional", "int64", "timeOfExecution", 3, "0"),
        ("optional", "int32", "activeState", 4, None),
        ("optional", "int64", "stateTime", 5, None),
        ("repeated", "double", "decimalParameters", 6, None),
        ("repeated", "bool", "booleanParameters", 7, None),
        ("repeated", "int32", "enumeratedParameters", 8, None),
        ("repeated", "XABSLActionSparse", "activeSubActions", 9, None),
    ),
    "XABSLActionSparse": (
        ("required", "XABSLActionSparse.ActionType", "type", 2, "Unknown"),
        ("optional", "XABSLSymbol", "symbol", 3, None),
        ("optional", "XABSLActiveOptionSparse", "option", 4, None),
    ),
    "SymbolValueList": (
        ("repeated", "SymbolValueList.DoubleSymbol", "decimal", 1, None),
        ("repeated", "SymbolValueList.BooleanSymbol", "boolean", 2, None),
        ("repeated", "SymbolValueList.EnumSymbol", "enumerated", 3, None),
    ),
    "SymbolValueList.DoubleSymbol": (
        ("required", "int32", "id", 1, "-1"),
        ("optional", "string", "name", 2, None),
        ("optional", "double", "value", 3, None),
    ),
    "SymbolValueList.BooleanSymbol": (
        ("required", "int32", "id", 1, "-1"),
        ("optional", "string", "name", 2, None),
        ("optional", "bool", "value", 3, None),
    ),
    "SymbolValueList.EnumSymbol": (
        ("required", "int32", "id", 1, "-1"),
        ("optional", "string", "name", 2, None),
        ("optional", "int32", "value", 13, None),
        ("optional", "int32", "typeId", 14, None),
    ),
    "BehaviorStateSparse": (
        ("optional", "string", "agent", 1, None),
        ("repeated", "XABSLActionSparse", "activeRootActions", 2, None),
        ("optional", "SymbolValueList", "inputSymbolList", 10, None),
        ("optional", "SymbolValueList", "outputSymbolList", 11, None),
        ("optional", "uint32", "frameNumber", 5, None),
        ("optional", "string", "errorMessage", 6, None),
    ),
    "BehaviorStateComplete": (
        ("repeated", "BehaviorStateComplete.EnumType", "enumerations", 10, None),
        ("repeated", "BehaviorStateComplete.Option", "options", 11, None),
        ("repeated", "BehaviorStateComplete.Agent", "agents", 12, None),
        ("optional", "SymbolValueList", "inputSymbolList", 13, None),
        ("optional", "SymbolValueList", "outputSymbolList", 14, None),
        ("optional", "uint32", "frameNumber", 15, None),
    ),
    "BehaviorStateComplete.EnumType": (
        ("required", "string", "name", 1, None),
        ("repeated", "BehaviorStateComplete.EnumType.Element", "elements", 2, None),
    ),
    "BehaviorStateComplete.EnumType.Element": (
        ("required", "int32", "value", 1, None),
        ("required", "string", "name", 2, None),
    ),
    "BehaviorStateComplete.Option": (
        ("required", "string", "name", 1, None),
        ("repeated", "BehaviorStateComplete.Option.State", "states", 3, None),
        ("repeated", "XABSLSymbol", "parameters", 2, None),
    ),
    "BehaviorStateComplete.Option.State": (
        ("required", "string", "name", 1, None),
        ("optional", "bool", "target", 2, None),
    ),
    "BehaviorStateComplete.Agent": (
        ("required", "string", "name", 1, None),
        ("required", "string", "rootOption", 2, None),
    ),
}


def _children(parent: str) -> list[str]:
    depth = parent.count(".") + 1 if parent else 0
    return [n for n in MESSAGES if n.count(".") == depth and (not parent or n.startswith(parent + "."))]


def _fill(message: descriptor_pb2.DescriptorProto, name: str) -> None:
    message.name = name.rsplit(".", 1)[-1]
    for label, kind, field_name, number, default in MESSAGES[name]:
        field = message.field.add(name=field_name, number=number)
        field.label = {"required": _REQUIRED, "optional": _OPTIONAL, "repeated": _REPEATED}[label]
        if kind in _TYPES:
            field.type = _TYPES[kind]
        else:
            field.type = _F.TYPE_ENUM if kind in ENUMS else _F.TYPE_MESSAGE
            field.type_name = f".{PACKAGE}.{kind}"
        if default is not None:
            field.default_value = default
    for enum_name, values in ENUMS.items():
        if enum_name.rsplit(".", 1)[0] == name:
            enum = message.enum_type.add(name=enum_name.rsplit(".", 1)[-1])
            for value_name, number in values:
                enum.value.add(name=value_name, number=number)
    for child in _children(name):
        _fill(message.nested_type.add(), child)


def _build() -> dict[str, type[Message]]:
    file = descriptor_pb2.FileDescriptorProto(name="xabsl_studio_naoth.proto", package=PACKAGE, syntax="proto2")
    for name in _children(""):
        _fill(file.message_type.add(), name)
    pool = descriptor_pool.DescriptorPool()
    pool.Add(file)
    return {name: message_factory.GetMessageClass(pool.FindMessageTypeByName(f"{PACKAGE}.{name}")) for name in MESSAGES}


_CLASSES = _build()


def message_class(name: str) -> type[Message]:
    """The protobuf class of message ``name`` (``"BehaviorStateSparse"``, ``"CMD"``, nested with ``.``).

    Raises:
        KeyError: no such message.
    """
    return _CLASSES[name]


def new(name: str, /, **fields: Any) -> Any:
    """A new message ``name`` with ``fields`` set (typed ``Any``: protobuf classes are built at run time)."""
    return _CLASSES[name](**fields)


def parse(name: str, data: bytes, /) -> Any:
    """Message ``name`` decoded from ``data`` (required fields not checked: a robot may leave them out).

    Raises:
        DecodeError: ``data`` is not a message of that type.
    """
    message = _CLASSES[name]()
    message.ParseFromString(data)  # proto2 required fields are checked by IsInitialized, not here
    return message


def proto_text() -> str:
    """The definitions as ``.proto`` source (proto2), for docs and for comparing with NaoTH's file."""
    lines = ['syntax = "proto2";', f"package {PACKAGE};", ""]

    def emit(name: str, indent: str) -> None:
        lines.append(f"{indent}message {name.rsplit('.', 1)[-1]} {{")
        for enum_name, values in ENUMS.items():
            if enum_name.rsplit(".", 1)[0] == name:
                lines.append(f"{indent}  enum {enum_name.rsplit('.', 1)[-1]} {{")
                lines.extend(f"{indent}    {v} = {n};" for v, n in values)
                lines.append(f"{indent}  }}")
        for child in _children(name):
            emit(child, indent + "  ")
        for label, kind, field_name, number, default in MESSAGES[name]:
            extra = f" [default = {default}]" if default is not None else ""
            lines.append(f"{indent}  {label} {kind} {field_name} = {number}{extra};")
        lines.append(f"{indent}}}")

    for name in _children(""):
        emit(name, "")
        lines.append("")
    return "\n".join(lines)
