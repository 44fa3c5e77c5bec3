"""How far each stop reaches (issue 35, What 1), on the simulated Nav2 world in both dialects.

The operator's E-STOP also cancels every goal of the robot's known motion action servers, whoever sent it (a
raw client's NavigateToPose goal; a server known only by its type, under a name of its own), and leaves the
servers that move nothing alone; ``stop_robot`` reaches only what this server caused. A goal sent through
``_action/send_goal`` is cancelled by its UUID; a cancel that cannot be sent is said.
"""

from __future__ import annotations

import base64
import json
from collections.abc import Awaitable, Callable
from typing import Any

import pytest
from mcp_harness import open_session, text_of
from test_mcp_effects import Watcher, watching
from test_mcp_stop_carriers import FAR, SPEED, console_stand, moving, stamped_pose, stands_still

from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.robot.approval import ALLOW_ALL
from rosbridge_mcp_server.robot.effects import service_effects, topic_effects
from rosbridge_mcp_server.robot.goals.caused import caused_by_call, caused_by_publish
from rosbridge_mcp_server.robot.session import RobotSession
from rosbridge_mcp_server.safety import emergency_stop
from rosbridge_mcp_server.sim import SimulatedRobot

MakeSim = Callable[..., Awaitable[SimulatedRobot]]
STATUS = "action_msgs/msg/GoalStatusArray"


async def nav2(make_sim: MakeSim, dialect: str) -> SimulatedRobot:
    robot = await make_sim(dialect=dialect, world="nav2")
    robot.nav2.navigator.speed = SPEED
    return robot


async def raw_navigation_goal(watcher: Watcher, dialect: str) -> None:
    """Another client of the bridge (the watcher's socket) sends NavigateToPose a goal to FAR."""
    goal = {"pose": stamped_pose(*FAR)}
    if dialect == "ros2":
        frame = {
            "op": "send_action_goal",
            "id": "another-client",
            "action": "/navigate_to_pose",
            "action_type": "nav2_msgs/action/NavigateToPose",
            "args": goal,
        }
        await watcher.ws.send(json.dumps(frame))
        return
    goal_type = "nav2_msgs/NavigateToPoseActionGoal"
    await watcher.ws.send(
        json.dumps({"op": "advertise", "topic": "/navigate_to_pose/goal", "type": goal_type})
    )
    message = {"header": {}, "goal_id": {"id": "another-client"}, "goal": goal}
    await watcher.ws.send(json.dumps({"op": "publish", "topic": "/navigate_to_pose/goal", "msg": message}))


async def watch_navigator(watcher: Watcher, dialect: str) -> str:
    """Subscribe to what shows the navigator's cancels; returns the topic."""
    if dialect == "ros1":
        await watcher.subscribe("/navigate_to_pose/cancel", "actionlib_msgs/GoalID")
        return "/navigate_to_pose/cancel"
    await watcher.subscribe("/navigate_to_pose/_action/status", STATUS)
    return "/navigate_to_pose/_action/status"


def cancelled(message: dict[str, Any], dialect: str) -> bool:
    if dialect == "ros1":
        return message.get("id") == ""  # every goal: the E-STOP does not know the other client's id
    return any(entry["status"] == 5 for entry in message["status_list"])


@pytest.mark.parametrize("dialect", ["ros1", "ros2"])
async def test_estop_cancels_a_navigation_goal_another_client_sent(make_sim: MakeSim, dialect: str) -> None:
    robot = await nav2(make_sim, dialect)
    state = robot.nav2.robots[0]
    async with console_stand(robot) as (_, hub, trail), watching(robot) as watcher:
        topic = await watch_navigator(watcher, dialect)
        await raw_navigation_goal(watcher, dialect)
        await robot.wait_for(lambda world: moving(state), timeout=15.0)
        [report] = await hub.estop()
        await watcher.wait_for(topic, lambda message: cancelled(message, dialect))
        await stands_still(robot, state)
        hub.release()
    assert report["failures"] == []
    cancels = report["cancels"]
    if dialect == "ros2":
        # The one server that had a goal says so on a line of its own; the idle ones are grouped.
        assert (
            "every goal on /navigate_to_pose (a motion server, by its name): 1 goal(s) cancelling" in cancels
        )
    # Every motion server is reached, by name; what moves nothing is left alone.
    reached = {
        name for line in cancels for name in line.split(" (")[0].removeprefix("every goal on ").split(", ")
    }
    assert {"/navigate_to_pose", "/spin", "/backup", "/follow_path", "/dock_robot"} <= reached
    assert not reached & {"/compute_path_to_pose", "/smooth_path", "/wait"}
    if dialect == "ros1":
        assert "/move_base" in reached
    audited = [json.loads(line) for line in trail.getvalue().splitlines()]
    assert {"action": "/navigate_to_pose", "cancel": "all"} in [
        {"action": entry["name"], "cancel": (entry.get("payload") or {}).get("cancel")} for entry in audited
    ]


@pytest.mark.parametrize("dialect", ["ros1", "ros2"])
async def test_stop_robot_leaves_a_goal_another_client_sent_alone(make_sim: MakeSim, dialect: str) -> None:
    """The model's stop reaches only what this server caused (docs/safety.md says why)."""
    robot = await nav2(make_sim, dialect)
    state = robot.nav2.robots[0]
    async with console_stand(robot) as (session, hub, _), watching(robot) as watcher:
        await raw_navigation_goal(watcher, dialect)
        await robot.wait_for(lambda world: moving(state), timeout=15.0)
        answer = text_of(await session.ok("stop_robot"))
        here = (state.x, state.y)
        # Still driving: it goes on moving away from where it was when stop_robot answered.
        await robot.wait_for(lambda world: abs(state.x - here[0]) + abs(state.y - here[1]) > 0.2, timeout=5.0)
        await hub.estop()
        await stands_still(robot, state)
        hub.release()
    assert "Nothing to stop" in answer


@pytest.mark.parametrize("dialect", ["ros1", "ros2"])
async def test_estop_knows_a_motion_server_by_its_type_under_any_name(
    make_sim: MakeSim, dialect: str
) -> None:
    """A DriveOnHeading server of a client's own at /arm/creep gets the E-STOP's cancel-all: by type."""
    robot = await make_sim(dialect=dialect, world="nav2")
    async with console_stand(robot) as (_, hub, _trail), watching(robot) as owner:
        if dialect == "ros2":
            await owner.ws.send(
                json.dumps(
                    {
                        "op": "advertise_action",
                        "action": "/arm/creep",
                        "type": "nav2_msgs/action/DriveOnHeading",
                    }
                )
            )
            await robot.wait_for(lambda world: "/arm/creep" in robot.graph.actions, timeout=15.0)
        else:
            prefix = "nav2_msgs/DriveOnHeadingAction"
            for leaf, type_name in (
                ("status", "actionlib_msgs/GoalStatusArray"),
                ("feedback", f"{prefix}Feedback"),
                ("result", f"{prefix}Result"),
            ):
                await owner.ws.send(
                    json.dumps({"op": "advertise", "topic": f"/arm/creep/{leaf}", "type": type_name})
                )
            await owner.subscribe("/arm/creep/goal", f"{prefix}Goal")
            await owner.subscribe("/arm/creep/cancel", "actionlib_msgs/GoalID")
        [report] = await hub.estop()
        if dialect == "ros1":
            await owner.wait_for("/arm/creep/cancel", lambda message: message.get("id") == "")
        hub.release()
    creep = [line for line in report["cancels"] if line.startswith("every goal on /arm/creep ")]
    assert creep, report
    assert "DriveOnHeading" in creep[0]


async def test_a_goal_sent_through_send_goal_is_cancelled_by_its_uuid(make_sim: MakeSim) -> None:
    """rosbridge_suite cannot load an action's SendGoal type, so the goal is started here as a bridge that can
    would start it, and remembered as publish_service remembers it; stop_robot cancels that UUID."""
    robot = await nav2(make_sim, "ros2")
    state = robot.nav2.robots[0]
    client = RosbridgeClient(robot.url, request_timeout=5.0)
    session = RobotSession(client, ALLOW_ALL)
    async with client, watching(robot) as watcher:
        await client.wait_connected(30.0)
        await watcher.subscribe("/navigate_to_pose/_action/status", STATUS)
        server = robot.graph.actions["/navigate_to_pose"]
        uuid = bytes(range(1, 17))
        request = {"goal_id": {"uuid": list(uuid)}, "goal": {"pose": stamped_pose(*FAR)}}
        service = "/navigate_to_pose/_action/send_goal"
        effects = service_effects(service, "nav2_msgs/action/NavigateToPose_SendGoal", request, 2)
        session.goals.caused(caused_by_call(service, request, effects, 2))
        server.submit(request["goal"], key=None, on_feedback=None, uuid=uuid)
        await robot.wait_for(lambda world: moving(state), timeout=15.0)
        report = await emergency_stop(session, by="stop_robot")
        mine = base64.b64encode(uuid).decode()

        def ended_mine(message: dict[str, Any]) -> bool:
            return any(
                entry["goal_info"]["goal_id"]["uuid"] in (mine, list(uuid)) and entry["status"] == 5
                for entry in message["status_list"]
            )

        await watcher.wait_for("/navigate_to_pose/_action/status", ended_mine)
        await stands_still(robot, state)
    assert report.failures == []
    assert report.goals_cancelled == [uuid.hex()]
    [cancel] = report.cancels
    assert (cancel.action, cancel.outcome) == ("/navigate_to_pose", "cancelling")


async def test_a_send_goal_call_the_bridge_refuses_leaves_nothing_to_stop(make_sim: MakeSim) -> None:
    robot = await make_sim(dialect="ros2", world="nav2")
    request = {"goal_id": {"uuid": list(range(16))}, "goal": {"pose": stamped_pose(*FAR)}}
    call = {
        "service": "/navigate_to_pose/_action/send_goal",
        "service_type": "nav2_msgs/action/NavigateToPose_SendGoal",
        "request": request,
    }
    async with open_session(robot.url) as session:
        refused = await session.error("publish_service", call)
        answer = text_of(await session.ok("stop_robot"))
    assert "NavigateToPose_SendGoal" in refused
    assert "Nothing to stop" in answer


async def test_a_cancel_that_cannot_be_sent_is_said(make_sim: MakeSim) -> None:
    """A goal published on /move_base/goal, then the bridge goes: the stop says it could not cancel it."""
    robot = await make_sim(dialect="ros1", world="nav2")
    client = RosbridgeClient(robot.url, request_timeout=1.0, reconnect_min=5.0, reconnect_max=5.0)
    session = RobotSession(client, ALLOW_ALL)
    message = {"goal_id": {"id": "g"}, "goal": {}}
    async with client:
        await client.wait_connected(30.0)
        topic = "/move_base/goal"
        effects = topic_effects(topic, "move_base_msgs/MoveBaseActionGoal")
        session.goals.caused(caused_by_publish(topic, message, effects, 1))
        await robot.stop()
        await client.wait_disconnected(5.0)
        report = await emergency_stop(session, by="stop_robot")
    assert report.did_anything
    assert any(
        failure.startswith("goal g on /move_base (sent on /move_base/goal by this server): the cancel failed")
        for failure in report.failures
    ), report.failures
    # Not forgotten: the next stop tries it again.
    assert [goal.goal_id for goal in session.goals.caused_goals()] == ["g"]


async def test_a_goal_pose_with_no_navigator_on_the_graph_is_said_once_and_forgotten(
    make_sim: MakeSim,
) -> None:
    """The turtle world has no /navigate_to_pose: the stop says no goal of it runs, and forgets it."""
    robot = await make_sim(dialect="ros2")
    pose = {
        "topic": "/goal_pose",
        "message_type": "geometry_msgs/msg/PoseStamped",
        "message": stamped_pose(1, 1),
    }
    async with open_session(robot.url) as session:
        await session.ok("publish_topic", pose)
        first = text_of(await session.ok("stop_robot"))
        again = text_of(await session.ok("stop_robot"))
    assert (
        "every goal on /navigate_to_pose (sent on /goal_pose by this server): no such action server" in first
    )
    assert "Nothing to stop" in again


async def test_estop_says_which_servers_it_could_not_place_in_time(make_sim: MakeSim) -> None:
    """rosapi at 1.2 s a call: E-STOP still cancels the servers it knows by name, and names those whose type
    it could not learn within its 3 s, instead of skipping them silently."""
    robot = await make_sim(dialect="ros1", world="nav2", rosapi_latency=1.2)
    client = RosbridgeClient(robot.url, request_timeout=10.0)
    session = RobotSession(client, ALLOW_ALL)
    async with client:
        await client.wait_connected(30.0)
        report = await emergency_stop(session, by="console")
    late = [failure for failure in report.failures if "its type was not learnt" in failure]
    assert late, report.failures
    assert all(failure.startswith("every goal on /") for failure in late)
    assert ("/move_base", "") in report.goals
    assert ("/navigate_to_pose", "") in report.goals


async def test_ros1_a_goal_topic_publish_advertises_its_cancel_topic_at_once(make_sim: MakeSim) -> None:
    """A new ROS 1 publisher's first message is often lost: the cancel topic is advertised with the goal, so a
    later stop's cancel goes out on a publisher the action server already hears."""
    robot = await make_sim(dialect="ros1", world="nav2")
    goal = {"header": {}, "goal_id": {"id": "g"}, "goal": {"target_pose": stamped_pose(5.8, 5.5)}}
    call = {"topic": "/move_base/goal", "message_type": "move_base_msgs/MoveBaseActionGoal", "message": goal}
    bridge = robot.graph.nodes["/rosbridge_websocket"]
    async with open_session(robot.url) as session:
        assert "/move_base/cancel" not in bridge.publishes
        await session.ok("publish_topic", call)
        await robot.wait_for(lambda world: "/move_base/cancel" in bridge.publishes, timeout=15.0)
