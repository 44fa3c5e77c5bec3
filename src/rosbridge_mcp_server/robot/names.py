"""ROS graph names: the one place that makes a name absolute, checks it, and suggests close ones."""

from __future__ import annotations

import difflib
import re

from rosbridge_mcp_server.errors import Advice, NotSentError

__all__ = [
    "MAX_NAME_CHARS",
    "absolute",
    "absolute_name",
    "check_name_for_ros",
    "did_you_mean",
    "parameter_name",
]

#: A ROS 2 name has at most 247 characters (rmw's limit: 255 less room for a DDS prefix); ROS 1 names never
#: come near it.
MAX_NAME_CHARS = 247
_SLASHES = re.compile(r"/{2,}")
_NAME_BAD_CHAR = re.compile(r"[^A-Za-z0-9_/]")
_DIGIT_TOKEN = re.compile(r"/([0-9][A-Za-z0-9_]*)")


def absolute(name: str) -> str:
    """*name* with one leading slash, no doubled slashes and no trailing one (rosapi matches names exactly).

    ROS names never end in "/" nor hold "//"; either would make rosapi's exact-name look-ups miss. rospy
    resolves "//a//b/" to "/a/b" (a real 0.11.17 bridge answers for it), so we do the same on both lines.
    """
    text = _SLASHES.sub("/", name.strip()).rstrip("/")
    return text if text.startswith("/") else "/" + text


def absolute_name(name: str, what: str) -> str:
    """A name given by a caller, made absolute; :class:`NotSentError` for one no ROS name can be.

    Held to the naming rules both ROS lines share: tokens of ``[A-Za-z0-9_]`` separated by ``/``, at most
    :data:`MAX_NAME_CHARS` characters, no private ``~`` names (they resolve inside a node: rosbridge's).
    :func:`check_name_for_ros` adds what only ROS 2 refuses. A bridge given a name it cannot use logs it and
    answers nothing (a publish is "sent" and lost), so an invalid name is refused here.
    """
    if len(name) > 2 * MAX_NAME_CHARS:
        raise NotSentError(_too_long(what, len(name))).advise(Advice.NAME)
    text = absolute(name)
    if text == "/":
        raise NotSentError(f"The {what} name is empty; give a name such as /turtle1/cmd_vel.")
    if any(ch.isspace() for ch in text):
        raise NotSentError(f"The {what} name {_shown(name)} contains whitespace; ROS names never do.")
    if text.startswith("/~"):
        raise NotSentError(
            f"The {what} name {_shown(name)} is a private name (~), which only means something inside a "
            "node; give the full name, e.g. /turtle1/cmd_vel."
        )
    if len(text) > MAX_NAME_CHARS:
        raise NotSentError(_too_long(what, len(text))).advise(Advice.NAME)
    bad = _NAME_BAD_CHAR.search(text)
    if bad is not None:
        raise NotSentError(
            f"The {what} name {_shown(text)} has {bad.group()!r} at position {bad.start()}; ROS names use "
            "only the letters A-Z and a-z, digits, _ and / (e.g. /turtle1/cmd_vel)."
        )
    return text


def parameter_name(name: str, ros_version: int) -> str:
    """A parameter's canonical full name: the one the robot acts on, in the dialect's form.

    ROS 1: a graph name, made absolute as :func:`absolute` does (``//turtlesim//background_r/`` is
    ``/turtlesim/background_r``: the parameter server resolves it so). ROS 2: ``/node:name``, the node part
    made absolute the same way (``/turtlesim/:background_r`` and ``turtlesim//:background_r`` are the
    node ``/turtlesim``'s); the name within the node is kept as written (ROS 2 names hold dots and slashes,
    and a node knows only the exact name it declared). :class:`NotSentError` for what cannot be one.
    """
    text = name.strip()
    if not text or any(ch.isspace() for ch in text):
        raise NotSentError(f"The parameter name {name!r} is empty or holds whitespace.")
    if ros_version == 1:
        if ":" in text:
            raise NotSentError(
                f"{text!r} is a ROS 2 style name; ROS 1 parameters are graph names like "
                "/turtlesim/background_r."
            )
        if "~" in text:
            raise NotSentError(
                f"The parameter name {text!r} is a private name (~), which only means something inside a "
                "node; give the full name, e.g. /turtlesim/background_r."
            )
        full = absolute(text)
        if full == "/":
            raise NotSentError(f"The parameter name {name!r} names the root; give a parameter's name.")
        return full
    node, sep, local = text.partition(":")
    if not sep or not node.strip("/") or not local or ":" in local:
        raise NotSentError(
            f"{text!r} is not a ROS 2 parameter name: they look like /node:name, e.g. /turtlesim:background_r"
        ).advise(Advice.PARAMETER_NAMES)
    return f"{absolute(node)}:{local}"


def check_name_for_ros(name: str, what: str, ros_version: int) -> None:
    """What only ROS 2 refuses in a name from :func:`absolute_name`: a part that starts with a digit.

    ROS 1 allows ``/camera/2d`` (roscpp and rospy name rules); ROS 2's rcl/rmw name validation does not, and
    rosbridge 2.x then only logs the failure.
    """
    if ros_version == 2:
        token = _DIGIT_TOKEN.search(name)
        if token is not None:
            raise NotSentError(
                f"The {what} name {_shown(name)} has a part starting with a digit ({token.group(1)!r}), "
                "which ROS 2 names do not allow."
            ).advise(Advice.NAME)


def _too_long(what: str, length: int) -> str:
    return (
        f"The {what} name is {length} characters long, more than the {MAX_NAME_CHARS} a ROS name can have "
        "(ROS 2's limit)."
    )


def _shown(name: str) -> str:
    return repr(name) if len(name) <= 80 else repr(name[:77]) + "..."


def did_you_mean(name: str, known: list[str], cutoff: float = 0.8) -> str:
    """`` Did you mean /a or /b?`` for the names closest to a misspelt one, or ``""``."""
    close = difflib.get_close_matches(name, known, n=3, cutoff=cutoff)
    return f" Did you mean {' or '.join(close)}?" if close else ""
