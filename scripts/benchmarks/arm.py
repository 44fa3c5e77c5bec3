"""Item 18: the arm. Forward kinematics and joint limits along a joint goal's path (the kinematics a goal's
check runs, p50 ≤ 5 ms), ``view_arm`` on the simulated arm through the console script, and its text for a
7-joint arm with a gripper (≤ 8,000 characters)."""

from __future__ import annotations

import contextlib
import json
import math
import time

from benchmarks.harness import (
    Context,
    Row,
    Stats,
    our_server_command,
    raw_pipe_client,
    simulated_robot,
    timing_row,
    verdict,
)
from benchmarks.internals import Chain, arm_answer_text, parse_urdf

__all__: list[str] = []

PATH_POINTS = 100
PATH_TARGET = 5e-3
TEXT_TARGET = 8_000
LIMIT = '<limit lower="-2.8973" upper="2.8973" velocity="2.175" effort="87"/>'


def seven_joint_arm() -> str:
    """A Franka-like arm: 7 revolute joints with turned origins, a hand, two fingers (one mimics)."""
    links = (
        "".join(f'<link name="link{i}"/>' for i in range(9))
        + '<link name="hand"/><link name="lf"/><link name="rf"/>'
    )
    joints = "".join(
        f'<joint name="joint{i}" type="revolute"><parent link="link{i - 1}"/><child link="link{i}"/>'
        f'<origin xyz="0 0.05 0.2" rpy="{1.5708 if i % 2 else -1.5708} 0 0"/>'
        f'<axis xyz="0 0 1"/>{LIMIT}</joint>'
        for i in range(1, 8)
    )
    joints += '<joint name="flange" type="fixed"><parent link="link7"/><child link="link8"/></joint>'
    joints += '<joint name="hand_joint" type="fixed"><parent link="link8"/><child link="hand"/></joint>'
    for name, child, mimic in (("finger1", "lf", ""), ("finger2", "rf", '<mimic joint="finger1"/>')):
        joints += (
            f'<joint name="{name}" type="prismatic"><parent link="hand"/><child link="{child}"/>'
            f'<axis xyz="0 1 0"/><limit lower="0" upper="0.04" velocity="0.2" effort="100"/>{mimic}</joint>'
        )
    return f'<robot name="seven">{links}{joints}</robot>'


def _path_check(
    chain: Chain, limits: dict[str, tuple[float, float]], start: list[float], goal: list[float]
) -> bool:
    """Every point of the straight joint path within limits, and the tool's pose at each (what a workspace
    check then compares with its boxes)."""
    names = list(limits)
    for step in range(PATH_POINTS + 1):
        share = step / PATH_POINTS
        positions = {n: a + (b - a) * share for n, a, b in zip(names, start, goal, strict=True)}
        if not all(limits[n][0] <= v <= limits[n][1] for n, v in positions.items()):
            return False
        chain.tip_pose(positions)
    return True


def _fk_row(ctx: Context) -> Row:
    robot = parse_urdf(seven_joint_arm())
    chain = Chain(robot, "link0", "hand")
    limits = {
        j.name: (j.limits.lower or -math.pi, j.limits.upper or math.pi)
        for j in robot.movable_joints
        if j.name.startswith("joint")
    }
    start, goal = [0.0] * 7, [1.2, -0.8, 0.5, -1.5, 0.3, 1.0, -0.4]
    samples = []
    for _ in range(200 if ctx.plan.name == "full" else 20):
        began = time.perf_counter()
        _path_check(chain, limits, start, goal)
        samples.append(time.perf_counter() - began)
    stats = Stats.of(samples)
    row = timing_row(
        "18a",
        f"a 7-joint goal's path: limits and the tool's pose (forward kinematics) at {PATH_POINTS + 1} points",
        stats,
        target="p50 ≤ 5 ms",
    )
    row.verdict = verdict(stats.median <= PATH_TARGET)
    return row


async def measure_arm(ctx: Context) -> list[Row]:
    """Item 18: the path check's kinematics, ``view_arm`` on the simulated arm, its text for a 7-joint arm."""
    return [_fk_row(ctx), await _view_arm_row(ctx), _seven_joint_row()]


async def _view_arm_row(ctx: Context) -> Row:
    """``view_arm`` through the console script on the simulated arm (not in --quick: two processes to start,
    for the benchmark smoke's time)."""
    if ctx.plan.name != "full":
        return Row(
            item="18b", what="`view_arm` on the simulated arm", target="text ≤ 8,000", verdict="n/a (quick)"
        )
    async with contextlib.AsyncExitStack() as stack:
        url = await stack.enter_async_context(simulated_robot(ctx.errlog, world="arm"))
        ours = await stack.enter_async_context(raw_pipe_client(our_server_command(url), ctx.errlog, {}))
        answer = await ours.tool("view_arm", {})  # the first call also waits for the connection
        samples = []
        for _ in range(10):
            began = time.perf_counter()
            answer = await ours.tool("view_arm", {})
            samples.append(time.perf_counter() - began)
    result = answer["result"]
    text = "".join(block.get("text", "") for block in result["content"])
    structured = len(json.dumps(result.get("structuredContent")))
    row = timing_row(
        "18b",
        f"`view_arm` on the simulated arm (text {len(text):,} / structured {structured:,} characters)",
        Stats.of(samples),
        target="text ≤ 8,000",
    )
    row.verdict = verdict(len(text) <= TEXT_TARGET and not result.get("isError"))
    row.figures.update(text_chars=len(text), structured_chars=structured)
    return row


def _seven_joint_row() -> Row:
    """``view_arm``'s text for a 7-joint arm with a gripper and its controllers (the answer's own code)."""
    arm_type = "joint_trajectory_controller/JointTrajectoryController"
    controllers = {
        "controller": [
            {"name": "arm_controller", "state": "active", "type": arm_type,
             "claimed_interfaces": [f"joint{i}/position" for i in range(1, 8)]},
            {"name": "gripper_controller", "state": "active", "claimed_interfaces": ["finger1/position"],
             "type": "position_controllers/GripperActionController"},
            {"name": "joint_state_broadcaster", "state": "active",
             "type": "joint_state_broadcaster/JointStateBroadcaster"},
        ]
    }  # fmt: skip
    seven = arm_answer_text(seven_joint_arm(), controllers)
    return Row(
        item="18c",
        what=f"`view_arm`'s text, a 7-joint arm with a gripper, 3 controllers: {len(seven):,} characters",
        target="≤ 8,000",
        verdict=verdict(len(seven) <= TEXT_TARGET),
        figures={"text_chars": len(seven)},
    )
