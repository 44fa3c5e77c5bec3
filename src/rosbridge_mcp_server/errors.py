"""Every error the rosbridge client raises.

The tree::

    RosbridgeError                  base: anything that went wrong talking to the bridge
    ├── NotConnectedError           no open connection right now (the robot is down, wrong address, ...)
    ├── ConnectionLostError         the connection dropped while this request was waiting for its reply
    ├── RequestTimeoutError         no reply within the deadline (rosbridge answers most errors with silence)
    │   └── GoalTimeoutError        an action goal did not finish in time; we asked to cancel it and carry
    │                               whatever partial outcome arrived
    ├── ServiceError                ``service_response`` with ``result: false``; carries the bridge's own text
    ├── ActionError                 ``action_result`` with ``result: false``, or an unreachable action
    ├── InvalidMessageError         a message, request or goal that does not fit its ROS type (checked by us,
    │                               because the bridge drops such messages without a word)
    ├── UnknownTypeError            the bridge does not know the type (its rosapi has no definition for it)
    ├── NotSentError                a check before an act refused it (a wrong name or type, a message that
    │   │                           does not fit, a bridge that does not read); nothing was sent
    │   └── FrameTooLargeError      a frame larger than the bridge accepts (the bridge would drop the
    │                               connection)
    ├── PolicyRefusal               the safety policy (or the person asked) refused an act; names the rule
    ├── NotOnRobotError             what a question names is not on the robot or cannot be read there (a
    │                               node, a parameter, a frame, a type rosapi cannot describe); says what is
    └── ProtocolError               a frame that breaks the rosbridge v2 protocol

Each error's ``str()`` is a sentence a person (or a model) can act on: it says what was tried, where,
and what to check. What the model can call next names MCP tools, which the domain does not know: an error
carries it as a typed fact (:class:`Hint`, set with :meth:`Advised.advise`), and the MCP edge words it
(``server/advice.py``) when it turns the error into a tool error (``server/adapter.py``).
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Literal, Self

__all__ = [
    "ActionError",
    "Advice",
    "Advised",
    "ConnectionLostError",
    "FrameTooLargeError",
    "GoalTimeoutError",
    "Hint",
    "InvalidMessageError",
    "NotConnectedError",
    "NotOnRobotError",
    "NotSentError",
    "PolicyRefusal",
    "ProtocolError",
    "RequestTimeoutError",
    "RosbridgeError",
    "ServiceError",
    "UnknownTypeError",
]


class Advice(enum.Enum):
    """What the model can do next after an error, as a fact: the MCP edge words it, naming the tools."""

    #: The topic has another type (names: the graph's type): publish that type, or find another topic.
    TOPIC_TYPE = enum.auto()
    #: A service name that nothing offers: the services are listed.
    SERVICES = enum.auto()
    #: A service name the bridge did not find in the graph: check the name against the services.
    SERVICE_NAME = enum.auto()
    #: An action name nobody serves: the actions are listed.
    ACTIONS = enum.auto()
    #: A topic that is not in the graph: the topics are listed, or the type can be given to wait.
    TOPICS_OR_TYPE = enum.auto()
    #: A name ROS refuses: check it against the topics, services and actions.
    NAME = enum.auto()
    #: A parameter name of the wrong form: the parameters are listed.
    PARAMETER_NAMES = enum.auto()
    #: A parameter write the policy cannot judge: write one parameter at a time instead.
    ONE_PARAMETER = enum.auto()
    #: A type the bridge does not know: the types in use are listed with the topics, services and actions.
    TYPES_IN_USE = enum.auto()
    #: An action type rosapi cannot describe: the action's type is listed, and a goal is checked when sent.
    ACTION_TYPES = enum.auto()
    #: A service type rosapi can describe only in use: the services in use are listed.
    SERVICE_TYPES = enum.auto()
    #: A path outside the recording directory: the recordings in it are listed.
    RECORDINGS = enum.auto()
    #: No recording of that name: the recordings are listed.
    NO_RECORDING = enum.auto()
    #: No node of that name: the nodes are listed.
    NODES = enum.auto()
    #: A node that is not running: the running nodes are listed.
    RUNNING_NODES = enum.auto()
    #: A message type the bridge does not know: the topics show the types in use.
    TOPIC_TYPES = enum.auto()


@dataclass(frozen=True)
class Hint:
    """What to try after an error: an :class:`Advice` and the names it involves (e.g. a topic's type), and
    what a layer above said after the error's text (``tail``), which stays after the advice."""

    advice: Advice
    names: tuple[str, ...] = ()
    tail: str = ""


class Advised(Exception):  # a mixin of errors, never raised alone
    """An error whose text the MCP edge completes with what to try (``hint``; ``None``: nothing to add)."""

    hint: Hint | None = None

    def advise(self, advice: Advice | Hint | None, *names: str) -> Self:
        """This error, carrying what to try next (an :class:`Advice` and its names, or another's ``hint``)."""
        self.hint = advice if not isinstance(advice, Advice) else Hint(advice, names)
        return self

    @classmethod
    def carrying(cls, error: Advised, tail: str = "") -> Self:
        """*error*'s text and hint as this kind of error, with *tail* said last (after the advice, if any)."""
        if error.hint is None:
            return cls(f"{error}{tail}")
        return cls(str(error)).advise(replace(error.hint, tail=error.hint.tail + tail))


class RosbridgeError(Advised):
    """Base of every error raised by the rosbridge client."""


class NotConnectedError(RosbridgeError):
    """There is no open connection to the bridge, so nothing was sent."""

    #: The settings the text says to check; a fleet's robot names its own entry instead (``server/``).
    SETTINGS = "ROSBRIDGE_HOST/ROSBRIDGE_PORT (or ROSBRIDGE_URL)"

    def __init__(self, url: str, reason: str | None = None, *, timed_out: bool = False) -> None:
        self.url = url
        self.reason = reason
        #: The attempt ran out of time (no WebSocket answer), rather than being refused or cut off.
        self.timed_out = timed_out
        detail = f" ({reason})" if reason else ""
        super().__init__(
            f"Not connected to rosbridge at {url}{detail}; nothing was sent. "
            "Check that the robot is on, that rosbridge_server is running there "
            "(ROS 2: `ros2 launch rosbridge_server rosbridge_websocket_launch.xml`, "
            "ROS 1: `roslaunch rosbridge_server rosbridge_websocket.launch`), and that "
            f"{self.SETTINGS} point at it. "
            "The server keeps reconnecting in the background; try again in a few seconds."
        )


class ConnectionLostError(RosbridgeError):
    """The connection dropped while a request was waiting for its reply.

    ``goal_cancel`` is set when *what* is an action goal, which keeps running on the robot after a drop:
    ``"sent"`` when a cancel already reached the bridge, ``"pending"`` when the client will send one as soon
    as the connection is back.
    """

    def __init__(self, url: str, what: str, *, goal_cancel: Literal["sent", "pending"] | None = None) -> None:
        self.url = url
        self.what = what
        self.goal_cancel = goal_cancel
        if goal_cancel == "pending":
            outcome = (
                "the goal may still be running on the robot, so a cancel for it will be sent as soon as the "
                "connection is back. Nothing else will be re-sent automatically."
            )
        elif goal_cancel == "sent":
            outcome = (
                "a cancel for the goal was sent, so it stops if it is still running. "
                "Nothing will be re-sent automatically."
            )
        else:
            outcome = "its outcome on the robot is unknown. Nothing will be re-sent automatically."
        super().__init__(f"The connection to rosbridge at {url} dropped while waiting for {what}; {outcome}")


class RequestTimeoutError(RosbridgeError):
    """No reply arrived within the deadline."""

    def __init__(self, what: str, timeout: float, hint: str | None = None) -> None:
        self.what = what
        self.timeout = timeout
        extra = f" {hint}" if hint else ""
        super().__init__(f"No reply to {what} within {timeout:g} s.{extra}")


class GoalTimeoutError(RequestTimeoutError):
    """An action goal did not finish within its deadline; a cancel was sent for it.

    ``status`` and ``result`` are the goal's final state and result if the canceled result arrived
    within a short grace after the cancel (``None`` otherwise); ``feedback`` is the last feedback seen.
    """

    def __init__(
        self,
        action: str,
        goal_id: str,
        timeout: float,
        *,
        status: int | None = None,
        result: object = None,
        feedback: object = None,
    ) -> None:
        self.action = action
        self.goal_id = goal_id
        self.status = status
        self.result = result
        self.feedback = feedback
        after = (
            f"The goal ended with status {status} after the cancel."
            if status is not None
            else "No final result arrived after the cancel; the goal may still be running."
        )
        super().__init__(
            f"action goal {goal_id} on {action}",
            timeout,
            f"A cancel was sent. {after}",
        )


#: rosbridge-server-rs 0.1.6's refusal of a call without ``type`` to a service it cannot see in the graph.
_RS_NOT_IN_GRAPH = "type is required when interface is absent from ROS graph"


class ServiceError(RosbridgeError):
    """A service call failed; ``message`` is the bridge's own text."""

    def __init__(self, service: str, message: str) -> None:
        self.service = service
        self.message = message
        if _RS_NOT_IN_GRAPH in message:
            # The bridge's words are about its own needs; the model needs to hear what is wrong.
            text = f"Service {service} is not in the ROS graph (the bridge said: {message})"
            self.advise(Advice.SERVICE_NAME)
        else:
            text = f"Service call {service} failed: {message}"
        super().__init__(text)

    @property
    def not_in_graph(self) -> bool:
        """The bridge said the service is not there (rosbridge_suite 0.11 and 2.x; rosbridge-server-rs)."""
        return "does not exist" in self.message or _RS_NOT_IN_GRAPH in self.message


class ActionError(RosbridgeError):
    """An action goal failed before reaching a terminal state, or could not be sent."""

    def __init__(self, action: str, message: str) -> None:
        self.action = action
        self.message = message
        super().__init__(f"Action {action} failed: {message}")


class InvalidMessageError(RosbridgeError):
    """A message does not fit its ROS type; ``problems`` names each field that is wrong."""

    def __init__(self, type_name: str, problems: Sequence[str]) -> None:
        self.type_name = type_name
        self.problems = list(problems)
        listed = "; ".join(self.problems)
        super().__init__(f"The message does not fit {type_name}: {listed}")


class UnknownTypeError(RosbridgeError):
    """The bridge has no definition for this type."""

    def __init__(self, type_name: str, hint: str | None = None) -> None:
        self.type_name = type_name
        extra = f" {hint}" if hint else ""
        super().__init__(
            f"rosbridge does not know the type {type_name!r} (its interface package is not installed "
            f"on the robot, or the name is misspelled).{extra}"
        )


class NotSentError(RosbridgeError):
    """A check before an act refused it, so nothing was sent; ``str()`` says why and what to try."""


class FrameTooLargeError(NotSentError):
    """A frame over the bridge's size limit; it was not sent and the connection is untouched."""

    def __init__(self, what: str, size: int, limit: int) -> None:
        self.what = what
        self.size = size
        self.limit = limit
        super().__init__(
            f"The {what} frame would be {size / 1_000_000:.1f} MB, more than the "
            f"{limit // (1024 * 1024)} MiB ({limit} bytes) rosbridge accepts in one frame (a larger one "
            "makes it drop the connection), so nothing was sent. Send a smaller message."
        )


class PolicyRefusal(RosbridgeError):
    """The safety policy refused an act before anything was sent, or the person asked to confirm it did not.

    ``str()`` names the rule (e.g. ``[velocity] max_linear 0.5 m/s; you asked 2``) or the person's answer.
    """


class NotOnRobotError(RosbridgeError, LookupError):
    """What a question names is not on the robot, or cannot be read there; ``str()`` says what is."""


class ProtocolError(RosbridgeError):
    """A frame broke the rosbridge v2 protocol."""
