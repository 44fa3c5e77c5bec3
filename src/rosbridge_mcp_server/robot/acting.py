"""Checked sends: every act on the robot goes through here and through the safety seam (cancels: unguarded).

Each function takes what a caller gave (names, types, a message), makes the name absolute, has the client's
:class:`~rosbridge_mcp_server.client.Dialect` spell the type for the bridge, compares it with the graph,
checks the message as the bridge will read it against the type's definitions (raising a
:class:`~rosbridge_mcp_server.errors.NotSentError` that carries an example of the type), and only then asks
the guard of :mod:`rosbridge_mcp_server.robot.seam` whether the act may happen (:func:`approved`), telling
it the outcome once per act (:func:`carry_out`). Messages stay as the caller wrote them (time fields in
either spelling): the client respells them once, on the way out.

Nothing here knows MCP: the server hands in ``ask_person`` (its elicitation) through the tool's context.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

from rosbridge_mcp_server.client import Dialect
from rosbridge_mcp_server.errors import Advice, NotSentError, PolicyRefusal, RequestTimeoutError, ServiceError
from rosbridge_mcp_server.robot.arm_goals import carried_arm
from rosbridge_mcp_server.robot.effects import parameter_write, service_effects, topic_effects
from rosbridge_mcp_server.robot.goals import CancelReport, Goal, GoalFeedback, cancel_goals, run_goal
from rosbridge_mcp_server.robot.goals.caused import caused_by_call, caused_by_publish
from rosbridge_mcp_server.robot.graph import is_missing_service
from rosbridge_mcp_server.robot.messages import require_fit
from rosbridge_mcp_server.robot.motion_goals import carried_goal, read_motion
from rosbridge_mcp_server.robot.names import absolute_name, check_name_for_ros, did_you_mean
from rosbridge_mcp_server.robot.navigation import Scene, survey
from rosbridge_mcp_server.robot.parameters import SetOutcome, apply_set, plan_set
from rosbridge_mcp_server.robot.seam import Act, Approving, approved, cancelled_why, carry_out
from rosbridge_mcp_server.robot.velocity import clamp_text, is_velocity_type, stamped

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.activity import SessionActivity
    from rosbridge_mcp_server.robot.arm_scene import ArmScene
    from rosbridge_mcp_server.robot.gate import SendGate
    from rosbridge_mcp_server.robot.goals import GoalRegistry
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = [
    "PING_LIMIT",
    "SCENE_TIMEOUT",
    "Acting",
    "Published",
    "ServiceReply",
    "StreamProgress",
    "Streamed",
    "Timeouts",
    "call_service",
    "motion_scene",
    "publish_once",
    "publish_stream",
    "require_action_server",
    "send_goal",
    "set_parameter",
    "stop_goals",
]

_log = logging.getLogger(__name__)


class Timeouts(Protocol):
    """The one setting an act reads (the server's ``Config`` is one)."""

    @property
    def request_timeout(self) -> float: ...


class Acting(Approving, Protocol):
    """What an act needs: what the seam reads to approve it (the guard, who to ask, the caller), the robot
    session's parts and the call's own (a tool's ``ToolContext`` is one)."""

    @property
    def client(self) -> RosbridgeClient: ...
    @property
    def config(self) -> Timeouts: ...
    @property
    def graph(self) -> RosGraph: ...
    @property
    def activity(self) -> SessionActivity: ...
    @property
    def goals(self) -> GoalRegistry: ...
    @property
    def gate(self) -> SendGate: ...


#: Longest wait for the bridge's pong before a publish (less when the configured request timeout is shorter).
PING_LIMIT = 3.0


# --- topics -----------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Published:
    """What was published."""

    topic: str
    type: str  #: as the bridge was given it
    message: dict[str, Any]  #: as sent
    #: How the safety policy changed the message before it was sent (velocity caps in clamp mode), or None.
    adjusted: str | None = None


async def publish_once(
    ctx: Acting, *, tool: str, topic: str, message_type: str, message: dict[str, Any]
) -> Published:
    """Check *message* against *message_type* and the topic's type in the graph, then publish it once.

    Before the publish, a ping proves the bridge reads the connection now (see :func:`_bridge_is_reading`);
    then the send gate (``robot/gate.py``) says whether it may go now: no stop since the call began, no
    latched E-STOP, and a free slot within the topic's rate.
    """
    ticket = ctx.gate.ticket()  # a stop from now on voids this call
    name, bridge_type, body = await _checked_message(ctx, topic, message_type, message)
    act = await approved(
        ctx,
        Act(
            tool,
            "topic",
            name,
            bridge_type,
            body,
            effects=topic_effects(name, bridge_type),
            given=_given(topic, name),
            scene=await motion_scene(ctx, "topic", name, bridge_type, body),
        ),
    )
    # A goal it starts (a goal topic, a goal pose) is remembered for the stops once it is sent.
    caused = caused_by_publish(act.name, act.payload, act.effects, (await ctx.graph.dialect()).version)

    async def send() -> None:
        await _bridge_is_reading(ctx)
        # Advertised first, so that nothing but the message itself is sent after the gate said yes.
        await ctx.client.advertise(act.name, act.type)
        await ctx.gate.pace(ticket, act)
        await ctx.client.publish(act.name, act.type, act.payload)
        ctx.goals.caused(caused)
        ctx.graph.remember_publishing(act.name, act.type)
        # stop_robot zeroes every velocity topic this session has driven.
        ctx.activity.published(act.name, act.type, act.payload)

    await carry_out(ctx, act, send)
    adjusted = _adjusted(act.type, body, act.payload)
    return Published(act.name, act.type, act.payload, adjusted)


async def _checked_message(
    ctx: Acting, topic: str, message_type: str, message: dict[str, Any]
) -> tuple[str, str, dict[str, Any]]:
    """The absolute topic, the type as the bridge spells it, and the message, checked."""
    name = absolute_name(topic, "topic")
    dialect = await ctx.graph.dialect()
    check_name_for_ros(name, "topic", dialect.version)
    bridge_type = dialect.message_type(message_type)
    typedefs = await ctx.graph.message_typedefs(message_type)

    graph_type = await ctx.graph.publishing_type(name)
    if graph_type and not dialect.same_type(graph_type, bridge_type):
        raise NotSentError(
            f"Topic {name} has type {graph_type}, not {bridge_type}; rosbridge would drop the message."
        ).advise(Advice.TOPIC_TYPE, graph_type)
    require_fit(
        _as_read(dialect, message),
        typedefs,
        type_name=bridge_type,
        ros_version=dialect.version,
        nothing_sent="Nothing was published",
        looks_like=f"A {bridge_type} message",
    )
    return name, bridge_type, message


def _adjusted(type_name: str, before: Any, after: Any) -> str | None:
    """How the guard changed a message before it was sent, or ``None``: a velocity command scaled to the caps,
    or a motion goal's speed (DriveOnHeading, BackUp, carried by a topic) lowered to them."""
    if after == before:
        return None
    if is_velocity_type(type_name):
        return clamp_text(type_name, before, after)
    return "lowered the goal's speed to the [velocity] max_linear cap"


def _given(written: str, canonical: str) -> str | None:
    """The name as the caller wrote it, for the audit, when it is not the canonical one."""
    return written if written != canonical else None


def _as_read(dialect: Dialect, message: dict[str, Any]) -> Any:
    """*message* as the bridge will read it (ROS 1 time fields respelled), for checking only: the client
    respells what it sends itself, so the message that goes on stays as the caller wrote it."""
    return dialect.outgoing(message)


#: Told of a stream's progress: (messages sent, messages planned).
StreamProgress = Callable[[int, int], Awaitable[None]]


@dataclass(frozen=True)
class Streamed:
    """What a publish stream did."""

    topic: str
    type: str
    message: dict[str, Any]  #: as sent each time
    rate_hz: float  #: as approved (the guard may lower it)
    duration: float  #: as approved
    planned: int
    sent: int
    cancelled: bool  #: stopped early (an MCP cancel, or the server stopping)
    zero: dict[str, Any] | None  #: the all-zero message sent at the end (velocity types), else None
    stopped: bool = False  #: ended early because stop_robot (or the operator's E-STOP) asked
    #: How the safety policy changed the message before it was sent (velocity caps in clamp mode), or None.
    adjusted: str | None = None
    #: Who stopped it early, when ``stopped`` (the stop's ``by``: "stop_robot", or the operator's E-STOP).
    stopped_by: str = ""
    #: Ended before ``planned``: the topic's rate cap, shared with every other sender on it, left no slot
    #: within the stream's duration.
    rate_limited: bool = False


async def publish_stream(
    ctx: Acting,
    *,
    tool: str,
    topic: str,
    message_type: str,
    message: dict[str, Any],
    rate_hz: float,
    duration: float,
    on_progress: StreamProgress | None = None,
) -> Streamed:
    """Publish *message* at *rate_hz* for *duration* seconds, on an absolute schedule (no drift).

    The stream is approved once, at the start, with its rate and duration (the guard may clamp both); each
    message then passes the send gate (``robot/gate.py``): a stop or a latched E-STOP ends the stream (its
    first message refused: :class:`PolicyRefusal`), and the topic's rate cap may hold a message back (a slot
    after the stream's planned end ends it early). A velocity stream (``Twist``, ``TwistStamped``) always
    ends with one all-zero message, also when it is cancelled; cancellation stops it at once otherwise and is
    re-raised after that zero message.
    """
    ticket = ctx.gate.ticket()  # a stop from now on voids this stream
    name, bridge_type, body = await _checked_message(ctx, topic, message_type, message)
    act = await approved(
        ctx,
        Act(
            tool,
            "topic",
            name,
            bridge_type,
            body,
            rate_hz=rate_hz,
            duration=duration,
            effects=topic_effects(name, bridge_type),
            given=_given(topic, name),
            scene=await motion_scene(ctx, "topic", name, bridge_type, body),
        ),
    )
    caused = caused_by_publish(act.name, act.payload, act.effects, (await ctx.graph.dialect()).version)
    rate = act.rate_hz or rate_hz
    length = act.duration if act.duration is not None else duration
    planned = max(1, round(length * rate))
    zero = _zero_velocity(act.type, act.payload)
    sent = 0
    cancelled = False
    every = max(1, round(rate / 5))  # progress about five times a second at most
    loop = asyncio.get_running_loop()
    stopped = False
    stopped_by = ""  # who, once stopped: the stream's or the gate's stopper
    rate_limited = False
    try:
        # Registered before anything of it is sent (the ping included), so that stop_robot and the E-STOP
        # see it and end it: pause() returns early when asked.
        with ctx.activity.stream(act.name, act.type) as running:
            if not await running.unless_stopped(_bridge_is_reading(ctx)):
                await ctx.client.advertise(act.name, act.type)
            start = loop.time()
            # A slot (the topic's rate, shared with every other sender) later than this ends the stream.
            latest = start + length + 1 / rate
            for index in range(planned):
                if await running.pause(start + index / rate - loop.time()):
                    stopped, stopped_by = True, running.stopped_by
                    break
                try:
                    if not await ctx.gate.pace(ticket, act, latest=latest):
                        rate_limited = True
                        break
                except PolicyRefusal:
                    if sent == 0:
                        raise
                    stopped, stopped_by = True, ctx.gate.stopped_by
                    break
                await ctx.client.publish(act.name, act.type, act.payload)
                if sent == 0:
                    ctx.graph.remember_publishing(act.name, act.type)
                    ctx.activity.published(act.name, act.type, act.payload)
                    ctx.goals.caused(caused)
                sent += 1
                if on_progress is not None and (sent % every == 0 or sent == planned):
                    await on_progress(sent, planned)
    except asyncio.CancelledError:
        cancelled = True
        raise
    except PolicyRefusal:
        raise  # the gate refused its first message and audited it: nothing of the stream was sent
    except BaseException as exc:
        ctx.guard.record(act, f"failed after {sent} of {planned}: {type(exc).__name__}: {exc}")
        raise
    finally:
        if cancelled:
            # Recorded first: inside a cancelled anyio scope (the SDK's) every await raises again, the
            # shielded one below too, so a line written after it was lost.
            ctx.guard.record(act, f"{cancelled_why()} after {sent} of {planned}")
        if zero is not None and sent > 0:
            # Shielded: a second cancel must not leave the robot moving.
            await asyncio.shield(_publish_quietly(ctx, act, zero))
    ctx.guard.record(act, f"{f'stopped by {stopped_by} after' if stopped else 'sent'} {sent} of {planned}")
    adjusted = _adjusted(act.type, body, act.payload)
    return Streamed(
        act.name,
        act.type,
        act.payload,
        rate,
        length,
        planned,
        sent,
        cancelled,
        zero if sent > 0 else None,  # sent only after a message that moved
        stopped,
        adjusted,
        stopped_by,
        rate_limited,
    )


async def _publish_quietly(ctx: Acting, act: Act, message: dict[str, Any]) -> None:
    try:
        await ctx.client.publish(act.name, act.type, message)
    except Exception:
        _log.warning("could not send the zero message that ends the stream on %s", act.name, exc_info=True)


def _zero_velocity(bridge_type: str, message: dict[str, Any]) -> dict[str, Any] | None:
    """The all-zero command that ends a stream of velocity commands (a stream of them ends with one, so the
    robot stops); ``None`` for other types."""
    if not is_velocity_type(bridge_type):
        return None
    still = {"linear": {"x": 0.0, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": 0.0}}
    if not stamped(bridge_type):
        return still
    header = message.get("header")
    frame = header.get("frame_id", "") if isinstance(header, dict) else ""
    # The stamp is left out: rosbridge stamps a root header it is not given (ROS 1; ROS 2 2.0.7 / 2.7.0 on).
    return {"header": {"frame_id": frame}, "twist": still}


async def _bridge_is_reading(ctx: Acting) -> None:
    """Refuse to publish into a connection the bridge is not reading.

    A frozen bridge (or a link that died without a close) still takes our frame into the socket buffer and
    acts on it whenever it wakes up: a late velocity command. Seen against a real 0.11.17 bridge stopped with
    SIGSTOP: the publish "succeeded" and the message arrived after SIGCONT. One ping round trip first proves
    it reads the connection now.
    """
    limit = min(ctx.config.request_timeout, PING_LIMIT)
    try:
        await ctx.client.ping(limit)
    except RequestTimeoutError as exc:
        raise NotSentError(
            f"rosbridge at {ctx.client.url} did not answer a ping within {limit:g} s (the bridge is frozen, "
            "or the network to the robot is down), so nothing was published: a message sent now could reach "
            "the robot late and move it then. Check the robot and its network, then try again."
        ) from exc


# --- services ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ServiceReply:
    """A service's response."""

    service: str
    type: str  #: as the graph reports it (or as given, when the graph cannot tell)
    response: Any  #: the response message (an object on every bridge we know)


async def call_service(
    ctx: Acting, *, tool: str, service: str, service_type: str, request: dict[str, Any], timeout: float
) -> ServiceReply:
    """Check the request when rosapi can describe the type, call the service, return its response.

    The send gate is asked right before the call's frame is written (after a lane is opened for it)."""
    ticket = ctx.gate.ticket()  # a stop from now on voids this call
    name = absolute_name(service, "service")
    dialect = await ctx.graph.dialect()
    check_name_for_ros(name, "service", dialect.version)
    given_type = dialect.service_type(service_type)

    graph_type = await ctx.graph.service_type(name, cached=True)
    if graph_type and not dialect.same_type(graph_type, given_type):
        # The cached type may be stale (the service was offered anew with another type): ask once more.
        graph_type = await ctx.graph.service_type(name)
    if graph_type and not dialect.same_type(graph_type, given_type):
        raise NotSentError(
            f"Service {name} has type {graph_type}, not {given_type}. Build the request for {graph_type} "
            "and call again with that service_type."
        )
    srv_type = graph_type or given_type
    if graph_type:
        typedefs = await ctx.graph.service_request_typedefs(srv_type)
        if typedefs:
            fit = "The service was not called"
            require_fit(
                _as_read(dialect, request),
                typedefs,
                ros_version=dialect.version,
                nothing_sent=fit,
                looks_like="A request",
            )

    # What the call does (an action's goal, parameter writes, motion) is judged too, not only its name.
    effects = service_effects(name, srv_type, request, dialect.version)
    scene = await motion_scene(ctx, "service", name, srv_type, request)
    act = await approved(
        ctx,
        Act(
            tool,
            "service",
            name,
            srv_type,
            request,
            effects=effects,
            given=_given(service, name),
            scene=scene,
        ),
    )
    caused = caused_by_call(act.name, act.payload, act.effects, dialect.version)

    def check() -> None:
        ctx.gate.check(ticket, act)
        # The goal a send_goal call starts is remembered for the stops before the call goes out: its answer
        # may never come while the goal runs.
        ctx.goals.caused(caused)

    try:
        response = await carry_out(
            ctx,
            act,
            lambda: ctx.client.call_service(act.name, act.payload, timeout=timeout, check=check),
        )
    except ServiceError as exc:
        ctx.goals.forget_caused(caused)  # the bridge refused the call: no goal started
        # rosapi does not list hidden services (ROS 2 `_action/...`), so an unlisted name is still tried;
        # the bridge answers at once when nothing offers it.
        if not is_missing_service(exc):
            raise
        ctx.graph.forget_service(act.name)
        hint = did_you_mean(act.name, await ctx.graph.service_names())
        raise NotSentError(f"Service {act.name} is not offered by any node.{hint}").advise(
            Advice.SERVICES
        ) from exc
    return ServiceReply(act.name, srv_type, response)


# --- action goals -----------------------------------------------------------------------------------------


async def send_goal(
    ctx: Acting,
    *,
    tool: str,
    action: str,
    action_type: str,
    goal: dict[str, Any],
    timeout: float,
    on_feedback: GoalFeedback | None = None,
    scene: Scene | ArmScene | None = None,
) -> Goal:
    """Check the goal against the action server's type, run it until it ends, and return how it ended.

    *on_feedback* gets the running goal (``goal_id``, ``feedback_count``) and each feedback, so that a caller
    can name the goal (to cancel it) while it runs. The goal is tracked (seen by stop_robot and the E-STOP)
    from before anything of it is sent; right before the goal itself is sent, the send gate is asked, and a
    goal whose cancel or timeout came first is not sent at all. A motion goal (``robot/motion_goals.py``) is
    judged with the robot's map and pose: *scene* when the caller learnt them, else they are learnt here (as
    for a goal carried by a topic or a service), so that the guard judges a goal the same whichever tool and
    carrier sends it.
    """
    ticket = ctx.gate.ticket()  # a stop from now on voids this goal
    name = absolute_name(action, "action")
    dialect = await ctx.graph.dialect()
    check_name_for_ros(name, "action", dialect.version)
    wire_type = dialect.action_type(action_type)
    await require_action_server(ctx.graph, name, action_type)
    typedefs = await ctx.graph.action_goal_typedefs(action_type)
    if typedefs:
        require_fit(
            _as_read(dialect, goal),
            typedefs,
            ros_version=dialect.version,
            nothing_sent="No goal was sent",
            looks_like="A goal",
        )

    if scene is None:
        scene = await motion_scene(ctx, "action", name, wire_type, goal)
    act = await approved(
        ctx, Act(tool, "action", name, wire_type, goal, given=_given(action, name), scene=scene)
    )
    outcome: Goal = await carry_out(
        ctx,
        act,
        lambda: run_goal(
            ctx.goals,
            act.name,
            action_type,
            act.payload,
            timeout=timeout,
            on_feedback=on_feedback,
            before_send=lambda: ctx.gate.check(ticket, act),
        ),
    )
    return outcome


#: How long a motion goal not sent by navigate_to waits for the map and /tf before it is judged.
SCENE_TIMEOUT = 3.0


async def motion_scene(
    ctx: Acting, kind: str, name: str, type_name: str, payload: Any
) -> Scene | ArmScene | None:
    """The map (``<namespace>/map``) and the robot (``base_link``) a motion goal the act carries is judged
    against, whichever carrier (``robot/motion_goals.py``); for an arm's trajectory or gripper goal
    (``robot/arm_goals.py``) the arm's description and joint positions; ``None`` when it carries none, or one
    the fence cannot read or place (the guard says why)."""
    from rosbridge_mcp_server.robot.arm_scene import learn_arm  # noqa: PLC0415 - arm acts only

    arm = carried_arm(kind, name, type_name, payload)
    if arm is not None:
        if arm.kind == "switch" or isinstance(arm.body, str):
            return None
        return await learn_arm(ctx.client, ctx.graph, timeout=min(SCENE_TIMEOUT, ctx.config.request_timeout))
    carried = carried_goal(kind, name, type_name, payload)
    if carried is None:
        return None
    motion = read_motion(carried)
    if isinstance(motion, str) or motion.unplaceable is not None:
        return None
    return await survey(
        ctx.client,
        ctx.graph,
        map_topic=f"{carried.namespace}/map",
        base_frame="base_link",
        namespace=carried.namespace,
        poses=motion.poses,
        along=motion.along,
        timeout=min(SCENE_TIMEOUT, ctx.config.request_timeout),
    )


async def require_action_server(graph: RosGraph, name: str, action_type: str | None = None) -> None:
    """Fail fast on an action nobody serves, or (given *action_type*) on a type that is not the server's."""
    hint = await graph.missing_action(name)
    if hint is not None:
        raise NotSentError(f"No action server {name} is running on the robot.{hint}").advise(Advice.ACTIONS)
    if action_type is None:
        return
    found = await graph.action_type(name)
    if found is None:
        return
    if not Dialect.same_action(found, action_type):
        raise NotSentError(
            f"Action {name} has type {found}, not {action_type}. Send a goal of type {found} instead."
        )


async def stop_goals(ctx: Acting, *, action: str, goal_id: str | None = None) -> CancelReport:
    """Cancel one goal of *action* (by id) or all of them, after checking that the action is served.

    A cancel only stops what the robot does, so it does not ask the guard.
    """
    name = absolute_name(action, "action")
    hint = await ctx.graph.missing_action(name)
    if hint is not None:
        raise NotSentError(
            f"No action server {name} is running on the robot, so there is nothing to cancel.{hint}"
        ).advise(Advice.ACTIONS)
    return await cancel_goals(ctx.goals, name, goal_id)


# --- parameters -------------------------------------------------------------------------------------------


async def set_parameter(ctx: Acting, *, tool: str, name: str, value: Any) -> SetOutcome:
    """Check the parameter (name form, and on ROS 2 that its node has it), then set it and read it back."""
    ticket = ctx.gate.ticket()  # a stop from now on voids this call
    planned = await plan_set(ctx.graph, ctx.client, name, value)
    full = planned.name.full
    dialect = await ctx.graph.dialect()
    act = await approved(
        ctx,
        Act(
            tool,
            "parameter",
            full,
            "",
            planned.value,
            effects=(parameter_write(full, dialect.version),),
            given=_given(name, full),
        ),
    )
    outcome: SetOutcome = await carry_out(
        ctx,
        act,
        lambda: apply_set(
            ctx.graph, ctx.client, planned, act.payload, before_write=lambda: ctx.gate.check(ticket, act)
        ),
    )
    return outcome
