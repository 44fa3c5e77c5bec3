"""diagnose on the simulated arm: an inactive controller, stale joint states and a joint at its limit are
named with what to call next; a healthy arm reports none; a robot without an arm is not told about one."""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

from mcp_harness import open_session, text_of

from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.nodes.arm import ARM_JOINTS

MakeSim = Callable[..., Awaitable[SimulatedRobot]]


async def diagnosis(robot: SimulatedRobot, focus: str | None = "arm") -> tuple[dict[str, Any], str]:
    async with open_session(robot.url) as session:
        result = await session.ok("diagnose", {"focus": focus} if focus else {})
    return result.structured_content or {}, text_of(result)


async def test_a_healthy_arm_has_no_finding(make_sim: MakeSim) -> None:
    """Every controller active, /joint_states flowing, no joint at a limit (the open gripper is not one)."""
    data, text = await diagnosis(await make_sim(world="arm"))
    assert text.startswith("No problem found"), text
    assert data["checked"]["arm"] == "3 of 3 controllers active; 7 joints against their URDF limits"
    assert data["checked"]["streams"].startswith("1 of 1 key streams flowing")


async def test_an_inactive_arm_controller_is_a_problem_with_the_call_that_activates_it(
    make_sim: MakeSim,
) -> None:
    """arm-controller-inactive: a problem naming arm_controller, its joints, and switch_controller."""
    data, text = await diagnosis(await make_sim(world="arm", faults=["arm-controller-inactive"]))
    (finding,) = data["findings"]
    assert (finding["severity"], finding["area"], finding["subject"]) == ("problem", "arm", "arm_controller")
    assert finding["details"]["joints"] == list(ARM_JOINTS)
    assert '"activate_controllers": ["arm_controller"]' in finding["next"]
    assert (
        "PROBLEM [arm] Controller arm_controller (joint_trajectory_controller/JointTrajectoryController)"
        in text
    )


async def test_stale_joint_states_are_a_problem_of_the_stream(make_sim: MakeSim) -> None:
    """joint-states-stale: /joint_states sends nothing in the window, its publisher named."""
    data, _ = await diagnosis(await make_sim(world="arm", faults=["joint-states-stale"]))
    subjects = {(f["area"], f["subject"]) for f in data["findings"] if f["severity"] == "problem"}
    assert ("streams", "/joint_states") in subjects
    assert data["checked"]["arm"].endswith("no joint state heard: limits not checked")


async def test_a_joint_at_its_limit_is_a_warning(make_sim: MakeSim) -> None:
    """The elbow at its upper limit (2.7925 rad): a warning naming the joint, the side and the limit."""
    robot = await make_sim(world="arm")
    robot.arm.positions["elbow_joint"] = 2.7925
    data, _ = await diagnosis(robot)
    (finding,) = data["findings"]
    assert (finding["severity"], finding["subject"]) == ("warning", "elbow_joint")
    assert finding["details"] == {"position": 2.7925, "side": "upper", "limit": 2.7925}
    assert finding["next"] == "view_arm"


async def test_a_robot_without_an_arm_gets_no_arm_line_unless_asked(make_sim: MakeSim) -> None:
    """The turtle has no controller manager and no /joint_states: silent by default, said when asked."""
    turtle = await make_sim()
    data, _ = await diagnosis(turtle, focus=None)
    assert "arm" not in data["checked"]
    assert "arm" not in data["unavailable"]
    data, _ = await diagnosis(turtle)
    assert data["unavailable"]["arm"] == "no controller manager (…/list_controllers) and no /joint_states"
