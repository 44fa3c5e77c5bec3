"""Whether a ``ros2msg``/``ros1msg`` schema can be decoded safely, and what decoding a message by it costs.

A decoder believes the schema: a type containing itself recurses without end, and an array of a type that
takes no bytes (ROS 1's empty message, a type holding only ``uint8[0]``) lets a four-byte length make
billions of objects. Refused: a type containing itself, nesting over
:data:`~rosbridge_mcp_server.mcapfile.model.MAX_NESTING` levels, a variable-length array of a type that takes
no bytes, and a type that decodes into over :data:`MAX_FREE_OBJECTS` objects more than its fewest bytes.
What is left is a :class:`DecodeCost`: at most so many objects, plus so many per byte of the message, held
to the budget before each message is decoded. Pure.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from rosbridge_mcp_server.mcapfile.model import MAX_NESTING, Schema

__all__ = ["OBJECT_BYTES", "DecodeCost", "decode_cost", "schema_problem"]

_SECTION = re.compile(r"^={10,}\s*$", re.MULTILINE)
_ARRAY = re.compile(r"\[(<=)?(\d*)\]$")
#: Each primitive's fewest bytes on the wire (a string: its length) and the objects it decodes into (a ROS 1
#: time: the time and its two numbers).
_PRIMITIVES: dict[str, tuple[int, int]] = {
    **dict.fromkeys(("bool", "byte", "char", "int8", "uint8"), (1, 1)),
    **dict.fromkeys(("int16", "uint16"), (2, 1)),
    **dict.fromkeys(("int32", "uint32", "float32", "string", "wstring"), (4, 1)),
    **dict.fromkeys(("int64", "uint64", "float64"), (8, 1)),
    **dict.fromkeys(("time", "duration"), (8, 3)),
}
#: Arrays of these are decoded as one bytes object.
_BYTES = frozenset({"uint8", "byte"})
#: Objects a type may decode into from its fewest bytes (a real type: a few hundred).
MAX_FREE_OBJECTS = 100_000
#: Memory one decoded object takes, about (a number, a list's slot; a message's dict once made plain).
OBJECT_BYTES = 100

#: A field: its base type and its array (None: not one; -1: variable length; else the fixed length).
_Field = tuple[str, int | None]


@dataclass(frozen=True)
class DecodeCost:
    """What decoding one message by a schema costs at most: ``free`` objects for its fewest bytes and
    ``per_byte`` more for each byte of the message."""

    free: int
    per_byte: float

    def memory(self, size: int) -> int:
        """Bytes of memory a message of ``size`` bytes may take decoded, about."""
        return (self.free + math.ceil(self.per_byte * size)) * OBJECT_BYTES


def schema_problem(schema: Schema) -> str | None:
    """Why a ``ros2msg``/``ros1msg`` schema cannot be decoded safely, or ``None``."""
    found = decode_cost(schema)
    return found if isinstance(found, str) else None


def decode_cost(schema: Schema) -> DecodeCost | str | None:
    """The cost of decoding a message by ``schema``, why it cannot be decoded safely, or ``None`` when it is
    not a ``ros2msg``/``ros1msg`` schema."""
    if schema.encoding not in ("ros2msg", "ros1msg"):
        return None
    root = schema.name.replace("/msg/", "/")
    fields = _fields(schema.data.decode("utf-8", "replace"), root)
    if problem := _nesting(
        {name: [base for base, _ in spec] for name, spec in fields.items()}, root, schema.name
    ):
        return problem
    costs: dict[str, tuple[int, int, float]] = {}
    try:
        _, free, per_byte = _cost(root, fields, costs, empty_size=1 if schema.encoding == "ros2msg" else 0)
    except _Costly as costly:
        return f"its schema {schema.name[:100]} {costly}; it was not decoded"
    return DecodeCost(free, per_byte)


def _fields(text: str, root: str) -> dict[str, list[_Field]]:
    fields: dict[str, list[_Field]] = {}
    for index, section in enumerate(_SECTION.split(text)):
        lines = [ln.split("#", 1)[0].strip() for ln in section.splitlines()]
        lines = [ln for ln in lines if ln]
        name = root
        if index:
            if not lines or not lines[0].startswith("MSG:"):
                continue
            name = lines.pop(0)[4:].strip().replace("/msg/", "/")
        fields[name] = [_field(ln.split()[0], name) for ln in lines if len(ln.split()) >= 2 and "=" not in ln]
    return fields


def _field(spelled: str, owner: str) -> _Field:
    array = _ARRAY.search(spelled)
    length = None if array is None else (int(array[2]) if array[2] and not array[1] else -1)
    return _base(spelled, owner), length


def _base(spelled: str, owner: str) -> str:
    base = spelled.split("[", 1)[0].split("<=", 1)[0].replace("/msg/", "/")
    if base in _PRIMITIVES or "/" in base:
        return base
    if base == "Header":
        return "std_msgs/Header"
    return f"{owner.split('/', maxsplit=1)[0]}/{base}"


class _Costly(Exception):
    """A type a decoder would make too many objects of (its text says why)."""


def _cost(
    name: str, fields: dict[str, list[_Field]], costs: dict[str, tuple[int, int, float]], empty_size: int
) -> tuple[int, int, float]:
    """A type's fewest bytes, the objects they decode into, and the most objects per further byte."""
    if name in _PRIMITIVES:
        return (*_PRIMITIVES[name], 0.0)
    if name not in fields:  # named but not defined: the decoder refuses it
        return 1, 1, 0.0
    if name in costs:
        return costs[name]
    size, free, per_byte = (0 if fields[name] else empty_size), 1, 0.0
    for base, length in fields[name]:
        each, objects, rate = _cost(base, fields, costs, empty_size)
        if length is None:
            size, free = size + each, free + objects
        elif length >= 0:
            size, free = size + length * each, free + 1 + (0 if base in _BYTES else length * objects)
        elif base in _BYTES:
            size, free = size + 4, free + 1
        elif each == 0:
            raise _Costly(f"has an array of {base[:100]}, a type that takes no bytes")
        else:
            size, free, rate = size + 4, free + 1, max(rate, objects / each)
        per_byte = max(per_byte, rate)
        if (
            free > MAX_FREE_OBJECTS + size
        ):  # a real type's objects are its bytes' (a number, a string), or few
            raise _Costly(f"has a type ({name[:100]}) that decodes into {free} objects from {size} bytes")
    costs[name] = (size, free, per_byte)
    return costs[name]


def _nesting(fields: dict[str, list[str]], root: str, shown: str) -> str | None:
    """Depth-first without recursion: a type met again while it is open is a cycle; the open path is the
    nesting."""
    state: dict[str, bool] = {root: False}  # False: open, True: done
    stack = [(root, iter(fields.get(root, [])))]
    while stack:
        child = next(stack[-1][1], None)
        if child is None:
            state[stack.pop()[0]] = True
            continue
        if child not in fields or state.get(child) is True:
            continue
        if child in state:
            return (
                f"its schema {shown[:100]} has a type that contains itself ({child[:100]}); "
                "it was not decoded"
            )
        if len(stack) >= MAX_NESTING:
            return f"its schema {shown[:100]} nests types over {MAX_NESTING} levels deep; it was not decoded"
        state[child] = False
        stack.append((child, iter(fields[child])))
    return None
