"""What the bridge can take in one frame, checked in one place: its size, and text that is text.

Two checks, one set of rules. :func:`payload_problem` looks at a message, request or goal as a tool is given
it (bounded work, before anything is looked up or asked); :func:`frame_bytes` refuses the encoded frame
itself, the last word before anything is written to a socket.
"""

from __future__ import annotations

import re
from typing import Any

from rosbridge_mcp_server.errors import FrameTooLargeError, NotSentError
from rosbridge_mcp_server.wire import protocol

__all__ = ["MAX_NESTING", "MAX_PAYLOAD_CHARS", "frame_bytes", "nesting_text", "payload_problem"]


def frame_bytes(text: str, what: str) -> bytes:
    """The UTF-8 bytes of a text frame, refused before anything is sent if the bridge could not take them.

    Encoded here rather than inside websockets: there, text that is not valid Unicode (an unpaired UTF-16
    surrogate, which JSON text can carry as ``\\ud800``) fails inside ``send()`` and websockets closes the
    connection. A frame over :data:`~rosbridge_mcp_server.wire.protocol.BRIDGE_MAX_FRAME_BYTES` would make the
    bridge drop the connection (:class:`FrameTooLargeError`).
    """
    try:
        data = text.encode("utf-8")
    except UnicodeEncodeError as exc:
        raise NotSentError(
            f"The {what} holds text that is not valid Unicode (an unpaired UTF-16 surrogate, "
            f"\\u{ord(text[exc.start]):04x}), so nothing was sent. Send plain text."
        ) from None
    if len(data) > protocol.BRIDGE_MAX_FRAME_BYTES:
        raise FrameTooLargeError(what, len(data), protocol.BRIDGE_MAX_FRAME_BYTES)
    return data


#: Deepest nesting of objects and arrays in a message, request or goal. ROS messages nest a handful of levels
#: (a nav_msgs/Path: 6); the bound keeps checking and encoding one bounded, well inside the recursion limits
#: of every JSON parser on the way.
MAX_NESTING = 64
#: The most text a message, request or goal may hold: what rosbridge accepts in one frame.
MAX_PAYLOAD_CHARS = protocol.BRIDGE_MAX_FRAME_BYTES
_SURROGATE = re.compile("[\ud800-\udfff]")


def nesting_text() -> str:
    """What is wrong with a value nested too deep (the end of a sentence that names it)."""
    return f"nests deeper than {MAX_NESTING} levels, the limit (ROS messages nest a handful of levels)"


def payload_problem(value: Any) -> str | None:
    """What makes ``value`` (a message, request or goal) unfit to send, or ``None``; bounded work.

    Too deep (:data:`MAX_NESTING`), too large for one rosbridge frame, or text that is not text (an unpaired
    UTF-16 surrogate, which cannot be encoded as UTF-8). Stops at the first problem.
    """
    size = 0
    stack: list[tuple[Any, int]] = [(value, 0)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, dict | list):
            if depth >= MAX_NESTING:
                return nesting_text()
            size += 2
            if isinstance(item, dict):
                for key, inner in item.items():
                    if isinstance(key, str):
                        size += len(key) + 3
                        if _SURROGATE.search(key):
                            return _surrogate_text(key)
                    stack.append((inner, depth + 1))
            else:
                stack.extend((inner, depth + 1) for inner in item)
        elif isinstance(item, str):
            size += len(item) + 3
            if _SURROGATE.search(item):
                return _surrogate_text(item)
        else:
            size += 8
        if size > MAX_PAYLOAD_CHARS:
            return (
                f"is larger than {MAX_PAYLOAD_CHARS // (1024 * 1024)} MiB, the most rosbridge accepts in one "
                "frame (a larger frame makes it drop the connection)"
            )
    return None


def _surrogate_text(text: str) -> str:
    found = _SURROGATE.search(text)
    code = ord(found.group()) if found is not None else 0
    return f"holds an unpaired UTF-16 surrogate (\\u{code:04x}), which is not text and cannot be sent"
