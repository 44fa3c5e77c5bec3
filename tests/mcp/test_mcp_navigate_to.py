"""``navigate_to`` on the Nav2 world in both dialects, through an in-memory MCP session under the server's own
guard: a goal in free space is reached (the pose from ``get_transform``), progress comes, the picture shows
the path; a goal in an obstacle, off the map or outside the geofence is refused before anything is sent (a raw
rosbridge socket sees no goal), and ``publish_action`` on the same action is refused the same way; a cancel of
the MCP call and ``stop_robot`` stop the robot; named places, relative moves and frames."""

from __future__ import annotations

import base64
import io
import math
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any

import pytest
from mcp.types import ImageContent
from mcp_harness import Session, open_session, text_of
from PIL import Image

from rosbridge_mcp_server.safety import parse_policy
from rosbridge_mcp_server.sim import SimulatedRobot

MakeSim = Callable[..., Awaitable[SimulatedRobot]]

#: The sim drives this many times faster than a real robot, so that a test drive takes a second or two.
TEST_SPEED = 5.0

POLICY = {
    "navigation": {
        "max_goal_distance": 6.0,
        "keep_out": {"corner": [[8.0, 1.0], [10.5, 1.0], [10.5, 3.0], [8.0, 3.0]]},
    },
    "places": {"door": [2.0, 8.0, 90], "dock": {"x": 3.0, "y": 3.0, "yaw": 180}},
}


@pytest.fixture(params=["ros2", "ros1"])
async def nav2(request: pytest.FixtureRequest, make_sim: MakeSim) -> SimulatedRobot:
    robot = await make_sim(dialect=request.param, world="nav2")
    robot.nav2.navigator.speed = TEST_SPEED
    return robot


@pytest.fixture
async def session(nav2: SimulatedRobot) -> AsyncIterator[Session]:
    async with open_session(nav2.url, guard=None, policy=parse_policy(POLICY, where="test.toml")) as opened:
        yield opened


def goal_topic(robot: SimulatedRobot) -> tuple[str, str]:
    """What a raw client subscribes to see every navigation goal the bridge is given."""
    if robot.dialect == "ros1":
        return "/move_base/goal", "move_base_msgs/MoveBaseActionGoal"
    return "/navigate_to_pose/_action/status", "action_msgs/msg/GoalStatusArray"


async def pose_of(session: Session) -> tuple[float, float, float]:
    """The robot's pose in the map from get_transform: x, y, yaw in degrees."""
    result = await session.ok("get_transform", {"target_frame": "map", "source_frame": "base_link"})
    data = result.structured_content or {}
    return data["translation"]["x"], data["translation"]["y"], data["rotation"]["yaw"]


def picture(result: Any) -> Image.Image:
    images = [block for block in result.content if isinstance(block, ImageContent)]
    assert images, "no picture in the answer"
    return Image.open(io.BytesIO(base64.b64decode(images[0].data)))


def green_pixels(image: Image.Image) -> int:
    """Pixels of the path colour (robot/drawing.PATH_COLOUR)."""
    from rosbridge_mcp_server.robot.drawing import PATH_COLOUR

    raw = image.convert("RGB").tobytes()
    return sum(1 for i in range(0, len(raw), 3) if tuple(raw[i : i + 3]) == PATH_COLOUR)


def yaw_error(a: float, b: float) -> float:
    return abs(math.degrees(math.atan2(math.sin(math.radians(a - b)), math.cos(math.radians(a - b)))))


async def test_a_goal_in_free_space_is_reached_with_progress_and_a_picture(
    session: Session, nav2: SimulatedRobot
) -> None:
    result = await session.ok("navigate_to", {"x": 2.5, "y": 7.5, "yaw": 90})
    data = result.structured_content or {}
    assert data["succeeded"], text_of(result)
    x, y, yaw = await pose_of(session)
    assert math.hypot(x - 2.5, y - 7.5) < 0.2
    assert yaw_error(yaw, 90) < 10
    assert session.progress, "no progress reported"
    assert any("m to go" in (message or "") for _, _, message in session.progress)
    assert data["driven"] > 3.0
    assert green_pixels(picture(result)) > 50


async def test_a_goal_in_an_obstacle_is_refused_before_anything_is_sent(
    session: Session, nav2: SimulatedRobot
) -> None:
    before = len(nav2.world.goals)
    # The pillar of the room is at (8.5, 8.5), 0.5 m round.
    text = await session.error("navigate_to", {"x": 8.5, "y": 8.5})
    assert "obstacle" in text
    assert "nothing was sent" in text
    assert len(nav2.world.goals) == before
