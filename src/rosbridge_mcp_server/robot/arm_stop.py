"""Stopping a trajectory this server published on a controller's ``…/joint_trajectory`` topic.

A ``trajectory_msgs/JointTrajectory`` on the topic has no goal to cancel: the controller follows it until its
last point, or until another trajectory replaces it. So a stop publishes one that holds the joints:

* **ROS 1** (ros_control's ``joint_trajectory_controller``): an empty trajectory (no points) stops every
  queued trajectory and holds the position, as that controller documents;
* **ROS 2** (ros2_controllers' ``JointTrajectoryController``, Jazzy and later): an empty trajectory is refused
  ("Empty trajectory received.") and changes nothing, so the stop sends one point, where ``/joint_states``
  says the joints are now, at ``time_from_start`` 0: the controller jumps its command there and holds it.

:class:`TrajectorySent` remembers, per topic, which joints the last trajectory named and when it runs out;
one that has run out is left alone (a hold then would only preempt what someone else runs). Pure but for
:func:`stop_trajectories`, which reads the joints and publishes.
"""

from __future__ import annotations

import math
import time
from collections.abc import Collection, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.client import Dialect
from rosbridge_mcp_server.errors import RosbridgeError
from rosbridge_mcp_server.robot.arm_goals import TRAJECTORY_TOPIC_TYPE

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = ["GRACE_SECONDS", "TrajectorySent", "hold_message", "stop_trajectories", "trajectory_sent"]

#: How long after its last point a trajectory still counts as running (the controller's goal-time slack).
GRACE_SECONDS = 1.0
#: The longest a trajectory is taken to run (a far-future stamp or a huge time is held to this).
LONGEST_SECONDS = 24 * 3600.0
#: How long the stop waits for ``/joint_states`` to learn where to hold a ROS 2 arm.
POSITIONS_SECONDS = 1.0


@dataclass(frozen=True)
class TrajectorySent:
    """The last trajectory this server published on *topic*: its type as sent, its joints, and until when
    (monotonic clock) it may run."""

    topic: str
    type: str
    joints: tuple[str, ...]
    until: float


def _seconds(value: Any) -> float:
    if not isinstance(value, Mapping):
        return 0.0
    total = 0.0
    for key, scale in (("sec", 1.0), ("secs", 1.0), ("nanosec", 1e-9), ("nsecs", 1e-9)):
        number = value.get(key)
        if isinstance(number, int | float) and not isinstance(number, bool) and math.isfinite(number):
            total += number * scale
    return total


def trajectory_sent(topic: str, type_name: str, message: Any, now: float) -> TrajectorySent | None:
    """The record of *message* published on *topic* at *now* (monotonic), or ``None`` when it is no
    JointTrajectory (or names no joint)."""
    short = Dialect.short_type(type_name) if "/" in type_name else type_name
    if short != TRAJECTORY_TOPIC_TYPE or not isinstance(message, Mapping):
        return None
    names = message.get("joint_names")
    joints = tuple(n for n in names if isinstance(n, str)) if isinstance(names, list) else ()
    points = message.get("points")
    if not joints or not isinstance(points, list) or not points:
        return None
    last = points[-1].get("time_from_start") if isinstance(points[-1], Mapping) else None
    header = message.get("header")
    stamp = _seconds(header.get("stamp")) if isinstance(header, Mapping) else 0.0
    later = max(0.0, stamp - time.time()) if stamp else 0.0
    runs = min(LONGEST_SECONDS, later + max(0.0, _seconds(last)))
    return TrajectorySent(topic, type_name, joints, now + runs + GRACE_SECONDS)


def hold_message(sent: TrajectorySent, ros_version: int, positions: Mapping[str, float]) -> dict[str, Any]:
    """The trajectory that stops *sent*'s controller where it is (see the module docstring); ROS 2 needs every
    joint's position in *positions* (``KeyError`` names the one missing)."""
    # Stamp 0 starts it now: a missing header is stamped by rosbridge with the time it arrives, which makes a
    # point at 0 s end in the past (refused as OLD_HEADER_TIMESTAMP).
    if ros_version == 1:
        header = {"stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}
        return {"header": header, "joint_names": list(sent.joints), "points": []}
    return {
        "header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": ""},
        "joint_names": list(sent.joints),
        "points": [
            {
                "positions": [positions[name] for name in sent.joints],
                "time_from_start": {"sec": 0, "nanosec": 0},
            }
        ],
    }


async def stop_trajectories(
    client: RosbridgeClient, graph: RosGraph, sent: list[TrajectorySent], streamed: Collection[str] = ()
) -> tuple[list[tuple[str, str, dict[str, Any]]], list[str]]:
    """Hold each controller *sent* still drives (or whose topic had a stream, *streamed*, that this stop
    ended: its last message may have come long after the first): the (topic, type, message) published, and
    what failed."""
    running = [entry for entry in sent if entry.until > time.monotonic() or entry.topic in streamed]
    if not running:
        return [], []
    # Imported past the return above: a stop with no trajectory to hold never loads the arm's modules (an
    # arm act has loaded them already, when it learnt the arm).
    from rosbridge_mcp_server.robot.arm_scene import positions_now  # noqa: PLC0415 - arm robots only

    try:
        version = (await client.ros_info()).version
        positions = {} if version == 1 else await positions_now(client, graph, POSITIONS_SECONDS)
    except RosbridgeError as exc:
        topics = ", ".join(entry.topic for entry in running)
        return [], [f"could not stop the trajectory on {topics}: {exc}"]
    held: list[tuple[str, str, dict[str, Any]]] = []
    failures: list[str] = []
    for entry in running:
        try:
            message = hold_message(entry, version, positions)
        except KeyError as missing:
            failures.append(
                f"the trajectory on {entry.topic} was not stopped: /joint_states did not give "
                f"{missing.args[0]}'s position within {POSITIONS_SECONDS:g} s, so there is no place to hold "
                "it; check the arm"
            )
            continue
        try:
            await client.publish(entry.topic, entry.type, message)
        except RosbridgeError as exc:
            failures.append(f"the hold on {entry.topic} failed: {exc}")
        else:
            held.append((entry.topic, entry.type, message))
    return held, failures
