"""A ROS type as a model reads it: a nested outline of its fields, and an example JSON object.

The input is what rosapi's ``message_details`` (and ``service_request_details``, ``action_goal_details`` …)
answer: a list of ``TypeDef`` objects, the root type first, each with ``fieldnames``, ``fieldtypes``,
``fieldarraylen`` (-1 a scalar, 0 a variable-length array, N a fixed length) and
``constnames``/``constvalues``.
rosapi 2.1.0 (Jazzy, Kilted) names the fields after the Python slots of the generated class (``_linear``); the
messages themselves use ``linear``, so the slot prefix is dropped here. Pure: no I/O.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from rosbridge_mcp_server.robot.messages import (
    TypeDef,
    example_message,
    short_type_name,
    typedefs_from_rosapi,
)

__all__ = ["RawTypeDefs", "TypeOutline", "clean_typedefs", "outline_type"]

RawTypeDefs = Sequence[Mapping[str, Any]]

_MAX_LINES = 120
# ROS 2 rosapi names primitives as in IDL; a .msg file (what people read and write) says these.
_MSG_NAMES = {"double": "float64", "float": "float32", "boolean": "bool", "octet": "byte"}
_BOUND = re.compile(r"^(.*?)(?:<=(\d+))$")
_SEQUENCE = re.compile(r"^sequence<\s*([^,>]+?)\s*(?:,\s*(\d+)\s*)?>$")


@dataclass(frozen=True)
class TypeOutline:
    """The outline text (one line per field, nested types indented) and an example message."""

    type: str
    lines: tuple[str, ...]
    example: dict[str, Any]
    constants: dict[str, str]
    truncated: bool


def clean_typedefs(raw: Any) -> list[dict[str, Any]]:
    """The ``typedefs`` of a rosapi answer, with rosapi 2.1.0's slot underscores removed from field names."""
    items = raw.get("typedefs") if isinstance(raw, Mapping) else raw
    if not isinstance(items, list):
        return []
    cleaned: list[dict[str, Any]] = []
    for item in items:
        if not isinstance(item, Mapping) or not isinstance(item.get("type"), str):
            continue
        raw_names = [str(name) for name in item.get("fieldnames") or ()]
        names = raw_names
        # Only when every field has the prefix: a real field may start with "_" in other messages.
        if names and all(name.startswith("_") and len(name) > 1 for name in names):
            names = [name[1:] for name in names]
        constants = [
            (name, value)
            for name, value in zip(
                _strings(item.get("constnames")), _strings(item.get("constvalues")), strict=False
            )
            if _is_constant(name, {*raw_names, *names})
        ]
        cleaned.append(
            {
                **item,
                "fieldnames": names,
                "constnames": [name for name, _ in constants],
                "constvalues": [value for _, value in constants],
            }
        )
    return cleaned


def _is_constant(name: str, fields: set[str]) -> bool:
    """Whether a rosapi "constant" is one.

    ROS 2 rosapi lists every member of the message class: ``SLOT_TYPES``, each field's property and each
    ``X__DEFAULT``; only the real constants are kept.
    """
    return name != "SLOT_TYPES" and not name.endswith("__DEFAULT") and name not in fields


def outline_type(type_name: str, raw: RawTypeDefs, *, ros_version: int) -> TypeOutline:
    """The outline and example of ``type_name`` from its cleaned TypeDefs (the root first in ``raw``)."""
    by_type = {short_type_name(str(item["type"])): item for item in raw}
    typedefs = typedefs_from_rosapi({"typedefs": list(raw)})
    root = short_type_name(str(raw[0]["type"])) if raw else short_type_name(type_name)
    lines: list[str] = []
    expanded: set[str] = set()
    _outline(root, by_type, typedefs, depth=0, lines=lines, expanded=expanded, parents=())
    truncated = len(lines) > _MAX_LINES
    if truncated:
        lines = [*lines[:_MAX_LINES], f"… ({len(lines) - _MAX_LINES} more lines)"]
    root_item = by_type.get(root, {})
    constants = dict(
        zip(_strings(root_item.get("constnames")), _strings(root_item.get("constvalues")), strict=False)
    )
    example = example_message(root, typedefs, ros_version=ros_version)
    return TypeOutline(root, tuple(lines), example, constants, truncated)


def _outline(
    type_name: str,
    by_type: Mapping[str, Mapping[str, Any]],
    typedefs: Mapping[str, TypeDef],
    *,
    depth: int,
    lines: list[str],
    expanded: set[str],
    parents: tuple[str, ...],
) -> None:
    item = by_type.get(type_name)
    if item is None:
        return
    indent = "  " * depth
    expanded.add(type_name)
    for name, value in zip(_strings(item.get("constnames")), _strings(item.get("constvalues")), strict=False):
        lines.append(f"{indent}{name} = {value}  (constant)")
    typedef = typedefs.get(type_name)
    if typedef is None:
        return
    for name, base, length in typedef.fields():
        raw_type = _raw_field_type(item, name)
        shown = _field_type(base, length, raw_type)
        nested = base in by_type
        if nested and base in expanded and base not in parents:
            lines.append(f"{indent}{name}: {shown}  (fields as above)")
            continue
        lines.append(f"{indent}{name}: {shown}")
        if nested and base not in parents:
            _outline(
                base,
                by_type,
                typedefs,
                depth=depth + 1,
                lines=lines,
                expanded=expanded,
                parents=(*parents, type_name),
            )


def _raw_field_type(item: Mapping[str, Any], field: str) -> str:
    names = _strings(item.get("fieldnames"))
    types = _strings(item.get("fieldtypes"))
    if field in names:
        index = names.index(field)
        if index < len(types):
            return types[index]
    return ""


def _field_type(base: str, length: int, raw: str) -> str:
    """``float32[]``, ``float64[36]``, ``int32[<=10]`` or ``string<=8`` as the type of one field."""
    bound = ""
    text = raw.strip()
    sequence = _SEQUENCE.match(text)
    comma = re.match(r"^[^,<>]+,\s*(\d+)$", text)
    if sequence and sequence.group(2):
        bound = f"<={sequence.group(2)}"
    elif comma:
        # rosapi 2.x writes a bounded sequence as "T, N" (its regex keeps what is inside sequence<...>).
        bound = f"<={comma.group(1)}"
    else:
        inside = re.search(r"\[<=(\d+)\]$", text)
        if inside:
            bound = f"<={inside.group(1)}"
    string_bound = _BOUND.match(re.sub(r"\[.*\]$", "", text))
    base = base.split(",", 1)[0].strip()
    shown = _MSG_NAMES.get(base, base)
    if string_bound and string_bound.group(2) and base in ("string", "wstring"):
        shown = f"{base}<={string_bound.group(2)}"
    if length == 0:
        return f"{shown}[{bound}]"
    if length > 0:
        return f"{shown}[{length}]"
    return shown


def _strings(value: Any) -> list[str]:
    if not isinstance(value, list):
        return []
    return [str(item) for item in value]
