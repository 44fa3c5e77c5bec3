"""Parsed interface definitions: the .msg/.srv/.action parser and the field tables conversion runs on.

Internal keys are ``pkg/msg/Name`` for messages in both dialects, ``pkg/srv/<part>`` for service requests and
responses (ROS 2 ``AddTwoInts_Request``, ROS 1 ``AddTwoIntsRequest``) and ``pkg/action/<part>`` for the ROS 2
action parts (``Fibonacci_Goal``, ``Fibonacci_FeedbackMessage``, ...). ROS 1 actions become plain messages, as
genaction generates them.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from enum import IntEnum
from typing import Any, Literal

__all__ = [
    "Cat",
    "ConstantSpec",
    "DefinitionError",
    "FieldSpec",
    "MessageSpec",
    "ParsedTable",
    "parse_table",
]

Dialect = Literal["ros1", "ros2"]


class DefinitionError(ValueError):
    """A definition text of ours is malformed (a bug in ``definitions.py``, never a client's fault)."""


class Cat(IntEnum):
    """What kind of value a field holds, which decides how it converts."""

    BOOL = 0
    INT = 1
    FLOAT = 2
    STRING = 3
    OCTET = 4  # ROS 2 ``byte`` (IDL octet): JSON int, Python bytes of length 1
    TIME = 5
    DURATION = 6
    MSG = 7


_INT_RANGES: dict[str, tuple[int, int]] = {
    "int8": (-(2**7), 2**7 - 1),
    "uint8": (0, 2**8 - 1),
    "int16": (-(2**15), 2**15 - 1),
    "uint16": (0, 2**16 - 1),
    "int32": (-(2**31), 2**31 - 1),
    "uint32": (0, 2**32 - 1),
    "int64": (-(2**63), 2**63 - 1),
    "uint64": (0, 2**64 - 1),
}
# ROS 1 byte is int8 and char is uint8 on the wire (genpy packs them as 'b' and 'B').
_ROS1_ALIASES = {"byte": "int8", "char": "uint8"}
# ROS 2 .msg primitives as rosidl names them in ``_fields_and_field_types`` (msg -> IDL mapping).
_ROS2_IDL = {
    "bool": "boolean",
    "byte": "octet",
    "char": "uint8",
    "float32": "float",
    "float64": "double",
    "string": "string",
    "wstring": "wstring",
    **{name: name for name in _INT_RANGES},
}
# array.array type codes rclpy uses for numeric sequences.
_TYPECODES = {
    "float": "f",
    "double": "d",
    "int8": "b",
    "uint8": "B",
    "int16": "h",
    "uint16": "H",
    "int32": "i",
    "uint32": "I",
    "int64": "q",
    "uint64": "Q",
}
_PRIMITIVES = {"bool", "byte", "char", "float32", "float64", "string", "wstring", *_INT_RANGES}
_ARRAY_RE = re.compile(r"^(?P<base>[^\[]+)(?:\[(?P<le><=)?(?P<n>\d*)\])?$")
_NAME_RE = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


@dataclass(slots=True)
class ConstantSpec:
    type_name: str
    name: str
    value: bool | int | float | str


@dataclass(slots=True, eq=False)
class FieldSpec:
    """One field, with everything conversion and rosapi need precomputed."""

    name: str
    cat: Cat
    prim: (
        str  # base type as the dialect's converter names it: ROS 1 'float64', ROS 2 'double'; msgs 'pkg/Type'
    )
    wire_type: str  # full type string: ROS 1 slot type 'float64[36]', ROS 2 IDL 'sequence<double>'
    is_array: bool = False
    fixed_len: int | None = None
    bound: int | None = None
    binary: bool = False  # travels as base64 (uint8[]/char[] and friends)
    msg_key: str | None = None
    lo: int = 0
    hi: int = 0
    typecode: str | None = None  # ROS 2 numeric sequences live in array.array(typecode)
    numpy: bool = False  # ROS 2 fixed numeric arrays live in numpy arrays
    string_bound: int | None = None
    ros1_char: bool = False
    default: Any = None  # ROS 2 default value from the definition (JSON form), if any
    msg: MessageSpec | None = None


@dataclass(slots=True, eq=False)
class MessageSpec:
    key: str
    pkg: str
    name: str
    text: str
    fields: list[FieldSpec] = field(default_factory=list)
    constants: list[ConstantSpec] = field(default_factory=list)
    field_map: dict[str, FieldSpec] = field(default_factory=dict)

    @property
    def short(self) -> str:
        """``pkg/Name``: what rosapi's TypeDef and rosbridge's error texts call this type."""
        return f"{self.pkg}/{self.name}"

    @property
    def is_header(self) -> bool:
        return self.pkg == "std_msgs" and self.name == "Header"


@dataclass(slots=True)
class ParsedTable:
    """Every type of one dialect: messages (incl. service/action parts) by internal key."""

    messages: dict[str, MessageSpec]
    services: dict[str, tuple[str, str]]  # 'pkg/srv/Name' -> (request key, response key)
    actions: dict[str, tuple[str, str, str]]  # 'pkg/action/Name' -> (goal, result, feedback keys)
    msg_names: set[str]  # 'pkg/msg/Name' of real .msg types (not generated parts)


def _parse_value(type_name: str, text: str, dialect: Dialect) -> bool | int | float | str:
    if type_name in ("string", "wstring") or type_name.startswith("string<"):
        if len(text) >= 2 and text[0] == text[-1] and text[0] in "\"'":
            return text[1:-1]
        return text
    if type_name == "bool":
        lowered = text.lower()
        if lowered in ("true", "1"):
            return True
        if lowered in ("false", "0"):
            return False
        raise DefinitionError(f"bad bool value {text!r}")
    if type_name in ("float32", "float64"):
        return float(text)
    if type_name in _INT_RANGES or type_name in ("byte", "char"):
        return int(text, 0)
    raise DefinitionError(f"type {type_name} cannot have a value ({dialect})")


def _parse_default(type_name: str, is_array: bool, text: str, dialect: Dialect) -> Any:
    if not is_array:
        value = _parse_value(type_name, text, dialect)
        return float(value) if type_name in ("float32", "float64") else value
    inner = text.strip()
    if not (inner.startswith("[") and inner.endswith("]")):
        raise DefinitionError(f"bad array default {text!r}")
    items = [item.strip() for item in inner[1:-1].split(",") if item.strip()]
    return [_parse_default(type_name, False, item, dialect) for item in items]


def _make_field(dialect: Dialect, pkg: str, name: str, type_text: str, default_text: str | None) -> FieldSpec:
    match = _ARRAY_RE.match(type_text)
    if match is None or not _NAME_RE.match(name):
        raise DefinitionError(f"bad field {type_text} {name}")
    base = match.group("base")
    is_array = "[" in type_text
    bounded = match.group("le") is not None
    size = int(match.group("n")) if match.group("n") else None
    fixed_len = size if is_array and not bounded else None
    bound = size if bounded else None
    string_bound: int | None = None
    if base.startswith("string<="):
        string_bound = int(base[len("string<=") :])
        base = "string"
    spec = FieldSpec(
        name=name,
        cat=Cat.MSG,
        prim=base,
        wire_type="",
        is_array=is_array,
        fixed_len=fixed_len,
        bound=bound,
        string_bound=string_bound,
    )
    if dialect == "ros1" and base in ("time", "duration"):
        spec.cat = Cat.TIME if base == "time" else Cat.DURATION
    elif base in _PRIMITIVES:
        _fill_primitive(spec, dialect, base)
    else:
        if "/" in base:
            ref_pkg, ref_name = base.split("/", 1)
        elif dialect == "ros1" and base == "Header":
            ref_pkg, ref_name = "std_msgs", "Header"
        else:
            ref_pkg, ref_name = pkg, base
        spec.msg_key = f"{ref_pkg}/msg/{ref_name}"
        spec.prim = f"{ref_pkg}/{ref_name}"
        if dialect == "ros2" and ref_pkg == "builtin_interfaces" and ref_name in ("Time", "Duration"):
            spec.cat = Cat.TIME if ref_name == "Time" else Cat.DURATION
    spec.wire_type = _wire_type(spec, dialect)
    spec.binary = _is_binary(spec, dialect, base)
    if dialect == "ros2" and is_array and spec.prim in _TYPECODES:
        if fixed_len is not None:
            spec.numpy = True
        else:
            spec.typecode = _TYPECODES[spec.prim]
    if default_text is not None:
        if dialect == "ros1":
            raise DefinitionError(f"ROS 1 fields have no default values ({name})")
        spec.default = _parse_default(base, is_array, default_text, dialect)
    return spec


def _fill_primitive(spec: FieldSpec, dialect: Dialect, base: str) -> None:
    if dialect == "ros2":
        spec.prim = _ROS2_IDL[base]
    int_name = _ROS1_ALIASES.get(base, base) if dialect == "ros1" else spec.prim
    if base == "bool":
        spec.cat = Cat.BOOL
    elif base in ("float32", "float64"):
        spec.cat = Cat.FLOAT
    elif base in ("string", "wstring"):
        spec.cat = Cat.STRING
    elif dialect == "ros2" and base == "byte":
        spec.cat = Cat.OCTET
        spec.lo, spec.hi = 0, 255
    else:
        spec.cat = Cat.INT
        spec.lo, spec.hi = _INT_RANGES[int_name]
        spec.ros1_char = dialect == "ros1" and base == "char"


def _wire_type(spec: FieldSpec, dialect: Dialect) -> str:
    if dialect == "ros1":
        base = {Cat.TIME: "time", Cat.DURATION: "duration"}.get(spec.cat, spec.prim)
        if not spec.is_array:
            return base
        return f"{base}[{spec.fixed_len if spec.fixed_len is not None else ''}]"
    base = spec.prim if spec.string_bound is None else f"string<{spec.string_bound}>"
    if not spec.is_array:
        return base
    if spec.fixed_len is not None:
        return f"{base}[{spec.fixed_len}]"
    if spec.bound is not None:
        return f"sequence<{base}, {spec.bound}>"
    return f"sequence<{base}>"


def _is_binary(spec: FieldSpec, dialect: Dialect, base: str) -> bool:
    # rosbridge matches 'uint8[...]'/'char[...]' and (ROS 2) unbounded 'sequence<uint8>' by pattern; ROS 2
    # bounded sequences ('sequence<uint8, 16>') slip through and travel as int lists [every version].
    if not spec.is_array:
        return False
    if dialect == "ros1":
        return base in ("uint8", "char")
    return spec.prim == "uint8" and spec.bound is None


def _parse_section(dialect: Dialect, key: str, pkg: str, name: str, text: str) -> MessageSpec:
    spec = MessageSpec(key=key, pkg=pkg, name=name, text=text)
    for raw in text.split("\n"):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        head = line.split(None, 1)
        if len(head) < 2:
            raise DefinitionError(f"{key}: bad line {raw!r}")
        type_text, rest = head
        if "=" in rest:
            const_name, value_text = (part.strip() for part in rest.split("=", 1))
            if type_text != "string":
                value_text = value_text.split("#", 1)[0].strip()
            spec.constants.append(
                ConstantSpec(type_text, const_name, _parse_value(type_text, value_text, dialect))
            )
            continue
        rest = rest.split("#", 1)[0].strip()
        parts = rest.split(None, 1)
        field_spec = _make_field(dialect, pkg, parts[0], type_text, parts[1] if len(parts) > 1 else None)
        spec.fields.append(field_spec)
        spec.field_map[field_spec.name] = field_spec
    return spec


def _split_sections(text: str, count: int, key: str) -> list[str]:
    sections: list[list[str]] = [[]]
    for line in text.split("\n"):
        if line.strip() == "---":
            sections.append([])
        else:
            sections[-1].append(line)
    if len(sections) != count:
        raise DefinitionError(f"{key}: expected {count} sections, got {len(sections)}")
    return ["\n".join(lines) for lines in sections]


_ACTIONLIB_HEADER = "# ====== DO NOT MODIFY! AUTOGENERATED FROM AN ACTION DEFINITION ======\n"


def _ros1_action_messages(pkg: str, name: str, text: str) -> dict[str, str]:
    """The seven messages genaction makes of one ROS 1 .action file."""
    goal, result, feedback = _split_sections(text, 3, f"{pkg}/action/{name}")
    return {
        f"{name}Action": (
            f"{_ACTIONLIB_HEADER}\n{name}ActionGoal action_goal\n{name}ActionResult action_result\n"
            f"{name}ActionFeedback action_feedback\n"
        ),
        f"{name}ActionGoal": (
            f"{_ACTIONLIB_HEADER}\nHeader header\nactionlib_msgs/GoalID goal_id\n{name}Goal goal\n"
        ),
        f"{name}ActionResult": (
            f"{_ACTIONLIB_HEADER}\nHeader header\nactionlib_msgs/GoalStatus status\n{name}Result result\n"
        ),
        f"{name}ActionFeedback": (
            f"{_ACTIONLIB_HEADER}\nHeader header\nactionlib_msgs/GoalStatus status\n{name}Feedback feedback\n"
        ),
        f"{name}Goal": f"{_ACTIONLIB_HEADER}{goal.strip()}\n",
        f"{name}Result": f"{_ACTIONLIB_HEADER}{result.strip()}\n",
        f"{name}Feedback": f"{_ACTIONLIB_HEADER}{feedback.strip()}\n",
    }


def parse_table(dialect: Dialect, texts: dict[str, str]) -> ParsedTable:
    """Parse every definition of one dialect and link nested message references."""
    table = ParsedTable(messages={}, services={}, actions={}, msg_names=set())

    def add(key: str, pkg: str, name: str, text: str) -> str:
        table.messages[key] = _parse_section(dialect, key, pkg, name, text)
        return key

    for key, text in texts.items():
        pkg, kind, name = key.split("/")
        if kind == "msg":
            add(key, pkg, name, text)
            table.msg_names.add(key)
        elif kind == "srv":
            request, response = _split_sections(text, 2, key)
            sep = "_" if dialect == "ros2" else ""
            table.services[key] = (
                add(f"{pkg}/srv/{name}{sep}Request", pkg, f"{name}{sep}Request", request),
                add(f"{pkg}/srv/{name}{sep}Response", pkg, f"{name}{sep}Response", response),
            )
        elif kind == "action" and dialect == "ros2":
            goal, result, feedback = _split_sections(text, 3, key)
            table.actions[key] = (
                add(f"{pkg}/action/{name}_Goal", pkg, f"{name}_Goal", goal),
                add(f"{pkg}/action/{name}_Result", pkg, f"{name}_Result", result),
                add(f"{pkg}/action/{name}_Feedback", pkg, f"{name}_Feedback", feedback),
            )
            add(
                f"{pkg}/action/{name}_FeedbackMessage",
                pkg,
                f"{name}_FeedbackMessage",
                f"unique_identifier_msgs/UUID goal_id\n{name}_Feedback feedback\n",
            )
        elif kind == "action":
            for msg_name, msg_text in _ros1_action_messages(pkg, name, text).items():
                add(f"{pkg}/msg/{msg_name}", pkg, msg_name, msg_text)
                table.msg_names.add(f"{pkg}/msg/{msg_name}")
            table.actions[key] = (
                f"{pkg}/msg/{name}Goal",
                f"{pkg}/msg/{name}Result",
                f"{pkg}/msg/{name}Feedback",
            )
        else:
            raise DefinitionError(f"unknown interface kind in {key}")

    for spec in table.messages.values():
        for field_spec in spec.fields:
            if field_spec.msg_key is None:
                continue
            target = table.messages.get(field_spec.msg_key)
            if target is None and field_spec.msg_key.endswith(("_Goal", "_Result", "_Feedback")):
                target = table.messages.get(field_spec.msg_key.replace("/msg/", "/action/"))
                if target is not None:
                    field_spec.msg_key = target.key
            if target is None:
                raise DefinitionError(f"{spec.key}.{field_spec.name}: unknown type {field_spec.msg_key}")
            field_spec.msg = target
    return table
