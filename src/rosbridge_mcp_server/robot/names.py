"""ROS graph names: the one place that makes a name absolute, checks it, and suggests close ones."""

from __future__ import annotations

import difflib
import re

from rosbridge_mcp_server.errors import NotSentError

__all__ = ["absolute", "absolute_name", "did_you_mean"]

_SLASHES = re.compile(r"/{2,}")


def absolute(name: str) -> str:
    """*name* with one leading slash, no doubled slashes and no trailing one (rosapi matches names exactly).

    ROS names never end in "/" nor hold "//"; either would make rosapi's exact-name look-ups miss. rospy
    resolves "//a//b/" to "/a/b" (a real 0.11.17 bridge answers for it), so we do the same on both lines.
    """
    text = _SLASHES.sub("/", name.strip()).rstrip("/")
    return text if text.startswith("/") else "/" + text


def absolute_name(name: str, what: str) -> str:
    """A name given by a caller, made absolute; :class:`NotSentError` for one no ROS name can be."""
    text = absolute(name)
    if text == "/":
        raise NotSentError(f"The {what} name is empty; give a name such as /turtle1/cmd_vel.")
    if any(ch.isspace() for ch in text):
        raise NotSentError(f"The {what} name {name!r} contains whitespace; ROS names never do.")
    return text


def did_you_mean(name: str, known: list[str]) -> str:
    """`` Did you mean /a or /b?`` for the names closest to a misspelt one, or ``""``."""
    close = difflib.get_close_matches(name, known, n=3, cutoff=0.8)
    return f" Did you mean {' or '.join(close)}?" if close else ""
