"""The arm on ROS 1: the same arm and controllers, reached as ros_control's are.

* ``/arm_controller/follow_joint_trajectory`` (``control_msgs/FollowJointTrajectoryAction``) and
  ``/gripper_controller/gripper_cmd`` (``control_msgs/GripperCommandAction``) as actionlib servers over their
  five topics (:class:`~rosbridge_mcp_server.sim.nodes.nav2.actionlib.ActionlibServer`): a goal runs the arm
  as on ROS 2; a cancel stops it where it is (PREEMPTED); a goal the controller cannot run, or one preempted
  by a newer goal or a trajectory on the topic, ends ABORTED with its ``error_code`` and ``error_string``
  (ros_control's controller *rejects* a goal with bad joints; here it is aborted, as the ROS 2 lab's arm
  does);
* ``/arm_controller/command`` (``trajectory_msgs/JointTrajectory``, ros_control's topic): replaces what runs;
  an **empty trajectory (no points) stops the arm where it is and holds it**, as ros_control's
  ``joint_trajectory_controller`` documents (ROS 2's controller ignores an empty one);
* the URDF and the SRDF as the parameters ``/robot_description`` and ``/robot_description_semantic``
  (MoveIt's ROS 1 layout), and ``/controller_manager``'s services in ROS 1 form (:mod:`.controllers`).
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.sim.nodes.arm.model import FINGER
from rosbridge_mcp_server.sim.nodes.arm.motion import LIMITS, Invalid
from rosbridge_mcp_server.sim.nodes.nav2.actionlib import ActionlibServer

if TYPE_CHECKING:
    from rosbridge_mcp_server.sim.nodes.arm.world import ArmWorld

__all__ = ["COMMAND_TOPIC", "build_ros1"]

COMMAND_TOPIC = "/arm_controller/command"
FEEDBACK_PERIOD = 1.0 / 20
Feedback = Callable[[dict[str, Any]], None]


def build_ros1(arm: ArmWorld) -> None:
    """The ROS 1 topics and action servers of *arm* (its controller manager is built by the caller)."""
    kit = arm.kit
    trajectory_type = kit.msg_type("trajectory_msgs", "JointTrajectory")
    if trajectory_type is not None:
        kit.graph.add_subscriber("/arm_controller", COMMAND_TOPIC, trajectory_type, arm.on_trajectory)
    if kit.msg_type("control_msgs", "FollowJointTrajectoryActionGoal") is not None:
        arm.actionlib.append(
            ActionlibServer(
                kit,
                name="/arm_controller/follow_joint_trajectory",
                node="/arm_controller",
                package="control_msgs",
                action="FollowJointTrajectory",
                steps=0,
                step=0.0,
                runner=lambda goal, cancel, feedback: _follow(arm, goal, cancel, feedback),
            )
        )
    if kit.msg_type("control_msgs", "GripperCommandActionGoal") is not None:
        arm.actionlib.append(
            ActionlibServer(
                kit,
                name="/gripper_controller/gripper_cmd",
                node="/gripper_controller",
                package="control_msgs",
                action="GripperCommand",
                steps=0,
                step=0.0,
                runner=lambda goal, cancel, feedback: _grip(arm, goal, cancel, feedback),
            )
        )


async def _follow(
    arm: ArmWorld, goal: dict[str, Any], cancel: asyncio.Event, feedback: Feedback
) -> tuple[str, dict[str, Any]]:
    arm.received_goals.append(goal)
    trajectory = goal.get("trajectory") or {}
    try:
        run = arm.start(trajectory, trajectory.get("header"), "goal")
    except Invalid as exc:
        return "aborted", {"error_code": exc.code, "error_string": exc.text}
    stop: asyncio.Future[Any] = asyncio.ensure_future(cancel.wait())
    try:
        while not run.done.done():
            feedback(arm.trajectory_feedback(run.trajectory.joints))
            await asyncio.wait((run.done, stop), timeout=FEEDBACK_PERIOD)
            if cancel.is_set():
                arm.stop(run)
        state, result = run.done.result()
        return state, result
    finally:
        stop.cancel()
        if not run.done.done():  # the robot stopped under it
            arm.stop(run)


async def _grip(
    arm: ArmWorld, goal: dict[str, Any], cancel: asyncio.Event, feedback: Feedback
) -> tuple[str, dict[str, Any]]:
    arm.gripper_goals.append(goal)
    if not arm.controllers.is_active("gripper_controller"):
        return "aborted", arm.gripper_result(stalled=False, reached=False)
    wanted = float((goal.get("command") or {}).get("position", 0.0))
    lower, upper = LIMITS[FINGER]
    arm.gripper_target = min(max(wanted, lower), upper)
    while arm.gripper_moving():
        feedback(arm.gripper_result(stalled=False, reached=False))
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(cancel.wait(), FEEDBACK_PERIOD)
        if cancel.is_set():
            arm.gripper_target = None
            arm.velocities[FINGER] = 0.0
            return "canceled", arm.gripper_result(stalled=False, reached=False)
    reached = abs(arm.positions[FINGER] - wanted) < 1e-6
    return ("succeeded" if reached else "aborted"), arm.gripper_result(stalled=not reached, reached=reached)
