"""The policy as a guard on every acting call: rules, then caps, then a person's confirmation, then the audit.

:class:`PolicyGuard` is what the acting layer calls before anything is sent. Order matters:

1. ``read_only`` and the allow/deny globs, for the act's carrier (the topic, the service) and for each of its
   effects (the action a goal topic reaches, the parameters a ``set_parameters`` call writes: see
   :mod:`rosbridge_mcp_server.robot.effects`), under canonical names: a name the policy forbids is refused
   without asking anyone;
2. stream limits and velocity caps: refused, or (``mode = "clamp"``) scaled down to the cap;
3. confirmation, with the act as it will be sent (after clamping), so the person approves exactly that: asked
   of the MCP client's person (the console's when the client cannot ask), or with ``approvals = "console"``
   of the console's person only.

A refusal raises :class:`~rosbridge_mcp_server.errors.PolicyRefusal` whose text names the rule. Every decision
is one audit line (:class:`Audit`): on stderr, and as JSON in the audit file when one is configured.
"""

from __future__ import annotations

import asyncio
import dataclasses
import datetime
import json
import logging
import re
from collections.abc import Callable
from fnmatch import fnmatchcase
from typing import IO, TYPE_CHECKING, Any, NoReturn

from rosbridge_mcp_server.errors import PolicyRefusal
from rosbridge_mcp_server.robot.approval import AnswerNotInForm
from rosbridge_mcp_server.robot.motion_goals import Motion, with_speed
from rosbridge_mcp_server.robot.velocity import clamp_text, is_velocity_type, measure, scaled
from rosbridge_mcp_server.safety.arm import act_arm, arm_refusal, source_refusal
from rosbridge_mcp_server.safety.fence import fence_refusal, writes_fence
from rosbridge_mcp_server.safety.navigation import act_motion, navigation_refusal
from rosbridge_mcp_server.safety.operator import Operator
from rosbridge_mcp_server.safety.policy import Policy
from rosbridge_mcp_server.safety.question import question

if TYPE_CHECKING:
    # Only for annotations: the acting layer imports this package's velocity rules, so a runtime import here
    # would be circular.
    from rosbridge_mcp_server.robot.approval import Act, Answer, AskPerson

__all__ = [
    "AUDIT_PAYLOAD_LIMIT",
    "LATCH_RULE",
    "Audit",
    "AuditEntry",
    "PolicyGuard",
    "moves",
    "question",
]

_log = logging.getLogger("rosbridge_mcp_server.audit")

#: Longest audit file line; beyond it the payload is cut, with its full length noted.
AUDIT_PAYLOAD_LIMIT = 16_000


#: The rule a refusal names while the operator's e-stop is latched.
LATCH_RULE = "e-stop latched by the operator"

#: An answer off the confirmation form, as the audit's ``person:`` and the refusal say it.
_NOT_IN_FORM = "answer not in the form"

#: One audit line as a dict (the audit file's JSON, before the payload is cut).
AuditEntry = dict[str, Any]


class Audit:
    """One line per acting decision on stderr, and a JSON line in ``stream`` (the audit file) when given."""

    def __init__(self, stream: IO[str] | None = None, robot: str | None = None) -> None:
        self._stream = stream
        #: The robot this audit is for, when the server drives several (named in every line).
        self.robot = robot
        self._listeners: list[Callable[[AuditEntry], None]] = []

    def listen(self, callback: Callable[[AuditEntry], None]) -> None:
        """Also hand every entry to ``callback`` (e.g. the operator console); it must not block."""
        self._listeners.append(callback)

    def write(self, act: Act, outcome: str, detail: str | None = None) -> str | None:
        """Write the line; why it could not go into the audit file, or ``None`` (written, or no file)."""
        self._log_line(act, outcome, detail)
        if self._stream is None and not self._listeners:
            return None
        entry = self._entry(act, outcome, detail)
        for callback in self._listeners:
            try:
                callback(entry)
            except Exception:
                _log.exception("an audit listener failed")
        if self._stream is None:
            return None
        line = json.dumps(entry, ensure_ascii=False, default=str)
        if len(line) > AUDIT_PAYLOAD_LIMIT:
            # A camera frame in every line would bury the audit; its size and start are enough.
            body = json.dumps(act.payload, ensure_ascii=False, default=str)
            entry["payload"] = {"truncated": body[: AUDIT_PAYLOAD_LIMIT // 4], "characters": len(body)}
            line = json.dumps(entry, ensure_ascii=False, default=str)
        try:
            self._stream.write(line + "\n")
            self._stream.flush()
        except (OSError, ValueError) as exc:
            # The guard refuses an act whose line this is (nothing unaudited is sent); stderr has the line.
            _log.error("could not write to the audit log: %s", exc)
            return (exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)) or type(
                exc
            ).__name__
        return None

    def _log_line(self, act: Act, outcome: str, detail: str | None) -> None:
        """The act on stderr: INFO when routine, WARNING otherwise."""
        extra = f" ({detail})" if detail else ""
        stream = f" at {act.rate_hz:g} Hz for {act.duration:g} s" if act.rate_hz and act.duration else ""
        # A stream that sent what it planned ("sent 30 of 30") is as routine as one message sent.
        routine = outcome in ("allowed", "confirmed", "sent") or re.fullmatch(r"sent (\d+) of \1", outcome)
        level = logging.INFO if routine else logging.WARNING
        caller = act.caller
        written = f" (written {act.given!r})" if act.given is not None else ""
        effects = f" [{'; '.join(e.describe() for e in act.effects)}]" if act.effects else ""
        _log.log(
            level,
            "audit: %s%s %s %s%s %s%s%s: %s%s%s",
            f"[{self.robot}] " if self.robot else "",
            act.tool,
            act.kind,
            act.name,
            written,
            act.type or "-",
            stream,
            effects,
            outcome,
            extra,
            f" [caller {caller}]" if caller else "",
        )

    def _entry(self, act: Act, outcome: str, detail: str | None) -> AuditEntry:
        """The act as one JSON line's object (what the file and the listeners get)."""
        entry: AuditEntry = {
            "time": datetime.datetime.now(datetime.UTC).isoformat(timespec="milliseconds"),
            "tool": act.tool,
            "kind": act.kind,
            "name": act.name,
            "type": act.type,
            "outcome": outcome,
            "detail": detail,
            "payload": act.payload,
            "rate_hz": act.rate_hz,
            "duration": act.duration,
        }
        if act.given is not None:
            entry["given"] = act.given
        if act.effects:
            entry["effects"] = [
                {
                    "kind": e.kind,
                    "name": e.name,
                    "what": e.what,
                    **({"subtree": True} if e.subtree else {}),
                    **({"why": e.why} if e.why else {}),
                }
                for e in act.effects
            ]
        if act.caller is not None:
            entry["caller"] = act.caller
        if self.robot is not None:
            entry["robot"] = self.robot
        return entry


class PolicyGuard:
    """Applies a :class:`Policy` to each acting call (see the module docstring for the order)."""

    def __init__(self, policy: Policy, audit: Audit | None = None, operator: Operator | None = None) -> None:
        self.policy = policy
        self.audit = audit if audit is not None else Audit()
        #: The person beside the robot (the operator console), when one is served: asked when the MCP client
        #: cannot ask, and their latched e-stop refuses every acting call.
        self.operator = operator

    async def approve(self, act: Act, ask: AskPerson) -> Act:
        """``act`` as it may be sent (perhaps clamped), or :class:`PolicyRefusal` naming the rule."""
        if self.operator is not None and self.operator.latched:
            self._refuse(act, LATCH_RULE, _LATCHED_TEXT)
        rule = self._rule_refusal(act)
        if rule is not None:
            self._refuse(act, rule, f"Refused by the safety policy ({rule}); nothing was sent.")
        place = navigation_refusal(act, self.policy.navigation) or fence_refusal(act, self.policy.navigation)
        if place is not None:
            self._refuse(act, place.rule, place.text)
        arm = arm_refusal(act, self.policy.arm) or source_refusal(act)
        if arm is not None:
            self._refuse(act, arm.rule, arm.text)
        approved, clamp = self._capped(act)
        if self._needs_person(approved):
            answer = await self._ask(approved, ask, clamp)
            if self.operator is not None and self.operator.latched:
                # E-STOP pressed while the person was being asked: the stop wins over any yes.
                self._refuse(approved, LATCH_RULE, _LATCHED_TEXT)
            if answer != "accept":
                self._refuse(approved, f"person: {answer}", _answer_text(approved, answer, self.policy))
            unwritten = self.audit.write(approved, "confirmed", clamp)
        else:
            unwritten = self.audit.write(approved, "clamped" if clamp else "allowed", clamp)
        if unwritten is not None:
            # An act the audit file cannot show is not sent (a stop is never asked here: it always goes).
            self._refuse(
                approved,
                "audit: the audit file could not be written",
                f"Not sent: the audit log could not be written ({unwritten}); nothing is sent that the audit "
                "cannot record. Free space on its disk or fix the file (--audit-log), then call again. "
                "Stopping still works.",
            )
        return approved

    def record(self, act: Act, outcome: str) -> None:
        """Audit what became of an act after :meth:`approve`.

        :meth:`approve` already wrote the decision (allowed, clamped, confirmed or refused), so ``"sent"`` and
        ``"refused: ..."`` add nothing; anything else (a send that failed, an e-stop) is a line of its own.
        """
        if outcome != "sent" and not outcome.startswith("refused"):
            self.audit.write(act, outcome)

    def held(self) -> str | None:
        """The refusal of every send while the operator's E-STOP is latched (asked at each send), or None."""
        if self.operator is not None and self.operator.latched:
            return _LATCHED_TEXT
        return None

    def send_interval(self, act: Act) -> float:
        """``1 / [publish] max_rate_hz`` for a message on a topic: the send gate keeps the messages on one
        topic (every stream and single publish together) at least this far apart; 0 without a cap."""
        rate = self.policy.publish.max_rate_hz
        if act.kind != "topic" or rate is None or rate <= 0:
            return 0.0
        return 1.0 / rate

    def _refuse(self, act: Act, rule: str, text: str) -> NoReturn:
        self.audit.write(act, "refused", rule)
        raise PolicyRefusal(text)

    def _rule_refusal(self, act: Act) -> str | None:
        policy = self.policy
        if policy.read_only:
            return "read_only: this server may only read the robot"
        section, rules = policy.rules_for(act.kind)
        refusal = rules.refusal(act.name, section)
        if refusal is not None:
            return refusal
        for effect in act.effects:
            # Judged as if the matching tool had been used: a goal sent through its topic or service meets
            # [actions], a parameter set through a service meets [parameters]. A cancel only stops what the
            # robot does (cancel_action asks no rule either); motion by service has no section of its own,
            # and a fence write meets [navigation] (fence_refusal).
            if effect.kind in ("motion", "fence") or effect.what == "cancel":
                continue
            section, rules = policy.rules_for(effect.kind)
            refusal = rules.refusal(effect.name, section, subtree=effect.subtree)
            if refusal is not None:
                return f"{refusal}: {act.tool} on {act.name} is {effect.describe()}"
        limits = policy.publish
        if act.rate_hz is not None:
            if limits.max_rate_hz is not None and act.rate_hz > limits.max_rate_hz:
                return f"[publish] max_rate_hz {limits.max_rate_hz:g} Hz; you asked {act.rate_hz:g} Hz"
            if limits.max_duration is not None:
                if act.duration is None:
                    return (
                        f"[publish] max_duration {limits.max_duration:g} s; you asked for an endless stream"
                    )
                if act.duration > limits.max_duration:
                    return f"[publish] max_duration {limits.max_duration:g} s; you asked {act.duration:g} s"
        return None

    def _capped(self, act: Act) -> tuple[Act, str | None]:
        caps = self.policy.velocity
        motion = act_motion(act)
        if isinstance(motion, Motion) and motion.speed is not None:
            return self._goal_speed_capped(act, motion.speed)
        if act.kind != "topic" or not is_velocity_type(act.type):
            return act, None
        if caps.max_linear is None and caps.max_angular is None:
            return act, None
        speed = measure(act.type, act.payload)
        if not speed.finite:
            rule = "[velocity] caps: the command holds a value that is not a finite number"
            self._refuse(act, rule, f"Refused by the safety policy ({rule}); nothing was sent.")
        over: list[str] = []
        linear_factor = angular_factor = 1.0
        if caps.max_linear is not None and speed.linear > caps.max_linear:
            over.append(f"max_linear {caps.max_linear:g} m/s; you asked {speed.linear:g}")
            linear_factor = caps.max_linear / speed.linear
        if caps.max_angular is not None and speed.angular > caps.max_angular:
            over.append(f"max_angular {caps.max_angular:g} rad/s; you asked {speed.angular:g}")
            angular_factor = caps.max_angular / speed.angular
        if not over:
            return act, None
        rule = f"[velocity] {' and '.join(over)}"
        if caps.mode == "refuse":
            self._refuse(
                act,
                rule,
                f"Refused by the safety policy ({rule}); nothing was sent. Send a command within the caps.",
            )
        payload = scaled(act.type, act.payload, linear_factor, angular_factor)
        clamped = dataclasses.replace(act, payload=payload)
        return clamped, clamp_text(act.type, act.payload, payload)

    def _goal_speed_capped(self, act: Act, speed: float) -> tuple[Act, str | None]:
        """A motion goal's own speed (DriveOnHeading, BackUp) under ``[velocity] max_linear``, refused or
        clamped as a velocity command is."""
        cap = self.policy.velocity.max_linear
        if cap is None or speed <= cap:
            return act, None
        rule = f"[velocity] max_linear {cap:g} m/s; the goal asks {speed:g} m/s"
        if self.policy.velocity.mode == "refuse":
            self._refuse(
                act,
                rule,
                f"Refused by the safety policy ({rule}); nothing was sent. Send a goal within the cap.",
            )
        payload = with_speed(act.kind, act.payload, cap)
        return dataclasses.replace(act, payload=payload), f"speed clamped from {speed:g} to {cap:g} m/s"

    def _needs_person(self, act: Act) -> bool:
        confirm = self.policy.confirm
        if self.policy.navigation.confirm == "motion" and (act_motion(act) is not None or writes_fence(act)):
            # Every motion goal by any carrier (robot/motion_goals.py), every write to what the fence reads.
            return True
        arm = act_arm(act)
        if arm is not None and (
            self.policy.arm.confirm == "motion" or (arm.kind == "switch" and self.policy.arm.configured)
        ):
            # Every arm motion by any carrier (robot/arm_goals.py); a controller switch always while [arm] has
            # boxes (it can hand the joints to a controller this server does not judge).
            return True
        if confirm == "always":
            return True
        if confirm == "motion":
            return moves(act, self.policy)
        return False

    async def _ask(self, act: Act, ask: AskPerson, clamp: str | None) -> Answer | str:
        text = question(act, clamp)
        try:
            async with asyncio.timeout(self.policy.confirm_timeout):
                if self.policy.approvals == "console":
                    # Only the person at the console: the MCP client's own answer could be the requester's.
                    if self.operator is None or not self.operator.present:
                        return "no console"
                    return await self.operator.ask(text, act)
                # A person whose client can open a URL comes with a way to send them there (approval.py).
                link = ask.by_link
                operator = self.operator
                if link is not None and operator is not None and operator.present and operator.link_base:
                    # The client can open a URL: it sends the person to this call's approval on the console,
                    # where the camera and the map are (the console's secret never goes to the client).
                    return await operator.ask(text, act, by_link=link)
                answer = await ask(text)
                if answer == "unsupported" and self.operator is not None and self.operator.present:
                    # The MCP client cannot ask: the person at the console can, within the same timeout.
                    answer = await self.operator.ask(text, act)
                return answer
        except TimeoutError:
            return "timeout"
        except AnswerNotInForm as exc:
            # The client asked, but its answer is no yes/no: say what was wrong, not that it cannot ask.
            return f"{_NOT_IN_FORM} ({exc})"
        except Exception as exc:
            # A client that fails the request (or never answers in time) has not said yes.
            _log.warning("asking the person failed: %s", exc)
            return "error"


_LATCHED_TEXT = (
    "Refused: the robot's operator pressed E-STOP on the operator console, and every acting call is refused "
    "until they release it there; nothing was sent. Tell the user; do not try to reach the same effect "
    "another way."
)


def moves(act: Act, policy: Policy) -> bool:
    """Whether ``act`` moves the robot, as ``confirm = "motion"`` judges it.

    A velocity command (Twist / TwistStamped on any topic), an action goal (``publish_action``, or a goal sent
    through an actionlib ``…/goal`` topic or a ROS 2 ``…/_action/send_goal`` service), a motion goal by any
    carrier and in any type spelling (``robot/motion_goals.py``), a known motion command or service
    (``robot/effects.py``: joint trajectories, joysticks, goal poses, turtlesim's teleports and resets,
    Gazebo's set-state and reset services, lifecycle transitions, ...), a write to what the fence or
    localisation reads (``/tf``, ``/initialpose``, the map, masks, the speed limit: the robot then moves
    differently) and a topic or service the policy's ``[topics]`` / ``[services] motion`` names.
    """
    if act.kind == "action" or (act.kind == "topic" and is_velocity_type(act.type)):
        return True
    if act_motion(act) is not None or act_arm(act) is not None:
        return True
    if any(e.kind in ("motion", "fence") or (e.kind == "action" and e.what == "goal") for e in act.effects):
        return True
    listed = {"service": policy.motion_services, "topic": policy.motion_topics}.get(act.kind, ())
    return any(fnmatchcase(act.name, pattern) for pattern in listed)


def _answer_text(act: Act, answer: str, policy: Policy) -> str:
    what = f"{act.tool} on {act.name}"
    if answer.startswith(_NOT_IN_FORM):
        return (
            f"The MCP client answered the confirmation for {what}, but the answer did not match the "
            f"confirmation form {answer.removeprefix(_NOT_IN_FORM).strip()}; nothing was sent. The client "
            "must answer with approve true or false: tell the user."
        )
    if answer == "decline":
        return f"The person declined {what}; nothing was sent. Do not retry it unless they ask you to."
    if answer == "cancel":
        return f"The person dismissed the confirmation for {what} without accepting; nothing was sent."
    if answer == "unsupported":
        return (
            f"The safety policy requires a person to confirm {what} (confirm = {policy.confirm!r}), but this "
            "MCP client cannot ask (it does not support elicitation); nothing was sent. Use an MCP client "
            "that supports elicitation, or ask the robot's operator to change the policy."
        )
    if answer == "no console":
        return (
            f"The safety policy requires the person at the operator console to confirm {what} (approvals = "
            "'console'), but no operator console is served (start the server with --console); nothing was "
            "sent. Tell the user."
        )
    if answer == "timeout":
        return (
            f"The person did not answer the confirmation for {what} within {policy.confirm_timeout:g} s, so "
            "nothing was sent (a late yes could move the robot when the moment has passed)."
        )
    return f"Could not ask the person to confirm {what}, so nothing was sent."
