"""Messages as ``ros2 bag`` and ``rosbag`` write them: the schema text and the serialised bytes.

rosapi's TypeDefs of a type (``/rosapi/message_details``) give everything both need. The schema is the
concatenated ``.msg`` text MCAP's ``ros2msg`` and ``ros1msg`` encodings carry (the type's own fields, then
each nested type after a line of 80 ``=`` and ``MSG: pkg/Type``); the bytes are CDR (little-endian XCDR1, as
rmw writes it, for ROS 2) or ROS 1's serialisation, encoded from the message rosbridge sent: JSON, or CBOR
(typed arrays written as they came, byte arrays as bytes).

What JSON loses, the recording cannot bring back: rosbridge sends NaN and ±inf as ``null`` (recorded as NaN)
and ``uint8[]`` as base64 text (decoded back to its bytes). Pure: no I/O.
"""

from __future__ import annotations

import base64
import math
import struct
import sys
from array import array
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from rosbridge_mcp_server.robot.messages import TypeDef, short_type_name

__all__ = ["EncodingError", "MessageCodec", "message_codec"]

_SEPARATOR = "=" * 80

#: rosapi's spellings (ROS 2 rosapi names IDL types) → the ``.msg`` primitive.
_PRIMITIVE_ALIASES = {
    "float": "float32",
    "double": "float64",
    "long double": "float64",
    "boolean": "bool",
    "octet": "byte",
    "short": "int16",
    "unsigned short": "uint16",
    "long": "int32",
    "unsigned long": "uint32",
    "long long": "int64",
    "unsigned long long": "uint64",
}
#: struct format and size of each primitive, little-endian (``byte`` is int8 on ROS 1, octet on ROS 2).
_FORMATS_ROS2 = {
    "bool": "?",
    "byte": "B",
    "char": "B",
    "int8": "b",
    "uint8": "B",
    "int16": "h",
    "uint16": "H",
    "int32": "i",
    "uint32": "I",
    "int64": "q",
    "uint64": "Q",
    "float32": "f",
    "float64": "d",
}
_FORMATS_ROS1 = {**_FORMATS_ROS2, "byte": "b", "char": "B"}
_BYTE_ARRAYS = frozenset({"uint8", "char", "byte"})
_STRINGS = frozenset({"string", "wstring"})
_ROS1_TIMES = {"time": "II", "duration": "ii"}


class EncodingError(ValueError):
    """The type cannot be written (rosapi described it in a way the recorder cannot use)."""


def _primitive(base: str) -> str:
    return _PRIMITIVE_ALIASES.get(base, base)


@dataclass(frozen=True)
class _Field:
    name: str
    base: str  # a primitive's .msg name, "time"/"duration" (ROS 1), or a message's pkg/Type
    length: int  # -1 scalar, 0 unbounded sequence, N fixed array
    nested: bool


class MessageCodec:
    """One message type of one dialect: its MCAP schema (name, encoding, text) and its encoder."""

    def __init__(self, type_name: str, typedefs: Mapping[str, TypeDef], ros_version: int) -> None:
        self.ros_version = ros_version
        short = short_type_name(type_name)
        if short not in typedefs:
            raise EncodingError(f"rosapi gave no definition of {type_name}")
        pkg, _, name = short.partition("/")
        self.schema_name = f"{pkg}/msg/{name}" if ros_version == 2 else short
        self.schema_encoding = "ros2msg" if ros_version == 2 else "ros1msg"
        self.message_encoding = "cdr" if ros_version == 2 else "ros1"
        self._fields: dict[str, tuple[_Field, ...]] = {}
        order: list[str] = []
        self._collect(short, typedefs, order)
        self._root = short
        self.schema_text = self._text(order)
        self._formats = _FORMATS_ROS2 if ros_version == 2 else _FORMATS_ROS1

    # --- the schema ---------------------------------------------------------------------------------------

    def _collect(self, type_name: str, typedefs: Mapping[str, TypeDef], order: list[str]) -> None:
        if type_name in self._fields:
            return
        typedef = typedefs.get(type_name)
        if typedef is None:
            raise EncodingError(
                f"rosapi gave no definition of {type_name}, a field type of {self._root_hint}"
            )
        fields = []
        for field_name, raw_base, length in typedef.fields():
            base = _primitive(raw_base)
            if self.ros_version == 1 and base in _ROS1_TIMES:
                fields.append(_Field(field_name, base, length, nested=False))
                continue
            if base in _FORMATS_ROS2 or base in _STRINGS:
                fields.append(_Field(field_name, base, length, nested=False))
                continue
            nested = short_type_name(base)
            if "/" not in nested:
                raise EncodingError(
                    f"{type_name}.{field_name} has a type the recorder does not know: {raw_base}"
                )
            fields.append(_Field(field_name, nested, length, nested=True))
        self._fields[type_name] = tuple(fields)
        order.append(type_name)
        for item in fields:
            if item.nested:
                self._collect(item.base, typedefs, order)

    @property
    def _root_hint(self) -> str:
        return getattr(self, "_root", "the message")

    def _text(self, order: list[str]) -> str:
        sections = []
        for index, type_name in enumerate(order):
            lines = [f"{_spelled(f)} {f.name}" for f in self._fields[type_name]]
            body = "\n".join(lines)
            sections.append(body if index == 0 else f"{_SEPARATOR}\nMSG: {type_name}\n{body}")
        return "\n".join(sections) + "\n"

    @property
    def fixed_size_arrays(self) -> bool:
        """Whether the type (or one inside it) has a fixed-size array (rosbridge cannot send it as CBOR)."""
        return any(item.length > 0 for fields in self._fields.values() for item in fields)

    # --- the bytes ------------------------------------------------------------------------------------------

    def encode(self, message: Mapping[str, Any]) -> bytes:
        """The serialised message (CDR with its 4-byte encapsulation header on ROS 2)."""
        out = bytearray()
        if self.ros_version == 2:
            out += b"\x00\x01\x00\x00"  # CDR_LE
            self._cdr(self._root, message, out)
        else:
            self._ros1(self._root, message, out)
        return bytes(out)

    def _cdr(self, type_name: str, message: Any, out: bytearray) -> None:
        fields = self._fields[type_name]
        msg = message if isinstance(message, Mapping) else {}
        if not fields:
            out.append(0)  # rosidl's structure_needs_at_least_one_member
            return
        for item in fields:
            value = _value(msg, item.name)
            if item.nested:
                if item.length == -1:
                    self._cdr(item.base, value, out)
                    continue
                items = _items(value, item.length, {})
                if item.length == 0:
                    _align(out, 4)
                    out += struct.pack("<I", len(items))
                for element in items:
                    self._cdr(item.base, element, out)
            elif item.base in _STRINGS:
                for text in _scalar_or_items(value, item.length, "", out, cdr=True):
                    data = str(text if text is not None else "").encode()
                    _align(out, 4)
                    out += struct.pack("<I", len(data) + 1)
                    out += data
                    out.append(0)
            else:
                self._numbers(item, value, out, cdr=True)

    def _ros1(self, type_name: str, message: Any, out: bytearray) -> None:
        msg = message if isinstance(message, Mapping) else {}
        for item in self._fields[type_name]:
            value = _value(msg, item.name)
            if item.nested:
                if item.length == -1:
                    self._ros1(item.base, value, out)
                    continue
                items = _items(value, item.length, {})
                if item.length == 0:
                    out += struct.pack("<I", len(items))
                for element in items:
                    self._ros1(item.base, element, out)
            elif item.base in _ROS1_TIMES:
                fmt = _ROS1_TIMES[item.base]
                for stamp in _scalar_or_items(value, item.length, {}, out, cdr=False):
                    out += struct.pack("<" + fmt, *_stamp(stamp, fmt))
            elif item.base in _STRINGS:
                for text in _scalar_or_items(value, item.length, "", out, cdr=False):
                    data = str(text if text is not None else "").encode()
                    out += struct.pack("<I", len(data))
                    out += data
            else:
                self._numbers(item, value, out, cdr=False)

    def _numbers(self, item: _Field, value: Any, out: bytearray, *, cdr: bool) -> None:
        fmt = self._formats[item.base]
        size = struct.calcsize(fmt)
        if item.length == -1:
            if cdr:
                _align(out, size)
            out += struct.pack("<" + fmt, _number(value, fmt))
            return
        if item.base in _BYTE_ARRAYS and isinstance(value, str | bytes | bytearray | memoryview):
            data = base64.b64decode(value) if isinstance(value, str) else bytes(value)
            if item.length > 0:
                data = data[: item.length].ljust(item.length, b"\0")
            else:
                if cdr:
                    _align(out, 4)
                out += struct.pack("<I", len(data))
            out += data
            return
        if (
            isinstance(value, array)
            and item.length == 0
            and value.itemsize == size
            and _SAME_KIND.get(fmt) == (value.typecode)
        ):
            # A CBOR typed array of the field's own type: its bytes are the wire bytes (little-endian).
            if cdr:
                _align(out, 4)
            out += struct.pack("<I", len(value))
            if cdr and len(value):
                _align(out, size)
            out += value.tobytes() if not _BIG_ENDIAN else _swapped(value)
            return
        values = list(value) if isinstance(value, list | tuple | array) else []
        if item.length > 0:
            values = (values + [0] * item.length)[: item.length]
        else:
            if cdr:
                _align(out, 4)
            out += struct.pack("<I", len(values))
        if cdr and values:
            _align(out, size)
        out += struct.pack(f"<{len(values)}{fmt}", *(_number(v, fmt) for v in values))


_BIG_ENDIAN = sys.byteorder == "big"
#: struct format → the array typecode of the same kind and size (CBOR typed arrays arrive as these).
_SAME_KIND = {
    "b": "b",
    "B": "B",
    "h": "h",
    "H": "H",
    "i": "i",
    "I": "I",
    "q": "q",
    "Q": "Q",
    "f": "f",
    "d": "d",
}


def _swapped(value: array[Any]) -> bytes:
    copy = array(value.typecode, value)
    copy.byteswap()
    return copy.tobytes()


def _spelled(item: _Field) -> str:
    suffix = "" if item.length == -1 else "[]" if item.length == 0 else f"[{item.length}]"
    return f"{item.base}{suffix}"


def _align(out: bytearray, size: int) -> None:
    # CDR aligns to the field's size (at most 8), counted from after the 4-byte encapsulation header.
    pad = (-(len(out) - 4)) % size
    if pad:
        out += b"\0" * pad


def _value(msg: Mapping[str, Any], name: str) -> Any:
    if name in msg:
        return msg[name]
    # Time fields may come in either spelling (rosbridge 2.x reads both).
    alias = {"sec": "secs", "nanosec": "nsecs", "secs": "sec", "nsecs": "nanosec"}.get(name)
    return msg.get(alias) if alias else None


def _items(value: Any, length: int, default: Any) -> list[Any]:
    items = list(value) if isinstance(value, list | tuple) else []
    if length > 0:
        items = (items + [default] * length)[:length]
    return items


def _scalar_or_items(value: Any, length: int, default: Any, out: bytearray, *, cdr: bool) -> list[Any]:
    if length == -1:
        return [value]
    items = _items(value, length, default)
    if length == 0:
        if cdr:
            _align(out, 4)
        out += struct.pack("<I", len(items))
    return items


def _number(value: Any, fmt: str) -> Any:
    if fmt in "fd":
        if value is None:
            return math.nan  # rosbridge sends NaN and ±inf as null
        return float(value)
    if fmt == "?":
        return bool(value)
    if value is None:
        return 0
    return int(value)


def _stamp(value: Any, fmt: str) -> tuple[int, int]:
    if isinstance(value, Mapping):
        secs = value.get("secs", value.get("sec", 0)) or 0
        nsecs = value.get("nsecs", value.get("nanosec", 0)) or 0
        return int(secs), int(nsecs)
    return 0, 0


CodecFactory = Callable[[str], MessageCodec]


def message_codec(type_name: str, typedefs: Mapping[str, TypeDef], ros_version: int) -> MessageCodec:
    """The codec of ``type_name``; :class:`EncodingError` when its definitions are incomplete."""
    return MessageCodec(type_name, typedefs, ros_version)
