"""Whether a ``ros2msg``/``ros1msg`` schema can be decoded without a decoder recursing without end: no type
containing itself, at most :data:`~rosbridge_mcp_server.mcapfile.model.MAX_NESTING` levels. Read without
recursion. Pure."""

from __future__ import annotations

import re

from rosbridge_mcp_server.mcapfile.model import MAX_NESTING, Schema

__all__ = ["schema_problem"]

_SECTION = re.compile(r"^={10,}\s*$", re.MULTILINE)
_PRIMITIVES = frozenset(
    {"bool", "byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64"}
    | {"float32", "float64", "string", "wstring", "time", "duration"}
)


def schema_problem(schema: Schema) -> str | None:
    """Why a ``ros2msg``/``ros1msg`` schema cannot be decoded safely (a type containing itself, nesting over
    :data:`MAX_NESTING`), or ``None``."""
    if schema.encoding not in ("ros2msg", "ros1msg"):
        return None
    text = schema.data.decode("utf-8", "replace")
    sections = _SECTION.split(text)
    root = schema.name.replace("/msg/", "/")
    fields: dict[str, list[str]] = {}
    for index, section in enumerate(sections):
        lines = [ln.split("#", 1)[0].strip() for ln in section.splitlines()]
        lines = [ln for ln in lines if ln]
        name = root
        if index:
            if not lines or not lines[0].startswith("MSG:"):
                continue
            name = lines.pop(0)[4:].strip().replace("/msg/", "/")
        fields[name] = [_base(ln.split()[0], name) for ln in lines if len(ln.split()) >= 2 and "=" not in ln]
    return _nesting(fields, root, schema.name)


def _base(spelled: str, owner: str) -> str:
    base = spelled.split("[", 1)[0].split("<=", 1)[0].replace("/msg/", "/")
    if base in _PRIMITIVES or "/" in base:
        return base
    if base == "Header":
        return "std_msgs/Header"
    return f"{owner.split('/', maxsplit=1)[0]}/{base}"


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
