"""Text from the robot or a file, made fit to show: escaped, capped, and never taken for a name it is not.

Anyone who can publish on the robot's graph writes what the server reads: a log line, a node or frame name,
a status message, a recording's metadata. None of it may speak in the server's voice, so every such string
goes through :func:`shown` before it reaches an answer, a question or a log line of ours:

* control characters (C0, DEL, C1: a newline, a carriage return, BEL, NUL, the ESC that starts an ANSI
  sequence), Unicode format characters (bidi overrides and isolates, zero-width characters, tag characters),
  line and paragraph separators and unpaired UTF-16 surrogates are written as escapes (``\\n``, ``\\x1b``,
  ``\\u202e``), so the text cannot start a line of ours, colour a terminal or reorder what the reader sees;
* a field longer than its cap is cut, and the cut is said (``… (12,345 characters)``).

:func:`is_graph_name` and :func:`is_frame_name` are the strict checks a name passes before it goes into a
call we suggest (it is then a ROS name, nothing more); :func:`repaired` replaces unpaired surrogates in a
whole JSON-like value, the last step before an answer is written (the SDK's JSON writer refuses them, and
the stdio server would end). Pure: no I/O.
"""

from __future__ import annotations

import json
import re
from typing import Any, Final

__all__ = [
    "FIELD_CHARS",
    "NAME_CHARS",
    "is_frame_name",
    "is_graph_name",
    "json_shown",
    "repaired",
    "shown",
]

#: The default cap of one field of robot text (a log line's text, a status message).
FIELD_CHARS: Final = 500
#: The cap of a name (a node, a logger, a file, a function, a frame): ROS names stop at 247 characters.
NAME_CHARS: Final = 256

# What never reaches a reader raw: Unicode's Cc (controls), Cf (format: bidi, zero-width, tags), Cs
# (surrogates), Zl and Zp (line and paragraph separators). Written out (a test holds the list to
# unicodedata for every code point) so that importing costs nothing.
_UNSAFE: Final = re.compile(
    "[\x00-\x1f\x7f-\x9f\u00ad\u0600-\u0605\u061c\u06dd\u070f\u0890\u0891\u08e2\u180e\u200b-\u200f"
    "\u2028-\u202e\u2060-\u2064\u2066-\u206f\ufeff\ufff9-\ufffb\ud800-\udfff"
    "\U000110bd\U000110cd\U00013430-\U0001343f\U0001bca0-\U0001bca3\U0001d173-\U0001d17a"
    "\U000e0001\U000e0020-\U000e007f]"
)
_SHORT: Final = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}
_SURROGATE: Final = re.compile("[\ud800-\udfff]")
_GRAPH_NAME: Final = re.compile(r"(?:/[A-Za-z0-9_]+)+")
_FRAME_NAME: Final = re.compile(r"/?[A-Za-z0-9_][A-Za-z0-9_.\-]*(?:/[A-Za-z0-9_][A-Za-z0-9_.\-]*)*")


def _escape(match: re.Match[str]) -> str:
    char = match.group()
    if char in _SHORT:
        return _SHORT[char]
    code = ord(char)
    if code <= 0xFF:
        return f"\\x{code:02x}"
    if code <= 0xFFFF:
        return f"\\u{code:04x}"
    return f"\\U{code:08x}"


def shown(value: Any, limit: int = FIELD_CHARS) -> str:
    """*value* (a string, or anything ``str`` makes one of) escaped, and cut at *limit* characters with the
    cut said: ``… (1,048,576 characters)``. The cap counts the text as the robot sent it; escapes may make
    what is shown a little longer."""
    text = value if isinstance(value, str) else str(value)
    total = len(text)
    if total > limit:
        text = text[:limit]
    if not text.isprintable():
        # isprintable() is False for every character _UNSAFE holds (and for spaces other than " ", which
        # are kept): the fast path for the usual, clean text.
        text = _UNSAFE.sub(_escape, text)
    return text if total <= limit else f"{text}… ({total:,} characters)"


def _json_escape(match: re.Match[str]) -> str:
    code = ord(match.group())
    if code <= 0xFFFF:
        return f"\\u{code:04x}"
    code -= 0x10000
    return f"\\u{0xD800 + (code >> 10):04x}\\u{0xDC00 + (code & 0x3FF):04x}"


def json_shown(text: str) -> str:
    """A JSON text (``json.dumps(..., ensure_ascii=False)``, which escapes only C0 controls) with every other
    character :func:`shown` escapes written as a JSON escape (``\\u202e``): the same JSON, safe to show."""
    return text if text.isprintable() else _UNSAFE.sub(_json_escape, text)


def is_graph_name(name: str) -> bool:
    """Whether *name* is an absolute ROS graph name, strictly: ``/`` then tokens of ``[A-Za-z0-9_]`` (ROS 1
    allows a token that starts with a digit), at most 247 characters. What a suggested call may be built
    from."""
    return len(name) <= 247 and _GRAPH_NAME.fullmatch(name) is not None


def is_frame_name(name: str) -> bool:
    """Whether *name* is a plain tf frame id (``base_link``, ``robot1/odom``, ROS 1's ``/map``, dots and
    dashes allowed), at most 247 characters: nothing a JSON text or a line of ours could be broken with."""
    return len(name) <= 247 and _FRAME_NAME.fullmatch(name) is not None


def repaired(value: Any) -> Any:
    """*value* (a string, or what JSON holds) with every unpaired UTF-16 surrogate replaced by U+FFFD; the
    very object when it holds none (the usual case: one JSON encoding and one scan, at C speed, whatever the
    nesting)."""
    if isinstance(value, str):
        return _SURROGATE.sub("\ufffd", value) if _SURROGATE.search(value) else value
    text = json.dumps(value, ensure_ascii=False, default=str)
    if _SURROGATE.search(text) is None:
        return value
    return json.loads(_SURROGATE.sub("\ufffd", text))
