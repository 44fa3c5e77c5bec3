"""``navigate_to``: send the robot to a pose on its map (Nav2 ``NavigateToPose`` / ``NavigateThroughPoses``,
ROS 1 ``move_base``), checked against the map and the geofence first, with a picture of what happened."""

from __future__ import annotations

import asyncio
import math
from dataclasses import dataclass, replace
from typing import Annotated, Any

from pydantic import BaseModel, Field

from rosbridge_mcp_server.errors import PolicyRefusal, RosbridgeError
from rosbridge_mcp_server.robot.frames import planar_pose
from rosbridge_mcp_server.robot.goals import UNCONFIRMED_STATUS, Goal
from rosbridge_mcp_server.robot.lifecycle import inactive_reason
from rosbridge_mcp_server.robot.map_reader import read_map
from rosbridge_mcp_server.robot.namespaces import SeveralNamespacesError, find_namespace
from rosbridge_mcp_server.robot.navigation import (
    GoalPose,
    NavigationAction,
    Progress,
    Scene,
    goal_request,
    navigation_action,
    place,
    survey,
)
from rosbridge_mcp_server.robot.nodes import node_names
from rosbridge_mcp_server.robot.occupancy import Grid, Pose2D
from rosbridge_mcp_server.tools.arguments import JsonValue
from rosbridge_mcp_server.tools.base import (
    ACTS_ON_ROBOT,
    LongWork,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolImage,
    ToolSpec,
)
from rosbridge_mcp_server.tools.goal_argument import GoalArgument, read_goal
from rosbridge_mcp_server.tools.namespaces import (
    NamespaceArgument,
    choose_one,
    given_namespace,
    non_defaults,
)

__all__ = ["SPEC", "NavigateAnswer", "run"]

#: The robot's frame (Nav2's robot_base_frame and move_base's default).
BASE_FRAME = "base_link"
#: How long the map and /tf are waited for before "not ready".
_READY_WAIT = 3.0
_MAX_TIMEOUT = 3600.0
_CANCELLED_BY = {
    "timeout": "cancelled: it did not finish within the timeout",
    "request_cancelled": "cancelled because the tool call was cancelled",
    "cancel_action": "cancelled by cancel_action",
    "stop_robot": "cancelled by stop_robot",
    "estop": "cancelled by E-STOP on the operator console",
}


class NavigateAnswer(BaseModel):
    """How the navigation ended; poses are [x m, y m, yaw degrees] in the map frame."""

    goal_id: str = Field(description="The goal's id (cancel_action takes it)")
    status: str = Field(description="succeeded, canceled, aborted, ... in the bridge's words")
    succeeded: bool
    final: list[float] | None = Field(description="The robot's pose from /tf after the goal ended")
    distance_to_goal: float | None = Field(description="Metres from the final pose to the (last) goal")
    canceled_by: str | None


SPEC = ToolSpec(
    name="navigate_to",
    title="Go somewhere",
    description=(
        "Drive with Nav2/move_base to a map pose, a place or a relative move, checked on the map "
        'and geofence. Example: {"forward": 1, "turn": 90}'
    ),
    hints=ACTS_ON_ROBOT,
    acts_on="action",
    output=NavigateAnswer,
    long_work=LongWork(cancelled="its navigation goal was cancelled on the robot"),
)


class _Refused(ToolFailure):
    """A refused or failed navigation, with the map picture that shows why."""

    def __init__(self, text: str, image: bytes | None) -> None:
        super().__init__(text)
        self.images = (ToolImage(image, "image/png"),) if image is not None else ()


async def _is_turtlesim(ctx: ToolContext) -> bool:
    """Whether the robot is turtlesim (as the plain ``--demo`` is), which has no Nav2 to point at."""
    try:
        return "/turtlesim" in await node_names(ctx.graph)
    except RosbridgeError:
        return False


def _draw(
    grid: Grid,
    *,
    robot: Pose2D | None,
    goals: list[Pose2D],
    start: Pose2D | None,
    driven: list[tuple[float, float]],
    ctx: ToolContext,
) -> bytes:
    from rosbridge_mcp_server.pictures.drawing import png_bytes  # noqa: PLC0415 - on first use
    from rosbridge_mcp_server.pictures.navigation import draw_scene  # noqa: PLC0415 - on first use

    rules = ctx.config.policy.navigation
    picture = draw_scene(
        grid,
        robot=robot,
        goals=goals,
        start=start,
        driven=driven,
        allowed=dict(rules.allowed_zones),
        keep_out=dict(rules.keep_out),
    )
    return png_bytes(picture.image)


async def run(
    ctx: ToolContext,
    *,
    goal: Annotated[
        JsonValue,
        Field(
            description='e.g. {"x": 2, "y": 1, "yaw": 90} (m, DEGREES; no yaw: same heading), "dock", a list',
        ),
    ] = None,
    frame: Annotated[str, Field(description='e.g. odom ("" = map)')] = "",
    forward: Annotated[float, Field(description="Metres, e.g. 1.0")] = 0.0,
    left: Annotated[float, Field(description="Metres, e.g. -0.5")] = 0.0,
    turn: Annotated[float, Field(description="Degrees left, e.g. 90")] = 0.0,
    timeout: Annotated[float, Field(gt=0, le=_MAX_TIMEOUT, description="Seconds, e.g. 120")] = 300.0,
    namespace: NamespaceArgument = None,
) -> ToolAnswer:
    """Resolve the goal, check readiness and the map, send it, report progress, draw the outcome."""
    request = read_goal(goal, frame, (forward, left, turn), dict(ctx.config.policy.places))
    ros1 = (await ctx.client.dialect()).version == 1
    if request.kind == "waypoints" and ros1:
        raise ToolFailure(
            "waypoints need Nav2's NavigateThroughPoses (ROS 2); move_base takes one goal at a time. Nothing "
            "was sent."
        )
    action = navigation_action(ros1=ros1, waypoints=request.kind == "waypoints")
    given = {"goal": goal, "frame": frame, "forward": forward, "left": left, "turn": turn, "timeout": timeout}
    prefix, note, hint = await _robot_namespace(ctx, namespace, action.name, non_defaults(run, given))
    ready = await _ready(ctx, prefix, action, hint, ros1=ros1)
    scene = await _scene(ctx, ready, await _goal_poses(ctx, request, ready))
    answer = await _drive(ctx, ready, scene, NavigationAction(prefix + action.name, action.type), timeout)
    return answer if note is None else replace(answer, text=f"{note}\n{answer.text}")


@dataclass(frozen=True)
class _Ready:
    """What Nav2 being ready gave: the map, and the robot's pose on it; the robot's namespace."""

    grid: Grid
    start: Pose2D
    prefix: str

    @property
    def map_frame(self) -> str:
        return self.grid.frame_id or "map"


async def _ready(
    ctx: ToolContext, prefix: str, action: NavigationAction, hint: str | None, *, ros1: bool
) -> _Ready:
    """Is Nav2 ready? The map, the robot on it, the navigator active: each missing piece is said, and
    nothing is sent."""
    not_ready: list[str] = []
    if hint is not None:
        server = "move_base" if ros1 else "bt_navigator"
        not_ready.append(f"no action server {prefix + action.name} (is {server} running?){hint}")
        if await _is_turtlesim(ctx):
            not_ready.append("turtlesim has no Nav2; the built-in demo has one: --demo --demo-world nav2")
    grid, problem = await read_map(ctx.client, ctx.graph, f"{prefix}/map", _READY_WAIT)
    if problem is not None:
        not_ready.append(problem)
    map_frame = (grid.frame_id if grid is not None else "") or "map"
    start = await planar_pose(ctx.client, ctx.graph, map_frame, BASE_FRAME, _READY_WAIT, namespace=prefix)
    if isinstance(start, str):
        not_ready.append(f"no transform from {map_frame} to {BASE_FRAME} on {prefix}/tf: {start}")
    if not ros1 and hint is None:
        state = await inactive_reason(ctx.client, ctx.graph, f"{prefix}/bt_navigator")
        if state is not None:
            not_ready.append(f"the navigator {state}")
    if not_ready or grid is None or isinstance(start, str):
        missing = "; ".join(reason.rstrip(". ") for reason in not_ready)
        raise ToolFailure(f"Nav2 is not ready: {missing}. Nothing was sent.")
    return _Ready(grid, start, prefix)


async def _goal_poses(ctx: ToolContext, request: GoalArgument, ready: _Ready) -> list[GoalPose]:
    """The goal's poses, in the frame they were given in (a place and a relative move: the map's)."""
    map_frame, start = ready.map_frame, ready.start
    if request.kind == "place":
        px, py, pyaw = dict(ctx.config.policy.places)[request.place]
        return [GoalPose(map_frame, px, py, math.radians(pyaw))]
    if request.kind == "relative":
        forward, left, turn = request.move
        moved = place(GoalPose(map_frame, forward, left, math.radians(turn)), start)
        return [GoalPose(map_frame, moved.x, moved.y, moved.yaw)]
    if request.kind == "waypoints":
        return [
            GoalPose(map_frame, x, y, start.yaw if yaw is None else math.radians(yaw))
            for x, y, yaw in request.ways
        ]
    x, y, yaw = request.ways[0]
    goal_frame = request.frame.strip().lstrip("/") or map_frame
    if yaw is not None:
        return [GoalPose(goal_frame, x, y, math.radians(yaw))]
    # Keep the robot's heading: its yaw in the map, seen from the goal's frame.
    origin = await planar_pose(
        ctx.client, ctx.graph, map_frame, goal_frame, _READY_WAIT, namespace=ready.prefix
    )
    if isinstance(origin, str):
        raise ToolFailure(
            f"The goal's frame {goal_frame} cannot be placed in {map_frame}: {origin}. Give the goal "
            f"in {map_frame}, or check /tf (get_transform). Nothing was sent."
        )
    return [GoalPose(goal_frame, x, y, start.yaw - origin.yaw)]


async def _scene(ctx: ToolContext, ready: _Ready, poses: list[GoalPose]) -> Scene:
    """The goal's poses placed on the map (through /tf), with the map and the robot already read."""
    scene = await survey(
        ctx.client,
        ctx.graph,
        map_topic=f"{ready.prefix}/map",
        base_frame=BASE_FRAME,
        poses=poses,
        timeout=_READY_WAIT,
        grid=ready.grid,
        namespace=ready.prefix,
    )
    if len(scene.goals) != len(poses):
        raise ToolFailure(
            f"The goal cannot be placed on the map: {'; '.join(scene.problems)}. Give it in "
            f"{ready.map_frame}, or check /tf (get_transform). Nothing was sent."
        )
    return replace(scene, robot=ready.start)


async def _drive(
    ctx: ToolContext, ready: _Ready, scene: Scene, action: NavigationAction, timeout: float
) -> ToolAnswer:
    """Send the goal through the guard, report its progress, and answer with where the robot ended up."""
    from rosbridge_mcp_server.robot.acting import send_goal  # noqa: PLC0415 - on the first act

    goals, grid, start = list(scene.goals), ready.grid, ready.start
    body = await goal_request(ctx.graph, action.type, ready.map_frame, goals)
    progress = Progress(start, goals[-1])

    async def on_feedback(running: Goal, feedback: dict[str, Any]) -> None:
        said = progress.feed(running.goal_id, feedback)
        await ctx.report_progress(float(running.feedback_count), None, said)

    try:
        outcome = await send_goal(
            ctx,
            tool=SPEC.name,
            action=action.name,
            action_type=action.type,
            goal=body,
            timeout=timeout,
            on_feedback=on_feedback,
            scene=scene,
        )
    except PolicyRefusal as exc:
        image = await asyncio.to_thread(_draw, grid, robot=start, goals=goals, start=None, driven=[], ctx=ctx)
        raise _Refused(f"{exc} The picture shows the robot (blue) and the goal (magenta).", image) from None
    found = await planar_pose(
        ctx.client, ctx.graph, ready.map_frame, BASE_FRAME, _READY_WAIT, namespace=ready.prefix
    )
    final = found if isinstance(found, Pose2D) else None
    progress.ended_at(final)
    image = await asyncio.to_thread(
        _draw, grid, robot=final, goals=goals, start=start, driven=progress.track, ctx=ctx
    )
    return _answer(outcome, frame=ready.map_frame, goals=goals, final=final, progress=progress, image=image)


async def _robot_namespace(
    ctx: ToolContext, namespace: str | None, action: str, asked: dict[str, Any]
) -> tuple[str, str | None, str | None]:
    """(namespace, the note saying it was found, the missing action's hint or ``None`` when it is served):
    the one given, else the root's navigator, else the one namespace that has one (several: each call)."""
    chosen = given_namespace(ctx, namespace)
    if chosen is not None:
        return chosen, None, await ctx.graph.missing_action(chosen + action)
    hint = await ctx.graph.missing_action(action)
    if hint is None:
        return "", None, None
    try:
        found = await find_namespace(ctx.graph, None, action, kind="action", present=False)
    except SeveralNamespacesError as exc:
        raise choose_one(exc, SPEC.name, asked) from None
    if not found.namespace:
        return "", None, hint
    return found.namespace, found.note, await ctx.graph.missing_action(found.namespace + action)


def _answer(
    outcome: Goal,
    *,
    frame: str,
    goals: list[Pose2D],
    final: Pose2D | None,
    progress: Progress,
    image: bytes,
) -> ToolAnswer:
    last = goals[-1]
    distance = heading = None
    if final is not None:
        distance = round(math.hypot(final.x - last.x, final.y - last.y), 3)
        turned = final.yaw - last.yaw
        heading = round(math.degrees(math.atan2(math.sin(turned), math.cos(turned))), 1)
    data = NavigateAnswer(
        goal_id=outcome.goal_id,
        status=outcome.status,
        succeeded=outcome.succeeded,
        final=None if final is None else final.rounded(),
        distance_to_goal=distance,
        canceled_by=outcome.canceled_by,
    )
    lines = [_headline(outcome, frame, goals)]
    error = _navigator_error(outcome)
    if error:
        lines.append(f"Navigator error {error}.")
    if final is not None:
        lines.append(
            f"Robot now at ({final.x:.2f}, {final.y:.2f}, {math.degrees(final.yaw):.0f}°): "
            f"{distance:.2f} m and {abs(heading or 0):.0f}° from the goal; drove {progress.driven:.2f} m in "
            f"{progress.seconds:.1f} s"
            + (f", {progress.recoveries} recoveries" if progress.recoveries else "")
            + "."
        )
    else:
        lines.append("The robot's final pose is not known (/tf did not tell).")
    lines.append("Picture: start grey square, path driven green, goal magenta, robot blue.")
    return ToolAnswer(text="\n".join(lines), data=data, images=(ToolImage(image, "image/png"),))


def _headline(outcome: Goal, frame: str, goals: list[Pose2D]) -> str:
    target = ", then ".join(f"({g.x:.2f}, {g.y:.2f}, {math.degrees(g.yaw):.0f}°)" for g in goals)
    head = f"Navigation to {target} in {frame}: {outcome.status}"
    if outcome.status == UNCONFIRMED_STATUS:
        head += (
            "; a cancel was sent but the robot has not confirmed the goal ended: it may still be moving. "
            "Call stop_robot, or check the robot"
        )
    elif outcome.canceled_by is not None:
        head += f" ({_CANCELLED_BY.get(outcome.canceled_by, outcome.canceled_by)})"
    return head + "."


def _navigator_error(outcome: Goal) -> str | None:
    """The navigator's ``error_code: error_msg`` of a goal that did not succeed, when its result has one."""
    result = outcome.result or {}
    if outcome.succeeded or not (result.get("error_code") or result.get("error_msg")):
        return None
    return f"{result.get('error_code', 0)}: {result.get('error_msg', '')}".strip()
