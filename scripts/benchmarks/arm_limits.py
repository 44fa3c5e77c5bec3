"""Item 19d: the arm judge's check of one joint goal along its path (URDF limits, the speed scale, the
workspace and keep-out boxes by forward kinematics), on the simulated arm's own description: p50 ≤ 5 ms."""

from __future__ import annotations

import math
import time

from benchmarks.harness import Context, Row, Stats, timing_row, verdict
from benchmarks.internals import Act, ArmScene, arm_refusal, arm_urdf, parse_policy, parse_urdf, sim_arm_home

__all__: list[str] = []

#: The issue's target for one goal's limit and workspace check along its path.
PATH_CHECK_TARGET = 0.005
#: Boxes the goal stays clear of, so that every sample is checked against both kinds.
BOXES = {
    "arm": {
        "workspace": {"table": [[-1.0, -1.0, 0.3], [1.0, 1.0, 1.3]]},
        "keep_out": {"person": [[-1.0, 0.6, 0.0], [1.0, 2.0, 2.0]]},
    }
}


async def measure_arm_limits(ctx: Context) -> list[Row]:
    """A 90° pan with the elbow moving too (~50 samples of 2°, each a forward kinematics of the chain),
    judged under the boxes: the whole judgement's p50."""
    # The simulated robot appends the arm to its base's description: here on a bare base_link.
    robot = parse_urdf(f'<robot name="arm"><link name="base_link"/>{arm_urdf()}</robot>')
    home = sim_arm_home()
    joints = [joint.name for joint in robot.movable_joints if "gripper" not in joint.name]
    target = {**home, "shoulder_pan_joint": math.radians(-90), "elbow_joint": 0.6}
    goal = {
        "trajectory": {
            "joint_names": joints,
            "points": [
                {"positions": [target[n] for n in joints], "time_from_start": {"sec": 30, "nanosec": 0}}
            ],
        }
    }
    act = Act(
        "publish_action",
        "action",
        "/arm_controller/follow_joint_trajectory",
        "control_msgs/action/FollowJointTrajectory",
        goal,
        scene=ArmScene(robot, home),
    )
    rules = parse_policy(BOXES, where="benchmark").arm
    rounds = 200 if ctx.plan.name == "full" else 20
    samples = []
    for _ in range(rounds):
        began = time.perf_counter()
        refusal = arm_refusal(act, rules)
        samples.append(time.perf_counter() - began)
    if refusal is not None:
        raise RuntimeError(f"the benchmark's goal was refused: {refusal.text}")
    stats = Stats.of(samples)
    row = timing_row(
        "19d",
        "the arm judge: a 90° pan of the simulated arm's 6-joint chain checked along its path (limits, speed "
        "scale, a workspace and a keep-out box; ~50 forward kinematics)",
        stats,
        target=f"p50 ≤ {PATH_CHECK_TARGET * 1e3:g} ms",
    )
    row.verdict = verdict(stats.median <= PATH_CHECK_TARGET)
    return [row]
