"""``navigate_to``: send the robot to a pose on its map (Nav2 ``NavigateToPose`` / ``NavigateThroughPoses``,
ROS 1 ``move_base``), checked against the map and the geofence first, with a picture of what happened."""

from __future__ import annotations

import asyncio
import difflib
import json
import math
import time
from dataclasses import replace
from typing import Annotated, Any, Final

from pydantic import BaseModel, Field

from rosbridge_mcp_server.errors import PolicyRefusal, RosbridgeError
from rosbridge_mcp_server.pictures.drawing import png_bytes
from rosbridge_mcp_server.pictures.navigation import draw_scene
from rosbridge_mcp_server.robot.acting import send_goal
from rosbridge_mcp_server.robot.goals import UNCONFIRMED_STATUS, Goal
from rosbridge_mcp_server.robot.namespaces import SeveralNamespacesError, find_namespace
from rosbridge_mcp_server.robot.navigation import (
    GoalPose,
    Scene,
    frame_pose,
    read_map,
    survey,
)
from rosbridge_mcp_server.robot.nodes import node_names
from rosbridge_mcp_server.robot.occupancy import Grid, Pose2D
from rosbridge_mcp_server.tools.arguments import JsonValue
from rosbridge_mcp_server.tools.base import (
    ACTS_ON_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolImage,
    ToolSpec,
)
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
#: The farthest a goal's coordinate (metres; degrees for a yaw) may be: beyond any map, and drawable.
MAX_COORDINATE = 100_000.0
#: Most driven-path points kept for the picture.
_MAX_TRACK = 2000

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
)


class _Refused(ToolFailure):
    """A refused or failed navigation, with the map picture that shows why."""

    def __init__(self, text: str, image: bytes | None) -> None:
        super().__init__(text)
        self.images = (ToolImage(image, "image/png"),) if image is not None else ()


def _planar(pose: Pose2D | None) -> list[float] | None:
    if pose is None:
        return None
    return [round(pose.x, 3), round(pose.y, 3), round(math.degrees(pose.yaw), 1)]


def _pose_msg(frame: str, pose: Pose2D) -> dict[str, Any]:
    half = pose.yaw / 2
    return {
        "header": {"frame_id": frame},
        "pose": {
            "position": {"x": pose.x, "y": pose.y, "z": 0.0},
            "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(half), "w": math.cos(half)},
        },
    }


#: Keys a pose is often written with, and the key meant (``theta`` is turtlesim's, in radians).
_POSE_KEYS: Final[dict[str, str]] = {
    "theta": "yaw",
    "heading": "yaw",
    "angle": "yaw",
    "yaw_deg": "yaw",
    "yaw_degrees": "yaw",
    "rotation": "yaw",
    "orientation": "yaw",
    "direction": "yaw",
}


def _shown(value: Any) -> str:
    """A value the caller gave, as JSON (as they wrote it), shortened."""
    text = json.dumps(value, ensure_ascii=False, default=str)
    return text if len(text) <= 120 else text[:120] + "…"


def _number(value: Any, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ToolFailure(f"{what} must be a finite number, not {_shown(value)}. Nothing was sent.")
    if abs(value) > MAX_COORDINATE:
        raise ToolFailure(
            f"{what} {value:g} is beyond ±{MAX_COORDINATE:g} (metres, or degrees for yaw). Nothing was sent."
        )
    return float(value)


def _meant(unknown: set[str]) -> str:
    """`` Did you mean "yaw" (degrees) for "theta"?`` for keys that stand for a pose's own, or ``""``."""
    pairs = []
    for key in sorted(unknown):
        meant = _POSE_KEYS.get(key.lower()) or next(
            iter(difflib.get_close_matches(key, ["x", "y", "yaw"])), ""
        )
        if meant:
            pairs.append(f'"{meant}"{" (degrees)" if meant == "yaw" else ""} for "{key}"')
    return f" Did you mean {', '.join(pairs)}?" if pairs else ""


def _waypoint(item: Any, where: str) -> tuple[float, float, float | None]:
    if isinstance(item, dict):
        unknown = set(item) - {"x", "y", "yaw"}
        if unknown or "x" not in item or "y" not in item:
            missing = [key for key in ("x", "y") if key not in item]
            wrong = f"unknown {', '.join(sorted(unknown))}" if unknown else f"no {' or '.join(missing)}"
            raise ToolFailure(
                f'{where} must be {{"x": m, "y": m, "yaw": degrees}} (no yaw keeps the heading); got '
                f"{_shown(item)}: {wrong}.{_meant(unknown)} Nothing was sent."
            )
        yaw = item.get("yaw")
        return (
            _number(item["x"], f"{where}.x"),
            _number(item["y"], f"{where}.y"),
            None if yaw is None else _number(yaw, f"{where}.yaw"),
        )
    if isinstance(item, list) and len(item) in (2, 3):
        yaw_value = item[2] if len(item) == 3 else None
        return (
            _number(item[0], f"{where}[0]"),
            _number(item[1], f"{where}[1]"),
            None if yaw_value is None else _number(yaw_value, f"{where}[2]"),
        )
    raise ToolFailure(
        f'{where} must be {{"x": m, "y": m, "yaw": degrees}} or [x, y, yaw]; got {_shown(item)}. Nothing was '
        "sent."
    )


async def _is_turtlesim(ctx: ToolContext) -> bool:
    """Whether the robot is turtlesim (as the plain ``--demo`` is), which has no Nav2 to point at."""
    try:
        return "/turtlesim" in await node_names(ctx.graph)
    except RosbridgeError:
        return False


async def _navigator_state(ctx: ToolContext, namespace: str) -> str | None:
    """Why the ROS 2 navigator is not active (its lifecycle state), or ``None`` (active, or not told)."""
    service = f"{namespace}/bt_navigator/get_state"
    try:
        names = await ctx.graph.service_names()
    except RosbridgeError:
        return None
    if service not in names:
        return None
    try:
        answer = await ctx.client.call_service(service, {}, timeout=3.0)
    except RosbridgeError:
        return None
    state = answer.get("current_state") if isinstance(answer, dict) else None
    if isinstance(state, dict) and state.get("id") not in (None, 3):
        return (
            f"the navigator {namespace}/bt_navigator is {state.get('label') or state.get('id')}, not active"
        )
    return None


async def _takes_goals(ctx: ToolContext, action_type: str) -> bool:
    """Whether the action's goal takes its poses as one ``nav_msgs/Goals`` (Kilted on), not as a list."""
    try:
        typedefs = await ctx.graph.action_goal_typedefs(action_type)
    except RosbridgeError:
        return False
    return any(
        name.lstrip("_") == "poses" and length == -1 and base.endswith("/Goals")
        for typedef in (typedefs or {}).values()
        for name, base, length in typedef.fields()
    )


def _draw(
    grid: Grid,
    *,
    robot: Pose2D | None,
    goals: list[Pose2D],
    start: Pose2D | None,
    driven: list[tuple[float, float]],
    ctx: ToolContext,
) -> bytes:
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


_GOAL = '{"x": 2, "y": 1.5, "yaw": 90} (metres, DEGREES; no yaw: keep heading)'


def _parse_goal(goal: Any) -> tuple[str, list[tuple[float, float, float | None]]]:
    """A pose or poses given as ``goal``: ("pose", [one]) or ("waypoints", [...])."""
    if isinstance(goal, dict):
        return "pose", [_waypoint(goal, "goal")]
    if isinstance(goal, list) and goal and all(isinstance(v, int | float) for v in goal):
        return "pose", [_waypoint(goal, "goal")]
    if isinstance(goal, list) and goal:
        ways = [_waypoint(item, f"goal[{i}]") for i, item in enumerate(goal)]
        return ("waypoints" if len(ways) > 1 else "pose"), ways
    raise ToolFailure(
        f"goal must be a pose {_GOAL}, a place name, or a list of poses; got {_shown(goal)}. Nothing was "
        "sent."
    )


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
    relative = bool(forward or left or turn)
    for value, what, limit in ((forward, "forward", 100.0), (left, "left", 100.0), (turn, "turn", 360.0)):
        if not math.isfinite(value) or abs(value) > limit:
            raise ToolFailure(f"{what} must be within ±{limit:g}, not {value!r}. Nothing was sent.")
    if isinstance(goal, str) and not goal.strip():
        goal = None
    if goal is not None and relative:
        raise ToolFailure("Give a goal or a relative move (forward/left/turn), not both. Nothing was sent.")
    if goal is None and not relative:
        raise ToolFailure(
            f'Say where to go: goal {_GOAL} in the map frame, goal "PLACE", or forward/left/turn relative to '
            "the robot. Nothing was sent."
        )
    place = goal.strip() if isinstance(goal, str) else ""
    kind, ways = ("place", []) if place else ("relative", []) if relative else _parse_goal(goal)
    places = dict(ctx.config.policy.places)
    if place and place not in places:
        known = ", ".join(sorted(places)) or "none (the policy has no [places])"
        raise ToolFailure(f"No place named {place!r}. Known places: {known}. Nothing was sent.")
    if frame and kind != "pose":
        raise ToolFailure(f"frame applies to one goal pose, not to a {kind}. Nothing was sent.")
    x = y = yaw = None
    if kind == "pose":
        x, y, yaw = ways[0]
        ways = []

    dialect = await ctx.client.dialect()
    ros1 = dialect.version == 1
    if ways and ros1:
        raise ToolFailure(
            "waypoints need Nav2's NavigateThroughPoses (ROS 2); move_base takes one goal at a time. Nothing "
            "was sent."
        )
    if ros1:
        default_action, action_type = "/move_base", "move_base_msgs/MoveBaseAction"
    elif ways:
        default_action, action_type = "/navigate_through_poses", "nav2_msgs/action/NavigateThroughPoses"
    else:
        default_action, action_type = "/navigate_to_pose", "nav2_msgs/action/NavigateToPose"
    given = {"goal": goal, "frame": frame, "forward": forward, "left": left, "turn": turn, "timeout": timeout}
    asked = non_defaults(run, given)
    prefix, note, hint = await _robot_namespace(ctx, namespace, default_action, asked)
    name = prefix + default_action
    map_name = f"{prefix}/map"
    base = BASE_FRAME

    # Is Nav2 ready? Each missing piece is said, and nothing is sent.
    not_ready: list[str] = []
    if hint is not None:
        server = "move_base" if ros1 else "bt_navigator"
        not_ready.append(f"no action server {name} (is {server} running?){hint}")
        if await _is_turtlesim(ctx):
            not_ready.append("turtlesim has no Nav2; the built-in demo has one: --demo --demo-world nav2")
    grid, problem = await read_map(ctx.client, ctx.graph, map_name, _READY_WAIT)
    if problem is not None:
        not_ready.append(problem)
    map_frame = (grid.frame_id if grid is not None else "") or "map"
    start = await frame_pose(ctx.client, ctx.graph, map_frame, base, _READY_WAIT, namespace=prefix)
    if isinstance(start, str):
        not_ready.append(f"no transform from {map_frame} to {base} on {prefix}/tf: {start}")
    if not ros1 and hint is None:
        state = await _navigator_state(ctx, prefix)
        if state is not None:
            not_ready.append(state)
    if not_ready or grid is None or isinstance(start, str):
        missing = "; ".join(reason.rstrip(". ") for reason in not_ready)
        raise ToolFailure(f"Nav2 is not ready: {missing}. Nothing was sent.")

    # The goal's poses, in the frame they were given in.
    if kind == "place":
        px, py, pyaw = places[place]
        poses = [GoalPose(map_frame, px, py, math.radians(pyaw))]
    elif kind == "relative":
        c, s = math.cos(start.yaw), math.sin(start.yaw)
        poses = [
            GoalPose(
                map_frame,
                start.x + c * forward - s * left,
                start.y + s * forward + c * left,
                start.yaw + math.radians(turn),
            )
        ]
    elif ways:
        poses = [
            GoalPose(map_frame, wx, wy, start.yaw if wyaw is None else math.radians(wyaw))
            for wx, wy, wyaw in ways
        ]
    else:
        assert x is not None
        assert y is not None
        goal_frame = frame.strip().lstrip("/") or map_frame
        heading = math.radians(yaw) if yaw is not None else None
        if heading is None:
            # Keep the robot's heading: its yaw in the map, seen from the goal's frame.
            origin = await frame_pose(
                ctx.client, ctx.graph, map_frame, goal_frame, _READY_WAIT, namespace=prefix
            )
            if isinstance(origin, str):
                raise ToolFailure(
                    f"The goal's frame {goal_frame} cannot be placed in {map_frame}: {origin}. Give the goal "
                    f"in {map_frame}, or check /tf (get_transform). Nothing was sent."
                )
            heading = start.yaw - origin.yaw
        poses = [GoalPose(goal_frame, _number(x, "x"), _number(y, "y"), heading)]
    scene = await survey(
        ctx.client,
        ctx.graph,
        map_topic=map_name,
        base_frame=base,
        poses=poses,
        timeout=_READY_WAIT,
        grid=grid,
        namespace=prefix,
    )
    if len(scene.goals) != len(poses):
        raise ToolFailure(
            f"The goal cannot be placed on the map: {'; '.join(scene.problems)}. Give it in {map_frame}, or "
            "check /tf (get_transform). Nothing was sent."
        )
    goals = list(scene.goals)
    scene = Scene(
        map_topic=scene.map_topic,
        base_frame=base,
        grid=grid,
        robot=start,
        goals=scene.goals,
        problems=scene.problems,
    )
    stamped = [_pose_msg(map_frame, goal) for goal in goals]
    if ros1:
        body: dict[str, Any] = {"target_pose": stamped[0]}
    elif ways and await _takes_goals(ctx, action_type):
        body = {"poses": {"header": {"frame_id": map_frame}, "goals": stamped}}
    elif ways:
        body = {"poses": stamped}
    else:
        body = {"pose": stamped[0]}

    track: list[tuple[float, float]] = [(start.x, start.y)]
    recoveries: list[int] = []
    began = time.monotonic()

    async def on_feedback(running: Goal, feedback: dict[str, Any]) -> None:
        current = feedback.get("current_pose") or feedback.get("base_position")
        here = current.get("pose", {}).get("position") if isinstance(current, dict) else None
        if isinstance(here, dict) and len(track) < _MAX_TRACK:
            px, py = here.get("x"), here.get("y")
            if isinstance(px, int | float) and isinstance(py, int | float):
                track.append((float(px), float(py)))
        remaining = feedback.get("distance_remaining")
        if remaining is None and track:
            last = goals[-1]
            remaining = math.hypot(track[-1][0] - last.x, track[-1][1] - last.y)
        count = feedback.get("number_of_recoveries")
        if isinstance(count, int):
            recoveries.append(count)
        parts = [f"goal {running.goal_id}"]
        if isinstance(remaining, int | float):
            parts.append(f"{remaining:.2f} m to go")
        parts.append(f"{time.monotonic() - began:.0f} s")
        left_time = feedback.get("estimated_time_remaining")
        if isinstance(left_time, dict):
            seconds = float(left_time.get("sec", 0) or 0) + float(left_time.get("nanosec", 0) or 0) / 1e9
            parts.append(f"~{seconds:.0f} s left")
        if isinstance(count, int):
            parts.append(f"{count} recoveries")
        await ctx.report_progress(float(running.feedback_count), None, ", ".join(parts))

    try:
        outcome = await send_goal(
            ctx,
            tool=SPEC.name,
            action=name,
            action_type=action_type,
            goal=body,
            timeout=timeout,
            on_feedback=on_feedback,
            scene=scene,
        )
    except PolicyRefusal as exc:
        image = await asyncio.to_thread(_draw, grid, robot=start, goals=goals, start=None, driven=[], ctx=ctx)
        raise _Refused(f"{exc} The picture shows the robot (blue) and the goal (magenta).", image) from None

    final = await frame_pose(ctx.client, ctx.graph, map_frame, base, _READY_WAIT, namespace=prefix)
    final_pose = final if isinstance(final, Pose2D) else None
    if final_pose is not None:
        track.append((final_pose.x, final_pose.y))
    image = await asyncio.to_thread(
        _draw, grid, robot=final_pose, goals=goals, start=start, driven=track, ctx=ctx
    )
    answer = _answer(
        outcome,
        frame=map_frame,
        goals=goals,
        start=start,
        final=final_pose,
        track=track,
        recoveries=recoveries,
        began=began,
        image=image,
    )
    if note is not None:
        answer = replace(answer, text=f"{note}\n{answer.text}")
    return answer


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
    start: Pose2D,
    final: Pose2D | None,
    track: list[tuple[float, float]],
    recoveries: list[int],
    began: float,
    image: bytes,
) -> ToolAnswer:
    last = goals[-1]
    distance = heading = None
    if final is not None:
        distance = round(math.hypot(final.x - last.x, final.y - last.y), 3)
        heading = round(
            math.degrees(math.atan2(math.sin(final.yaw - last.yaw), math.cos(final.yaw - last.yaw))), 1
        )
    driven = sum(math.dist(track[i], track[i + 1]) for i in range(len(track) - 1))
    error = None
    result = outcome.result or {}
    if not outcome.succeeded and (result.get("error_code") or result.get("error_msg")):
        error = f"{result.get('error_code', 0)}: {result.get('error_msg', '')}".strip()
    data = NavigateAnswer(
        goal_id=outcome.goal_id,
        status=outcome.status,
        succeeded=outcome.succeeded,
        final=_planar(final),
        distance_to_goal=distance,
        canceled_by=outcome.canceled_by,
    )
    seconds = time.monotonic() - began
    target = ", then ".join(f"({g.x:.2f}, {g.y:.2f}, {math.degrees(g.yaw):.0f}°)" for g in goals)
    head = f"Navigation to {target} in {frame}: {outcome.status}"
    if outcome.status == UNCONFIRMED_STATUS:
        head += (
            "; a cancel was sent but the robot has not confirmed the goal ended: it may still be moving. "
            "Call stop_robot, or check the robot"
        )
    elif outcome.canceled_by is not None:
        head += f" ({_CANCELLED_BY.get(outcome.canceled_by, outcome.canceled_by)})"
    lines = [head + "."]
    if error:
        lines.append(f"Navigator error {error}.")
    if final is not None:
        lines.append(
            f"Robot now at ({final.x:.2f}, {final.y:.2f}, {math.degrees(final.yaw):.0f}°): "
            f"{distance:.2f} m and {abs(heading or 0):.0f}° from the goal; drove {driven:.2f} m in "
            f"{seconds:.1f} s"
            + (f", {recoveries[-1]} recoveries" if recoveries and recoveries[-1] else "")
            + "."
        )
    else:
        lines.append("The robot's final pose is not known (/tf did not tell).")
    lines.append("Picture: start grey square, path driven green, goal magenta, robot blue.")
    return ToolAnswer(text="\n".join(lines), data=data, images=(ToolImage(image, "image/png"),))
