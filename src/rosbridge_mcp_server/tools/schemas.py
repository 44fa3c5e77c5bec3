"""Tool schemas as a host pays for them: ``tools/list`` is read on every conversation, so every byte counts.

The input schema keeps what a model needs to call a tool right the first time (each parameter's type,
bounds, description with an example, which are required) and drops what restates it: pydantic's titles
(``goal_id`` → "Goal Id"), ``default: null``, the 1,000 characters every string argument may have (said
when one is longer), and ``anyOf [X, null]`` written out (``type: [X, "null"]`` says the same). The output
schema is for the client that checks structured content: its structure and types stay one level deep;
descriptions, titles and defaults go (the answer's text explains itself).
"""

from __future__ import annotations

from typing import Any

from rosbridge_mcp_server.tools.arguments import MAX_TEXT_ARGUMENT

__all__ = ["compact_input_schema", "compact_output_schema", "inline_refs"]

# Every plain string argument's limit (tools/arguments.py): said when one is longer, not on every string.
_EVERY_STRING = ("maxLength", MAX_TEXT_ARGUMENT)
# Structured content always holds every field (it is a model's dump), so "required" tells a client nothing.
_OUTPUT_DROPPED = frozenset({"title", "description", "default", "examples", "required"})


def compact_input_schema(schema: dict[str, Any]) -> dict[str, Any]:
    """An input schema without restated titles, null defaults and null arms; nested models written in place
    without their own titles and descriptions (the parameter's description says what to send)."""
    definitions: dict[str, Any] = schema.get("$defs", {})

    def inline(node: Any) -> Any:
        if isinstance(node, list):
            return [inline(item) for item in node]
        if not isinstance(node, dict):
            return node
        ref = node.get("$ref")
        if isinstance(ref, str) and ref.startswith("#/$defs/"):
            nested = definitions[ref.removeprefix("#/$defs/")]
            return inline({k: v for k, v in nested.items() if k not in ("title", "description")})
        return {key: inline(value) for key, value in node.items() if key != "$defs"}

    out: dict[str, Any] = _compact(inline(schema), frozenset())
    out.pop("title", None)
    return out


def compact_output_schema(schema: dict[str, Any]) -> dict[str, Any]:
    """An output schema's top-level fields and their types; a nested object is said to be an object (the
    answer's text explains what is in it)."""
    out: dict[str, Any] = _compact(schema, _OUTPUT_DROPPED)
    properties = out.get("properties")
    if isinstance(properties, dict):
        out["properties"] = {name: _shallow(prop) for name, prop in properties.items()}
    return out


def _shallow(prop: Any) -> Any:
    """A field's schema with any object inside it reduced to ``{"type": "object"}``: a model's fields and a
    mapping's value type alike (the answer's text says what is in it)."""
    if not isinstance(prop, dict):
        return prop
    if "properties" in prop or "additionalProperties" in prop:
        kind = prop.get("type", "object")
        return {"type": kind}
    out = dict(prop)
    if isinstance(out.get("items"), dict) and "properties" in out["items"]:
        out["items"] = {"type": "object"}
    if isinstance(out.get("anyOf"), list):
        out["anyOf"] = [_shallow(arm) for arm in out["anyOf"]]
    return out


def _compact(node: Any, dropped: frozenset[str]) -> Any:
    if isinstance(node, list):
        return [_compact(item, dropped) for item in node]
    if not isinstance(node, dict):
        return node
    out: dict[str, Any] = {}
    for key, value in node.items():
        if key in dropped or (key == "default" and value is None) or (key, value) == _EVERY_STRING:
            continue
        if key == "additionalProperties" and value is True:
            continue  # what JSON Schema assumes anyway
        if key == "properties" and isinstance(value, dict) and "type" not in value:
            out[key] = {name: _property(name, prop, dropped) for name, prop in value.items()}
        else:
            out[key] = _compact(value, dropped)
    return _without_null_arm(out)


def _property(name: str, prop: Any, dropped: frozenset[str]) -> Any:
    compact = _compact(prop, dropped)
    if isinstance(compact, dict) and compact.get("title") == name.title().replace("_", " "):
        compact = {key: value for key, value in compact.items() if key != "title"}
    return compact


def _without_null_arm(node: dict[str, Any]) -> dict[str, Any]:
    """``{"anyOf": [{"type": "number", ...}, {"type": "null"}]}`` → ``{"type": ["number", "null"], ...}``
    (one typed arm whose keywords the node does not have; anything else stays as it is). Every other keyword
    of the arm constrains only values of its type, so null still passes."""
    arms = node.get("anyOf")
    if not isinstance(arms, list) or len(arms) != 2 or {"type": "null"} not in arms:
        return node
    other = arms[0] if arms[1] == {"type": "null"} else arms[1]
    kind = other.get("type") if isinstance(other, dict) else None
    if not isinstance(kind, str) or node.keys() & other.keys() - {"type"}:
        return node
    merged = {key: value for key, value in node.items() if key != "anyOf"}
    merged.update(other)
    merged["type"] = [kind, "null"]
    return merged


def inline_refs(schema: dict[str, Any]) -> dict[str, Any]:
    """``schema`` with every ``$ref`` into ``$defs`` replaced by the definition itself, and no ``$defs``.

    MCP clients validate structured content against the output schema on every call; the Python SDK's
    ``jsonschema`` spends ~35 % more on a schema that resolves references (measured, docs/performance.md).
    Our answer models nest but never recurse, so inlining always ends.
    """
    definitions: dict[str, Any] = schema.get("$defs", {})

    def resolve(node: Any) -> Any:
        if isinstance(node, dict):
            ref = node.get("$ref")
            if isinstance(ref, str) and ref.startswith("#/$defs/"):
                siblings = {k: resolve(v) for k, v in node.items() if k != "$ref"}
                return {**resolve(definitions[ref.removeprefix("#/$defs/")]), **siblings}
            return {k: resolve(v) for k, v in node.items() if k != "$defs"}
        if isinstance(node, list):
            return [resolve(item) for item in node]
        return node

    resolved: dict[str, Any] = resolve(schema)
    return resolved
