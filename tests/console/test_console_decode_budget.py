"""The console's camera holds frames to the decode budget too: a PNG bomb published on the robot's graph by
a raw socket is not decoded, and the camera status says why, naming the size and the limit. Both dialects."""

from __future__ import annotations

import asyncio
import base64
import json

from console_harness import served_console
from websockets.asyncio.client import connect

from rosbridge_mcp_server.robot.budget import DECODE_BUDGET, byte_size
from rosbridge_mcp_server.sim import SimulatedRobot
from rosbridge_mcp_server.sim.png import png_bomb

TOPIC = "/attack/compressed"


async def test_the_console_camera_refuses_a_png_bomb_and_says_why(sim: SimulatedRobot) -> None:
    """The operator picks the bomb's topic: the camera shows no frame, its status names 13000x13000 and the
    budget."""
    msg_type = "sensor_msgs/msg/CompressedImage" if sim.dialect == "ros2" else "sensor_msgs/CompressedImage"
    bomb = {"format": "png", "data": base64.b64encode(png_bomb()).decode()}
    async with connect(sim.url, max_size=None) as attacker, served_console(sim.url) as console:
        await attacker.send(json.dumps({"op": "advertise", "topic": TOPIC, "type": msg_type, "latch": True}))
        await attacker.send(json.dumps({"op": "publish", "topic": TOPIC, "msg": bomb}))
        barrier = {"op": "call_service", "id": "barrier", "service": "/rosapi/get_time"}
        await attacker.send(json.dumps(barrier))
        async with asyncio.timeout(10):
            while json.loads(await attacker.recv()).get("id") != "barrier":
                pass
        hub = console.running.hub
        hub.show_camera(TOPIC)
        async with asyncio.timeout(15):
            while "budget" not in hub.camera_status:
                await hub.wait_changed(hub.marks(), 1.0)
        status = hub.camera_status
        frame = hub.frame
        hub.show_camera(None)
    assert status.startswith("cannot show this frame: The compressed image declares 13000x13000 pixels")
    assert f"budget of {byte_size(DECODE_BUDGET)}" in status
    assert frame is None
