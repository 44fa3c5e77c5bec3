"""Check a message against its ROS type before sending it, and name every field that is wrong.

rosbridge drops a message that does not fit its type with a line in its own log and nothing on the wire
(rosbridge_suite 0.11 and every ROS 2 release), so a model would never learn why the robot did not move. We
check first, against the rosapi ``TypeDef``s of the type (``/rosapi/message_details``,
``/rosapi/service_request_details``), with rosbridge's own strictness:

* unknown field names make the whole message fail (we suggest the close ones and list the valid fields);
* ``bool`` fields want ``true``/``false``; integer fields reject ``1.5`` (and ``1.0``) and values out of
  range; float fields take any number in their range (float32 up to about 3.4e38); strings only for
  ``string``; ``null`` is rejected for every primitive;
* fixed-size arrays must have the right length; ``uint8[]``/``char[]`` may also be a base64 string;
* ROS 1 time/duration read only ``secs``/``nsecs`` (``sec``/``nanosec`` are silently ignored by rosbridge
  0.11, so we flag them); ROS 2 accepts both spellings; the string ``"now"`` is accepted for a time. Each
  time field must fit its wire width: ROS 1 time is two uint32, duration two int32; ROS 2 is int32 sec,
  uint32 nanosec.

Missing fields are fine: rosbridge fills them with defaults. This module is pure: no I/O.

"""

from __future__ import annotations

import difflib
import json
import math
import re
import sys
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from rosbridge_mcp_server.client import Dialect
from rosbridge_mcp_server.errors import InvalidMessageError, NotSentError
from rosbridge_mcp_server.robot.text import json_shown
from rosbridge_mcp_server.robot.wording import full_stop

__all__ = [
    "TypeDef",
    "check_message",
    "compact_json",
    "example_message",
    "find_problems",
    "require_fit",
    "same_type",
    "short_type_name",
    "typedefs_from_rosapi",
]

_INT_RANGES: dict[str, tuple[int, int]] = {
    "int8": (-(2**7), 2**7 - 1),
    "uint8": (0, 2**8 - 1),
    "int16": (-(2**15), 2**15 - 1),
    "uint16": (0, 2**16 - 1),
    "int32": (-(2**31), 2**31 - 1),
    "uint32": (0, 2**32 - 1),
    "int64": (-(2**63), 2**63 - 1),
    "uint64": (0, 2**64 - 1),
    # ROS 1: byte is a deprecated alias of int8 and char of uint8; ROS 2: octet and char are 8-bit unsigned.
    "byte": (-(2**7), 2**7 - 1),
    "char": (0, 2**8 - 1),
    "octet": (0, 2**8 - 1),
}
_FLOATS = frozenset({"float32", "float64", "float", "double", "long double"})
# A finite number beyond a float field's range never arrives: genpy's struct.pack raises OverflowError
# (rosbridge 0.11.17 logs it and drops the message) and ROS 2's generated setters reject it. ROS 2's float32
# bound is the one below, a hair under FLT_MAX, so we use it for both lines.
_FLOAT_LIMITS: dict[str, float] = {
    "float32": 3.402823466e38,
    "float": 3.402823466e38,
    "float64": sys.float_info.max,
    "double": sys.float_info.max,
}
_BOOLS = frozenset({"bool", "boolean"})
_STRINGS = frozenset({"string", "wstring"})
_ROS1_TIMES = frozenset({"time", "duration"})
_ROS2_TIMES = frozenset({"builtin_interfaces/Time", "builtin_interfaces/Duration"})
# What each time field must fit on the wire. ROS 1 (0.11.17) sets secs/nsecs as given and genpy packs a time
# as two uint32 and a duration as two int32: a negative time field, or a duration field past int32, is dropped
# with a struct error in rosbridge's log (rosapi calls both int32, so its TypeDef is not used for them).
# ROS 2's builtin_interfaces Time and Duration are int32 sec and uint32 nanosec.
_ROS1_TIME_FIELDS: dict[str, str] = {"secs": "uint32", "nsecs": "uint32"}
_ROS1_DURATION_FIELDS: dict[str, str] = {"secs": "int32", "nsecs": "int32"}
_ROS2_TIME_FIELDS: dict[str, str] = {"sec": "int32", "nanosec": "uint32", "secs": "int32", "nsecs": "uint32"}
# Arrays of these may be sent as a base64 string (rosbridge's JSON encoding of byte arrays).
_BYTE_TYPES = frozenset({"uint8", "char", "octet", "byte"})

_BOUND = re.compile(r"<=\d+$")
_SEQUENCE = re.compile(r"^sequence<\s*([^,>]+)\s*(?:,\s*\d+\s*)?>$")
_ARRAY_SUFFIX = re.compile(r"\[[^\]]*\]$")


@dataclass(frozen=True)
class TypeDef:
    """One message type's fields as rosapi describes them (``rosapi/TypeDef``)."""

    type: str
    fieldnames: tuple[str, ...]
    fieldtypes: tuple[str, ...]
    fieldarraylen: tuple[int, ...]
    examples: tuple[str, ...] = ()

    def fields(self) -> Iterable[tuple[str, str, int]]:
        """(name, base type, array length) for each field; the length is -1 for a scalar, 0 for a list."""
        for index, name in enumerate(self.fieldnames):
            raw = self.fieldtypes[index] if index < len(self.fieldtypes) else ""
            length = self.fieldarraylen[index] if index < len(self.fieldarraylen) else -1
            base, inferred = _split_array(raw)
            if length == -1 and inferred is not None:
                length = inferred
            yield name, base, length


#: ``pkg/msg/Type`` → ``pkg/Type`` (the key rosapi's TypeDefs use); the dialect's rule.
short_type_name = Dialect.short_type
#: Whether two spellings name the same type; the dialect's rule.
same_type = Dialect.same_type


def _split_array(raw: str) -> tuple[str, int | None]:
    """Strip ROS 2 ``sequence<T>``/``T[N]``/bounds spellings; return the base type and any length shown."""
    text = raw.strip()
    match = _SEQUENCE.match(text)
    if match:
        return _normalize_base(match.group(1)), 0
    suffix = _ARRAY_SUFFIX.search(text)
    if suffix:
        inside = suffix.group(0)[1:-1].strip()
        length = int(inside) if inside.isdigit() else 0
        return _normalize_base(text[: suffix.start()]), length
    return _normalize_base(text), None


def _normalize_base(text: str) -> str:
    return short_type_name(_BOUND.sub("", text.strip()))


def typedefs_from_rosapi(values: Mapping[str, Any]) -> dict[str, TypeDef]:
    """The ``typedefs`` list of a rosapi ``*_details`` response, keyed by short type name (``pkg/Type``)."""
    result: dict[str, TypeDef] = {}
    raw_list = values.get("typedefs")
    if not isinstance(raw_list, list):
        return result
    for raw in raw_list:
        if not isinstance(raw, Mapping) or not isinstance(raw.get("type"), str):
            continue
        typedef = TypeDef(
            type=short_type_name(raw["type"]),
            fieldnames=_wire_field_names([str(x) for x in raw.get("fieldnames") or ()]),
            fieldtypes=tuple(str(x) for x in raw.get("fieldtypes") or ()),
            fieldarraylen=tuple(_int_or(x, -1) for x in raw.get("fieldarraylen") or ()),
            examples=tuple(str(x) for x in raw.get("examples") or ()),
        )
        result.setdefault(typedef.type, typedef)
    return result


def _wire_field_names(names: list[str]) -> tuple[str, ...]:
    """The field names a message is sent with, from the names one rosapi TypeDef lists.

    rosapi 2.1.0 (Jazzy and Kilted alike) lists the Python slot names of the message class, ``_linear``
    for ``linear``, while the bridge reads and writes the plain names. A ROS field name always starts with a
    letter (rosidl and genmsg both require it), so a TypeDef whose every field starts with ``_`` is in slot
    names: the answer tells which form it is, whatever the release.
    """
    if names and all(name.startswith("_") and len(name) > 1 for name in names):
        return tuple(name[1:] for name in names)
    return tuple(names)


def _int_or(value: Any, default: int) -> int:
    return value if isinstance(value, int) and not isinstance(value, bool) else default


def check_message(message: Any, type_name: str, typedefs: Mapping[str, TypeDef], *, ros_version: int) -> None:
    """Raise :class:`InvalidMessageError` naming every wrong field, or return if the message fits."""
    problems = find_problems(message, type_name, typedefs, ros_version=ros_version)
    if problems:
        raise InvalidMessageError(type_name, problems)


def find_problems(
    message: Any, type_name: str, typedefs: Mapping[str, TypeDef], *, ros_version: int
) -> list[str]:
    """Every way ``message`` does not fit ``type_name``, each as ``path: what is wrong``."""
    checker = _Checker(typedefs, ros_version)
    root = short_type_name(type_name)
    if not isinstance(message, Mapping):
        return [f"the message must be a JSON object with the fields of {root}, got {_describe(message)}"]
    checker.check_object(message, root, "")
    return checker.problems


class _Checker:
    def __init__(self, typedefs: Mapping[str, TypeDef], ros_version: int) -> None:
        self.typedefs = typedefs
        self.ros_version = ros_version
        self.problems: list[str] = []

    def add(self, path: str, text: str) -> None:
        self.problems.append(f"{path or '(message)'}: {text}")

    def check_object(self, value: Mapping[str, Any], type_name: str, path: str) -> None:
        typedef = self.typedefs.get(type_name)
        if type_name in _ROS2_TIMES or type_name in _ROS1_TIMES:
            self.check_time(value, type_name, path)
            return
        if typedef is None:
            # rosapi did not describe this nested type; rosbridge will judge it.
            return
        fields = {name: (base, length) for name, base, length in typedef.fields()}
        for key, item in value.items():
            field_path = f"{path}.{key}" if path else str(key)
            if key not in fields:
                self.add(field_path, _unknown_field(str(key), type_name, list(fields)))
                continue
            base, length = fields[key]
            self.check_field(item, base, length, field_path)

    def check_field(self, value: Any, base: str, length: int, path: str) -> None:
        if length == -1:
            self.check_scalar(value, base, path)
            return
        if base in _BYTE_TYPES and isinstance(value, str):
            return  # base64, as rosbridge itself encodes byte arrays
        if not isinstance(value, list):
            size = f"{length} " if length > 0 else ""
            self.add(path, f"expected an array of {size}{_expected(base)}, got {_describe(value)}")
            return
        if length > 0 and len(value) != length:
            self.add(path, f"expected exactly {length} elements ({_shown(base)}[{length}]), got {len(value)}")
        for index, item in enumerate(value):
            self.check_scalar(item, base, f"{path}[{index}]")

    def check_scalar(self, value: Any, base: str, path: str) -> None:
        if base in _BOOLS:
            if not isinstance(value, bool):
                self.add(path, f"expected true or false ({_shown(base)}), got {_describe(value)}")
        elif base in _INT_RANGES:
            if isinstance(value, bool) or not isinstance(value, int):
                self.add(path, f"expected an integer ({_shown(base)}), got {_describe(value)}")
            else:
                low, high = _INT_RANGES[base]
                if not low <= value <= high:
                    self.add(path, f"{value} is out of range for {_shown(base)} ({low}..{high})")
        elif base in _FLOATS:
            if isinstance(value, bool) or not isinstance(value, int | float):
                self.add(path, f"expected a number ({_shown(base)}), got {_describe(value)}")
            elif base in _FLOAT_LIMITS and not _infinite(value) and abs(value) > _FLOAT_LIMITS[base]:
                limit = _FLOAT_LIMITS[base]
                self.add(
                    path, f"{_describe(value)} is out of range for {_shown(base)} (-{limit:g}..{limit:g})"
                )
        elif base in _STRINGS:
            if not isinstance(value, str):
                self.add(path, f"expected a string ({_shown(base)}), got {_describe(value)}")
        elif base in _ROS1_TIMES:
            self.check_time(value, base, path)
        elif isinstance(value, Mapping):
            self.check_object(value, base, path)
        elif base in _ROS2_TIMES and value == "now":
            return
        else:
            self.add(path, f"expected an object ({_shown(base)}), got {_describe(value)}")

    def check_time(self, value: Any, type_name: str, path: str) -> None:
        is_time = type_name in ("time", "builtin_interfaces/Time")
        if is_time and value == "now":
            return
        if not isinstance(value, Mapping):
            now = ' or "now"' if is_time else ""
            self.add(path, f"expected an object like {self._time_example()}{now}, got {_describe(value)}")
            return
        ros1_keys = ("secs", "nsecs")
        ros2_keys = ("sec", "nanosec")
        allowed = ros1_keys if self.ros_version == 1 else ros1_keys + ros2_keys
        if self.ros_version == 1:
            widths = _ROS1_TIME_FIELDS if type_name == "time" else _ROS1_DURATION_FIELDS
        else:
            widths = _ROS2_TIME_FIELDS
        for key, item in value.items():
            key_path = f"{path}.{key}" if path else str(key)
            if key not in allowed:
                hint = ""
                if self.ros_version == 1 and key in ros2_keys:
                    hint = " (ROS 1 reads only secs and nsecs; rosbridge would silently ignore this one)"
                self.add(key_path, f"no such field in {type_name}{hint}; its fields are {', '.join(allowed)}")
            elif isinstance(item, bool) or not isinstance(item, int):
                self.add(key_path, f"expected an integer, got {_describe(item)}")
            else:
                width = widths[key]
                low, high = _INT_RANGES[width]
                if not low <= item <= high:
                    self.add(key_path, f"{item} is out of range for {width} in {type_name} ({low}..{high})")

    def _time_example(self) -> str:
        return '{"secs": 0, "nsecs": 0}' if self.ros_version == 1 else '{"sec": 0, "nanosec": 0}'


# ROS 2 rosapi names primitives by their IDL names; the .msg names are the ones people write.
_MSG_NAMES = {"double": "float64", "float": "float32", "boolean": "bool", "octet": "byte"}


def _infinite(value: float) -> bool:
    # Infinities pack fine (genpy's struct.pack; ROS 2's setters allow them) and are common, e.g. a
    # LaserScan's range_max; only finite numbers past the type's range cannot be represented.
    return isinstance(value, float) and math.isinf(value)


def _shown(base: str) -> str:
    return _MSG_NAMES.get(base, base)


def _unknown_field(name: str, type_name: str, valid: Sequence[str]) -> str:
    close = difflib.get_close_matches(name, valid, n=3, cutoff=0.6)
    hint = f" (did you mean {' or '.join(close)}?)" if close else ""
    listed = ", ".join(valid) if valid else "none: send {}"
    return f"no such field in {type_name}{hint}; its fields are {listed}"


def _expected(base: str) -> str:
    if base in _BOOLS:
        return f"booleans ({_shown(base)})"
    if base in _INT_RANGES:
        return f"integers ({_shown(base)})"
    if base in _FLOATS:
        return f"numbers ({_shown(base)})"
    if base in _STRINGS:
        return f"strings ({_shown(base)})"
    return f"objects ({_shown(base)})"


def _describe(value: Any) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool | int | float | str):
        text = json.dumps(value)
        return text if len(text) <= 40 else text[:37] + '..."'
    if isinstance(value, list):
        return f"an array of {len(value)}"
    if isinstance(value, Mapping):
        return "an object"
    return type(value).__name__


def example_message(
    type_name: str, typedefs: Mapping[str, TypeDef], *, ros_version: int, depth: int = 4
) -> dict[str, Any]:
    """A message of ``type_name`` with every field at its default, to show a model the shape."""
    return _example_object(short_type_name(type_name), typedefs, ros_version, depth)


def _example_object(
    type_name: str, typedefs: Mapping[str, TypeDef], ros_version: int, depth: int
) -> dict[str, Any]:
    typedef = typedefs.get(type_name)
    if typedef is None or depth <= 0:
        return {}
    result: dict[str, Any] = {}
    for name, base, length in typedef.fields():
        if length == 0:
            result[name] = []
        elif length > 0:
            result[name] = [_example_scalar(base, typedefs, ros_version, depth - 1)] * length
        else:
            result[name] = _example_scalar(base, typedefs, ros_version, depth - 1)
    return result


def _example_scalar(base: str, typedefs: Mapping[str, TypeDef], ros_version: int, depth: int) -> Any:
    if base in _BOOLS:
        return False
    if base in _INT_RANGES:
        return 0
    if base in _FLOATS:
        return 0.0
    if base in _STRINGS:
        return ""
    if base in _ROS1_TIMES and base not in typedefs:
        return {"secs": 0, "nsecs": 0}
    return _example_object(base, typedefs, ros_version, depth)


def require_fit(
    message: Any,
    typedefs: Mapping[str, TypeDef],
    *,
    type_name: str | None = None,
    ros_version: int,
    nothing_sent: str,
    looks_like: str,
) -> None:
    """Check *message* against *type_name* (default: the first of *typedefs*, the one rosapi asked about).

    One that does not fit is a :class:`NotSentError` with an example of the type, reading ``<the wrong
    fields>. <nothing_sent>. <looks_like> looks like <example>.``, e.g. ``... Nothing was published. A
    geometry_msgs/msg/Twist message looks like {...}.``
    """
    if type_name is None:
        type_name = next(iter(typedefs))
    try:
        check_message(message, type_name, typedefs, ros_version=ros_version)
    except InvalidMessageError as exc:
        shape = compact_json(example_message(type_name, typedefs, ros_version=ros_version))
        raise NotSentError(f"{full_stop(str(exc))} {nothing_sent}. {looks_like} looks like {shape}.") from exc


def compact_json(value: Any, limit: int = 600) -> str:
    """One-line JSON for an answer's text, cut at ``limit`` characters; a message's strings are robot text, so
    bidi overrides, zero-width and other unsafe characters are written as JSON escapes (``robot/text.py``)."""
    text = json_shown(json.dumps(_finite(value), separators=(", ", ": "), ensure_ascii=False, default=str))
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _finite(value: Any) -> Any:
    # ROS 2 can send NaN in fixed-size float arrays; strict JSON has no NaN, so show it as null.
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    return value
