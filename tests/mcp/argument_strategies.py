"""Hypothesis strategies for tool arguments, built from each tool's input schema (so new tools are covered).

What a confused or hostile client sends: every key present or missing, values of the right type and of every
wrong one, unknown keys, huge strings, NaN and infinities, booleans for numbers, deep nesting, odd names
(unicode, NUL characters, ``..``, ``~``, 6,000-character names) next to the robot's real names and types, so
that valid calls (which reach the robot) are mixed in. Numbers that would make a valid call run long are kept
small: a valid ``timeout`` or ``duration`` is at most 2 s and valid integers are small, so a run's time is
bounded.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any

from hypothesis import strategies as st

__all__ = ["Vocabulary", "call_deadline", "tool_calls"]

#: Longest a valid generated ``timeout`` may be, so that valid slow calls do not stretch a run.
MAX_VALID_TIMEOUT = 2.0


@dataclass
class Vocabulary:
    """Real names and types from the robot, so that some generated calls are valid."""

    names: list[str] = field(default_factory=list)
    types: list[str] = field(default_factory=list)
    #: (name, type) as the robot lists them: a topic, service or action with its type.
    pairs: list[tuple[str, str]] = field(default_factory=list)

    def add(self, name: str, type_name: str) -> None:
        self.names.append(name)
        if type_name:
            self.types.append(type_name)
        self.pairs.append((name, type_name))


def _nested(depth: int, leaf: Any = 0) -> Any:
    value: Any = leaf
    for i in range(depth):
        value = [value] if i % 2 else {"a": value}
    return value


ODD_NAMES = [
    "",
    "/",
    "//",
    "~",
    "~/private",
    "../..",
    "/tür",
    "/robot/🤖",
    "/a b",
    "/a-b",
    "/x.y",
    "/1abc",
    "/camera/2d",
    "/%s",
    "/{node}",
    "\0",
    "/\0\0\0",
    "/" + "a" * 300,
    "/" + "a" * 6000,
    "\0" * 2000,
    "/turtle1/cmd_vel/",
    "//turtle1//cmd_vel",
    "goal:/fibonacci:zz-1",
]
ODD_TYPES = ["", "pkg", "pkg/", "/Type", "pkg/msg/", "a/b/c/d", "std_msgs/msg/Strin", "x" * 2000, "🤖/msg/T"]

_keys = st.sampled_from(
    ["data", "a", "b", "order", "linear", "angular", "x", "y", "z", "theta", "", "é", "\0"]
)
_scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-10, 60),
    st.sampled_from([2**31, 2**63, -(2**63) - 1, 2**64]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=20),
)
_json_values = st.recursive(
    _scalars,
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(_keys, inner, max_size=4),
    max_leaves=12,
)
_huge_text = st.sampled_from([1_000, 1_000_000, 6_000_000]).flatmap(
    lambda n: st.sampled_from(["x" * n, "\0" * n, "€" * n])
)
# The SDK client serializes at most ~250 levels; deeper lines are sent raw by the stdio fuzz script.
_deep = st.integers(60, 200).map(_nested)
_deep_text = st.integers(60, 5000).map(lambda n: "[" * n + "]" * n)
_payload_objects = st.one_of(
    st.dictionaries(_keys, _json_values, max_size=5),
    _huge_text.map(lambda text: {"data": text}),
    _deep.map(lambda value: {"data": value}),
    st.just({"data": 12_000_000 * "x"}),
)
_any_value = st.one_of(
    _json_values,
    _huge_text,
    _deep,
    st.sampled_from(ODD_NAMES),
    st.sampled_from([math.nan, math.inf, -math.inf, -1.0, 0.0, 1e308, True, False]),
)


def _strings(vocabulary: Vocabulary, prop: dict[str, Any], key: str) -> st.SearchStrategy[Any]:
    real = vocabulary.types if "type" in key else vocabulary.names
    odd = ODD_TYPES if "type" in key else ODD_NAMES
    options: list[st.SearchStrategy[Any]] = [st.sampled_from(odd), st.text(max_size=30)]
    if real:
        options.insert(0, st.sampled_from(real))
    return st.one_of(*options)


def _value_for(vocabulary: Vocabulary, key: str, prop: dict[str, Any]) -> st.SearchStrategy[Any]:
    kinds: set[str] = set()
    if isinstance(prop.get("type"), str):
        kinds.add(prop["type"])
    elif isinstance(prop.get("type"), list):
        # An optional value is written type: [X, "null"] (tools/schemas.py).
        kinds.update(kind for kind in prop["type"] if isinstance(kind, str))
    for arm in prop.get("anyOf", []):
        if isinstance(arm, dict) and isinstance(arm.get("type"), str):
            kinds.add(arm["type"])
    fitting: list[st.SearchStrategy[Any]] = []
    if "object" in kinds:
        fitting.append(_payload_objects)
        fitting.append(_payload_objects.map(json.dumps))
        fitting.append(_deep_text)
    if "string" in kinds:
        fitting.append(_strings(vocabulary, prop, key))
    if "number" in kinds or "integer" in kinds:
        # Valid values stay small (a short wait, a few messages), so that valid calls end quickly.
        fitting.append(st.floats(0.01, MAX_VALID_TIMEOUT) if _time_like(key) else st.integers(-2, 5))
        fitting.append(st.sampled_from([0, -1, 1e9, math.nan, math.inf, True]))
    if "boolean" in kinds:
        fitting.append(st.booleans())
    if "null" in kinds:
        fitting.append(st.none())
    if not fitting:
        fitting.append(_json_values)
    return st.one_of(st.one_of(*fitting), _any_value) if fitting else _any_value


def _well_formed(schema: dict[str, Any], vocabulary: Vocabulary) -> st.SearchStrategy[dict[str, Any]]:
    """Required arguments only, a real name with its own type and an empty payload: often a valid call."""
    properties: dict[str, Any] = schema.get("properties", {})
    required = [key for key in schema.get("required", []) if key in properties]
    if not vocabulary.pairs:
        return st.just({})

    def build(pair: tuple[str, str]) -> dict[str, Any]:
        name, type_name = pair
        return {key: type_name if "type" in key else name for key in required}

    return st.sampled_from(vocabulary.pairs).map(build)


def _arguments(schema: dict[str, Any], vocabulary: Vocabulary) -> st.SearchStrategy[dict[str, Any]]:
    return st.one_of(_hostile(schema, vocabulary), _well_formed(schema, vocabulary))


def _hostile(schema: dict[str, Any], vocabulary: Vocabulary) -> st.SearchStrategy[dict[str, Any]]:
    properties: dict[str, Any] = schema.get("properties", {})
    entries = {
        key: st.one_of(st.just(_MISSING), _value_for(vocabulary, key, prop))
        for key, prop in properties.items()
    }
    unknown = st.dictionaries(
        st.one_of(
            st.sampled_from(["mesage", "requst", "timout", "extra", "", "\0"]), st.text(max_size=10)
        ).filter(lambda key: key not in properties),
        _json_values,
        max_size=2,
    )

    def build(pair: tuple[dict[str, Any], dict[str, Any]]) -> dict[str, Any]:
        known, extra = pair
        return {k: v for k, v in known.items() if v is not _MISSING} | extra

    return st.tuples(st.fixed_dictionaries(entries), st.one_of(st.just({}), unknown)).map(build)


class _Missing:
    def __repr__(self) -> str:
        return "<missing>"


_MISSING = _Missing()


def tool_calls(
    schemas: dict[str, dict[str, Any]], vocabulary: Vocabulary
) -> st.SearchStrategy[tuple[str, dict[str, Any]]]:
    """``(tool name, arguments)`` for any of the tools whose input schemas are given."""
    # The tool is drawn first, evenly (one_of favours its first branches), so every tool is reached.
    strategies = {
        name: _arguments(schema, vocabulary).map(lambda args, name=name: (name, args))
        for name, schema in schemas.items()
    }
    return st.sampled_from(list(strategies)).flatmap(strategies.__getitem__)


_TIME_WORDS = ("timeout", "duration", "seconds", "period", "wait")


def _time_like(key: str) -> bool:
    return any(word in key for word in _TIME_WORDS)


def call_deadline(arguments: dict[str, Any], schema: dict[str, Any], slack: float = 15.0) -> float:
    """How long a call may take: its time arguments (``timeout``, ``duration``, ...) as given when valid, else
    their defaults, added up, plus ``slack``."""
    total = slack
    for key, prop in schema.get("properties", {}).items():
        if not _time_like(key):
            continue
        given = arguments.get(key)
        # An optional argument keeps its bounds inside an anyOf branch: {"anyOf": [{"maximum": 60}, null]}.
        bounds = [prop, *prop.get("anyOf", [])]
        maximum = min(float(branch.get("maximum", math.inf)) for branch in bounds)
        if isinstance(given, int | float) and not isinstance(given, bool) and 0 < given <= maximum:
            total += float(given)
        elif isinstance(prop.get("default"), int | float):
            total += float(prop["default"])
    return total
