"""The arm world: the turtle world plus an arm and its gripper, driven by ros2_control as on a real robot.

What it adds (names as ros2_control and the ROS 2 lab use them; on ROS 1 as ros_control does, :mod:`.ros1`):

* ``/joint_states`` (``/joint_state_broadcaster``, 50 Hz while listened to): the six arm joints and
  ``gripper_finger_joint``; ``/tf`` with every movable joint's link, ``/tf_static`` with the fixed ones;
* ``/robot_description`` (latched) holds the arm too; ``/robot_description_semantic`` (latched) the SRDF with
  the named poses ``home``, ``ready``, ``zero`` (and the gripper's ``open``, ``closed``);
* ``/arm_controller/follow_joint_trajectory`` (``control_msgs/action/FollowJointTrajectory``) and the
  ``/arm_controller/joint_trajectory`` topic; ``/gripper_controller/gripper_cmd``
  (``control_msgs/action/GripperCommand``);
* ``/controller_manager/list_controllers`` and ``switch_controller`` (really (de)activating).

Faults (:data:`ARM_FAULTS`): ``arm-controller-inactive`` (``arm_controller`` inactive and refusing to
activate: "hardware fault on the arm"), ``joint-states-stale`` (the broadcaster stays active and in the graph
but ``/joint_states``, and with it the arm's ``/tf``, stop).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import time
from typing import Any

from rosbridge_mcp_server.sim.actions import ActionServer, GoalHandle
from rosbridge_mcp_server.sim.actions.ros2 import FeedbackFn
from rosbridge_mcp_server.sim.nodes.arm.controllers import ControllerManager
from rosbridge_mcp_server.sim.nodes.arm.model import ARM_JOINTS, FINGER, HOME, JOINTS, joint_transform, srdf
from rosbridge_mcp_server.sim.nodes.arm.motion import (
    INVALID_GOAL,
    LIMITS,
    Invalid,
    Run,
    check_trajectory,
    make_trajectory,
)
from rosbridge_mcp_server.sim.nodes.kit import NodeKit

__all__ = ["ARM_FAULTS", "ARM_NODES", "ArmWorld"]

log = logging.getLogger("rosbridge_mcp_server.sim")

ARM_FAULTS = ("arm-controller-inactive", "joint-states-stale")
UPDATE_PERIOD = 1.0 / 50
FEEDBACK_PERIOD = 1.0 / 20
GRIPPER_SPEED = 0.05  # m/s
SEMANTIC_NODE = "/robot_semantic_publisher"
ARM_NODES = ("/controller_manager", "/arm_controller", "/gripper_controller", "/joint_state_broadcaster")


class ArmWorld:
    """The arm's state (:attr:`positions`), its controllers and what it publishes."""

    def __init__(self, kit: NodeKit, faults: tuple[str, ...] = ()) -> None:
        unknown = [f for f in faults if f not in ARM_FAULTS]
        if unknown:
            raise ValueError(f"unknown arm fault {', '.join(unknown)}; choose from {', '.join(ARM_FAULTS)}")
        self.kit = kit
        self.faults = set(faults)
        #: Every joint's position now (radians / metres), mimic joints left out.
        self.positions: dict[str, float] = dict(HOME)
        self.velocities: dict[str, float] = dict.fromkeys(HOME, 0.0)
        self.run: Run | None = None
        self.gripper_target: float | None = None
        self.controllers = ControllerManager(kit, self.faults, self._deactivated)
        #: Goals and topic trajectories that reached the controllers, as sent (tests read them).
        self.received_goals: list[dict[str, Any]] = []
        self.received_trajectories: list[dict[str, Any]] = []
        self.gripper_goals: list[dict[str, Any]] = []
        self.joint_state_count = 0
        #: ROS 1: the actionlib servers (:mod:`.ros1`).
        self.actionlib: list[Any] = []

    # --- building ------------------------------------------------------------------------------------------

    def build(self) -> None:
        kit = self.kit
        for node in ARM_NODES:
            kit.graph.node(node)
        kit.publisher("/joint_state_broadcaster", "/joint_states", kit.msg_type("sensor_msgs", "JointState"))
        self.controllers.build()
        if not kit.ros2:
            kit.world.params.update(
                {
                    "/arm_controller/joints": list(ARM_JOINTS),
                    "/arm_controller/allow_partial_joints_goal": False,
                    "/gripper_controller/joint": FINGER,
                    "/robot_description_semantic": srdf(),
                }
            )
            kit.loops.append(self._loop)
            return
        kit.graph.node(SEMANTIC_NODE)
        kit.publisher(
            SEMANTIC_NODE, "/robot_description_semantic", kit.msg_type("std_msgs", "String"), latched=True
        )
        trajectory_type = kit.msg_type("trajectory_msgs", "JointTrajectory")
        if trajectory_type is not None:
            kit.graph.add_subscriber(
                "/arm_controller", "/arm_controller/joint_trajectory", trajectory_type, self.on_trajectory
            )
        follow = kit.type("control_msgs/action/FollowJointTrajectory", "", "action")
        if follow is not None:
            self.follow = TrajectoryServer(self, follow)
        gripper = kit.type("control_msgs/action/GripperCommand", "", "action")
        if gripper is not None:
            self.gripper = GripperServer(self, gripper)
        params = kit.world.params
        params.update(
            {
                "/arm_controller:joints": list(ARM_JOINTS),
                "/arm_controller:command_interfaces": ["position"],
                "/arm_controller:state_interfaces": ["position", "velocity"],
                "/arm_controller:allow_partial_joints_goal": False,
                "/arm_controller:reject_invalid_goals": False,
                "/gripper_controller:joint": FINGER,
                "/controller_manager:update_rate": 50,
                f"{SEMANTIC_NODE}:robot_description_semantic": srdf(),
            }
        )
        kit.loops.append(self._loop)

    def static_transforms(self) -> list[tuple[str, str, float, float, float, float]]:
        """The arm's fixed joints as (parent, child, x, y, z, yaw), for ``/tf_static``."""
        return [(j.parent, j.child, *j.xyz, j.yaw) for j in JOINTS if j.kind == "fixed"]

    # --- the update loop -----------------------------------------------------------------------------------

    async def _loop(self) -> None:
        if self.kit.ros2:
            self.kit.publish("/robot_description_semantic", {"data": srdf()})
        while True:
            self.step(time.monotonic())
            if "joint-states-stale" not in self.faults and self.controllers.is_active(
                "joint_state_broadcaster"
            ):
                self._publish_state()
            await asyncio.sleep(UPDATE_PERIOD)

    def step(self, now: float) -> None:
        """Advance the running trajectory and the gripper to *now*."""
        run = self.run
        if run is not None:
            positions, velocities = run.trajectory.sample(now)
            for name, position, velocity in zip(run.trajectory.joints, positions, velocities, strict=True):
                self.positions[name] = position
                self.velocities[name] = velocity
            if now >= run.trajectory.end:
                self.run = None
                for name in run.trajectory.joints:
                    self.velocities[name] = 0.0
                run.finish("succeeded", 0, "goal reached")
            self.kit.world.notify()
        if self.gripper_target is not None:
            self._move_fingers(self.gripper_target)
            self.kit.world.notify()

    def _move_fingers(self, target: float) -> None:
        """One update's travel of the finger towards *target* at the gripper's speed (the last one lands)."""
        here = self.positions[FINGER]
        travel = GRIPPER_SPEED * UPDATE_PERIOD
        if abs(target - here) <= travel:
            self.positions[FINGER], self.velocities[FINGER] = target, 0.0
            self.gripper_target = None
        else:
            self.positions[FINGER] = here + math.copysign(travel, target - here)
            self.velocities[FINGER] = math.copysign(GRIPPER_SPEED, target - here)

    def _publish_state(self) -> None:
        kit = self.kit
        if not (kit.wants("/joint_states") or kit.wants("/tf")):
            return
        now = time.time()
        names = [*ARM_JOINTS, FINGER]
        if kit.wants("/joint_states"):
            kit.publish(
                "/joint_states",
                {
                    "header": kit.header("", now),
                    "name": names,
                    "position": [self.positions[n] for n in names],
                    "velocity": [self.velocities[n] for n in names],
                    "effort": [0.0] * len(names),
                },
            )
            self.joint_state_count += 1
        if kit.wants("/tf"):
            kit.publish("/tf", {"transforms": [self._transform(j, now) for j in JOINTS if j.kind != "fixed"]})

    def _transform(self, joint: Any, now: float) -> dict[str, Any]:
        position = self.positions[joint.mimic or joint.name]
        (x, y, z), (qx, qy, qz, qw) = joint_transform(joint, position)
        return {
            "header": self.kit.header(joint.parent, now),
            "child_frame_id": joint.child,
            "transform": {
                "translation": {"x": x, "y": y, "z": z},
                "rotation": {"x": qx, "y": qy, "z": qz, "w": qw},
            },
        }

    # --- trajectories --------------------------------------------------------------------------------------

    def param(self, name: str) -> Any:
        """The parameter ``/node:leaf`` (ROS 2 spelling; ROS 1's ``/node/leaf``)."""
        return self.kit.world.params.get(name if self.kit.ros2 else name.replace(":", "/"))

    def start(self, trajectory: Any, header: Any, source: str, multi_dof: Any = None) -> Run:
        """Check and start a trajectory, preempting what runs; :class:`Invalid` when it cannot run."""
        if not self.controllers.is_active("arm_controller"):
            raise Invalid(INVALID_GOAL, "arm_controller is not active")
        names, points = check_trajectory(
            trajectory,
            allow_partial=bool(self.param("/arm_controller:allow_partial_joints_goal")),
            multi_dof=multi_dof,
        )
        planned = make_trajectory(names, points, header, self.positions)
        self.preempt(f"preempted by a newer {'goal' if source == 'goal' else 'trajectory on the topic'}")
        self.run = Run(planned, source)
        self.kit.world.notify()
        return self.run

    def _deactivated(self, controller: str) -> None:
        if controller == "arm_controller":
            self.preempt("arm_controller was deactivated")
        elif controller == "gripper_controller":
            self.gripper_target = None

    def preempt(self, reason: str) -> None:
        """End what runs (ABORTED, −1, *reason*); the arm stays where it is."""
        run, self.run = self.run, None
        if run is not None:
            for name in run.trajectory.joints:
                self.velocities[name] = 0.0
            run.finish("aborted", INVALID_GOAL, reason)

    def stop(self, run: Run) -> None:
        """Stop *run* where the arm is now (a cancel)."""
        self.stop_here(run, "canceled", "goal canceled")

    def stop_here(self, run: Run, state: str, why: str) -> None:
        """Stop *run* where the arm is now; it ends *state* (code 0 for a cancel, −1 else) with *why*."""
        if self.run is run:
            self.step(time.monotonic())
            if self.run is run:
                self.run = None
                for name in run.trajectory.joints:
                    self.velocities[name] = 0.0
        run.finish(state, 0 if state == "canceled" else INVALID_GOAL, why)
        self.kit.world.notify()

    def trajectory_feedback(self, joints: tuple[str, ...]) -> dict[str, Any]:
        """A FollowJointTrajectory feedback: the joints now (``desired`` = ``actual``, no error)."""
        now = {
            "positions": [self.positions[n] for n in joints],
            "velocities": [self.velocities[n] for n in joints],
        }
        return {
            "header": self.kit.header(""),
            "joint_names": list(joints),
            "desired": now,
            "actual": now,
            "error": {"positions": [0.0] * len(joints), "velocities": [0.0] * len(joints)},
        }

    def gripper_result(self, *, stalled: bool, reached: bool) -> dict[str, Any]:
        """A GripperCommand result (and feedback): where the finger is."""
        return {
            "position": self.positions[FINGER],
            "effort": 0.0,
            "stalled": stalled,
            "reached_goal": reached,
        }

    def gripper_moving(self) -> bool:
        return self.gripper_target is not None

    def on_trajectory(self, message: dict[str, Any], _client: int) -> None:
        self.received_trajectories.append(message)
        if not self.kit.ros2 and not message.get("points"):
            # ros_control (ROS 1): an empty trajectory stops what runs and holds the arm where it is.
            if self.run is not None:
                self.stop_here(self.run, "aborted", "stopped by an empty trajectory on the topic")
            return
        try:
            self.start(message, message.get("header"), "topic")
        except Invalid as exc:
            log.warning("/arm_controller: trajectory on the topic ignored: %s", exc.text)


class TrajectoryServer(ActionServer):
    """``/arm_controller/follow_joint_trajectory``: a goal is checked, then followed with feedback at 20 Hz.

    As the lab's arm: a bad goal is accepted and aborted at once (its code and reason in the result); with
    ``/arm_controller:reject_invalid_goals`` true it is rejected, as ros2_controllers' controller does.
    """

    def __init__(self, arm: ArmWorld, action_type: str) -> None:
        super().__init__(
            arm.kit.bridge, "/arm_controller/follow_joint_trajectory", action_type, "/arm_controller"
        )
        self.arm = arm

    def accepts(self, goal: dict[str, Any], goal_key: str) -> bool:
        self.arm.received_goals.append(goal)
        if not self.arm.param("/arm_controller:reject_invalid_goals"):
            return True
        try:
            if not self.arm.controllers.is_active("arm_controller"):
                return False
            check_trajectory(
                goal.get("trajectory"),
                allow_partial=bool(self.arm.param("/arm_controller:allow_partial_joints_goal")),
                multi_dof=goal.get("multi_dof_trajectory"),
            )
        except Invalid:
            return False
        return True

    async def run_goal(self, handle: GoalHandle, feedback: FeedbackFn) -> tuple[str, dict[str, Any]]:
        goal = handle.goal
        trajectory = goal.get("trajectory") or {}
        try:
            run = self.arm.start(
                trajectory, trajectory.get("header"), "goal", goal.get("multi_dof_trajectory")
            )
        except Invalid as exc:
            return "aborted", {"error_code": exc.code, "error_string": exc.text}
        cancel: asyncio.Future[Any] = asyncio.ensure_future(handle.cancel.wait())
        try:
            while not run.done.done():
                feedback(self._feedback(run.trajectory.joints))
                await asyncio.wait((run.done, cancel), timeout=FEEDBACK_PERIOD)
                if handle.cancel.is_set():
                    self.arm.stop(run)
            return run.done.result()
        finally:
            cancel.cancel()
            if not run.done.done():  # the server closed under it
                self.arm.stop(run)

    def _feedback(self, joints: tuple[str, ...]) -> dict[str, Any]:
        return self.arm.trajectory_feedback(joints)


class GripperServer(ActionServer):
    """``/gripper_controller/gripper_cmd``: ``command.position`` is the finger's target (0 closed, 0.04 open),
    reached at 0.05 m/s; beyond the travel it stops at the limit (ABORTED, ``stalled``); cancel stops it."""

    def __init__(self, arm: ArmWorld, action_type: str) -> None:
        super().__init__(
            arm.kit.bridge, "/gripper_controller/gripper_cmd", action_type, "/gripper_controller"
        )
        self.arm = arm

    def accepts(self, goal: dict[str, Any], goal_key: str) -> bool:
        self.arm.gripper_goals.append(goal)
        return True

    async def run_goal(self, handle: GoalHandle, feedback: FeedbackFn) -> tuple[str, dict[str, Any]]:
        arm = self.arm
        if not arm.controllers.is_active("gripper_controller"):
            return "aborted", self._result(stalled=False, reached=False)
        command = handle.goal.get("command") or {}
        wanted = float(command.get("position", 0.0))
        lower, upper = LIMITS[FINGER]
        arm.gripper_target = min(max(wanted, lower), upper)
        while arm.gripper_moving():
            feedback(self._result(stalled=False, reached=False))
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(handle.cancel.wait(), FEEDBACK_PERIOD)
            if handle.cancel.is_set():
                arm.gripper_target = None
                arm.velocities[FINGER] = 0.0
                return "canceled", self._result(stalled=False, reached=False)
        reached = abs(arm.positions[FINGER] - wanted) < 1e-6
        return ("succeeded" if reached else "aborted"), self._result(stalled=not reached, reached=reached)

    def _result(self, *, stalled: bool, reached: bool) -> dict[str, Any]:
        return self.arm.gripper_result(stalled=stalled, reached=reached)
