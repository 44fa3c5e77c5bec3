"""What the person is asked before an act: every value that moves the robot, whole, before any text.

The MCP client's elicitation and the operator console's approval page show this same text. A message is
shown field by field (``linear.x: 9.0``), never as one blob cut at a length, so that nothing the model writes
can push a value out of sight:

1. every number, flag and enum (an integer) first, whole, one per line; fixed fields before the contents of
   arrays (whose length the model chooses), so a long array cannot push ``x`` down; an array of numbers on
   one line, its first :data:`ARRAY_SHOWN` elements and its length;
2. then every string, cut at :data:`TEXT_SHOWN` characters with the cut said;
3. control, bidirectional and other invisible characters, in strings and in field names alike, shown
   escaped (``\\u202e``), quotes too, so a string cannot fake a line or a field of ours;
4. beyond :data:`LINES_SHOWN` lines, how many more values and strings were not shown.

The text depends on the act alone (a client answering in a second round matches the exact question).
"""

from __future__ import annotations

import json
import math
import unicodedata
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.safety.arm import arm_goal_text
from rosbridge_mcp_server.safety.navigation import goal_text

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.approval import Act

__all__ = ["ARRAY_SHOWN", "LINES_SHOWN", "TEXT_SHOWN", "question", "shown_text"]

#: The longest string shown whole; longer ones are cut, and the cut said.
TEXT_SHOWN = 120
#: The most elements of an array of numbers shown on its line (the array's length is always said).
ARRAY_SHOWN = 32
#: The most field lines in one question; beyond, how many more were not shown.
LINES_SHOWN = 200
#: The most elements of one array of messages walked; beyond, how many more were not shown.
ITEMS_WALKED = 64
#: The longest field name shown whole (names come from the message, which the model writes).
NAME_SHOWN = 80
#: The longest line of the question's head shown whole (a name, what the act does).
HEADER_SHOWN = 400

_NOUNS = {"topic": "topic", "service": "service", "action": "action", "parameter": "parameter"}
_PAYLOADS = {"topic": "message", "service": "request", "action": "goal", "parameter": "value"}
_VERBS = {
    "topic": "publish on",
    "service": "call the service",
    "action": "send a goal to",
    "parameter": "set the parameter",
}
#: Unicode categories never shown raw: controls, format characters (bidi overrides, zero-width), line and
#: paragraph separators, surrogates, private use, unassigned.
_HIDDEN = frozenset({"Cc", "Cf", "Zl", "Zp", "Cs", "Co", "Cn"})


def shown_text(text: str) -> str:
    """*text* in double quotes, every control and invisible character escaped (``\\n``, ``\\u202e``).

    (A small local helper: the project's text-sanitising module may replace it.)"""
    return '"' + _escaped(text, quotes=True) + '"'


def _escaped(text: str, *, quotes: bool) -> str:
    out = []
    for ch in text:
        if quotes and ch in '"\\':
            out.append("\\" + ch)
        elif ch in "\n\r\t":
            out.append({"\n": "\\n", "\r": "\\r", "\t": "\\t"}[ch])
        elif unicodedata.category(ch) in _HIDDEN:
            code = ord(ch)
            out.append(f"\\u{code:04x}" if code <= 0xFFFF else f"\\U{code:08x}")
        else:
            out.append(ch)
    return "".join(out)


def _header(line: str) -> str:
    """A line of the question's head (it may hold names the model or the robot spelt), escaped and cut at
    :data:`HEADER_SHOWN` characters with the cut said, so it cannot push the values down."""
    if len(line) > HEADER_SHOWN:
        line = f"{line[:HEADER_SHOWN]}… ({len(line)} characters, {len(line) - HEADER_SHOWN} not shown)"
    return _escaped(line, quotes=False)


def _number(value: Any) -> str:
    if isinstance(value, bool) or value is None:
        return json.dumps(value)
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    return json.dumps(value) if isinstance(value, int | float) else shown_text(str(value))


def _is_scalar(value: Any) -> bool:
    return value is None or isinstance(value, bool | int | float)


@dataclass
class _Fields:
    """The payload's fields as lines: (array depth, order, line) for values and for text."""

    values: list[tuple[int, int, str]] = field(default_factory=list)
    texts: list[tuple[int, int, str]] = field(default_factory=list)

    def add(self, into: list[tuple[int, int, str]], depth: int, line: str) -> None:
        into.append((depth, len(self.values) + len(self.texts), line))


def _name(key: Any) -> str:
    text = str(key)
    plain = text.isidentifier() and text.isascii()
    cut = text if len(text) <= NAME_SHOWN else text[:NAME_SHOWN]
    shown = cut if plain else shown_text(cut)
    return shown if len(text) <= NAME_SHOWN else f"{shown}…"


def _walk(value: Any, path: str, depth: int, fields: _Fields) -> None:
    where = path or "value"
    if _is_scalar(value):
        fields.add(fields.values, depth, f"{where}: {_number(value)}")
    elif isinstance(value, str):
        cut = ""
        if len(value) > TEXT_SHOWN:
            cut = f" … ({len(value)} characters, {len(value) - TEXT_SHOWN} not shown)"
        fields.add(fields.texts, depth, f"{where}: {shown_text(value[:TEXT_SHOWN])}{cut}")
    elif isinstance(value, dict):
        if not value and path:
            fields.add(fields.values, depth, f"{where}: {{}}")
        for key, item in value.items():
            _walk(item, f"{path}.{_name(key)}" if path else _name(key), depth, fields)
    elif isinstance(value, list | tuple):
        _walk_array(list(value), where, depth, fields)
    else:
        _walk(str(value), path, depth, fields)


def _walk_array(items: list[Any], where: str, depth: int, fields: _Fields) -> None:
    if all(_is_scalar(item) for item in items):
        shown = ", ".join(_number(item) for item in items[:ARRAY_SHOWN])
        more = f", … ({len(items)} in all)" if len(items) > ARRAY_SHOWN else ""
        fields.add(fields.values, depth, f"{where}: [{shown}{more}]")
        return
    for index, item in enumerate(items[:ITEMS_WALKED]):
        _walk(item, f"{where}[{index}]", depth + 1, fields)
    if len(items) > ITEMS_WALKED:
        fields.add(fields.values, depth, f"{where}: {len(items) - ITEMS_WALKED} more elements not shown")


def payload_lines(payload: Any, noun: str) -> list[str]:
    """The payload as the question shows it: values first (fixed fields before array contents), then text."""
    fields = _Fields()
    _walk(payload, "", 0, fields)
    values = [line for _, _, line in sorted(fields.values)]
    texts = [line for _, _, line in sorted(fields.texts)]
    room = LINES_SHOWN
    lines = [f"{noun.capitalize()} values (every number, flag and enum, whole):"] if values else []
    lines += [f"  {line}" for line in values[:room]]
    room -= min(room, len(values))
    if texts:
        lines.append(
            f"{noun.capitalize()} text (each cut at {TEXT_SHOWN} characters; control and direction "
            "characters shown escaped):"
        )
        lines += [f"  {line}" for line in texts[:room]]
    hidden = max(0, len(values) - LINES_SHOWN) + max(0, len(texts) - room)
    if hidden:
        lines.append(f"  … and {hidden} more fields not shown")
    if not values and not texts:
        lines.append(f"{noun.capitalize()}: (empty)")
    return lines


def question(act: Act, clamp: str | None = None) -> str:
    """What the person is asked: exactly what would be sent, and by which tool."""
    payload_kind = _PAYLOADS.get(act.kind, "payload")
    lines = [
        f"The AI assistant wants to {_VERBS.get(act.kind, 'act on')} {act.name} on the robot.",
        f"Tool: {act.tool}",
        f"{_NOUNS.get(act.kind, act.kind).capitalize()}: {act.name}",
    ]
    if act.type:
        lines.append(f"Type: {act.type}")
    if act.effects:
        lines.append(f"What it does: {'; '.join(e.describe() for e in act.effects)}.")
    if act.rate_hz is not None:
        lasting = f" for {act.duration:g} s" if act.duration is not None else " until stopped"
        lines.append(f"Repeated at {act.rate_hz:g} Hz{lasting}.")
    if clamp:
        lines.append(f"Note: {clamp}.")
    where = goal_text(act) or arm_goal_text(act)
    if where:
        lines.append(where)
    lines = [_header(line) for line in lines]
    lines += payload_lines(act.payload, payload_kind)
    lines.append("Allow this?")
    return "\n".join(lines)
