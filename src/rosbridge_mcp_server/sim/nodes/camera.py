"""``/camera``: a colour image (raw and PNG-compressed) and a depth image, published while someone watches."""

from __future__ import annotations

import array
import asyncio
import base64
import math
import sys
from collections.abc import Callable

from rosbridge_mcp_server.sim.nodes.kit import NodeKit
from rosbridge_mcp_server.sim.nodes.room import CEILING_HEIGHT, ray_distance
from rosbridge_mcp_server.sim.png import encode_png

__all__ = [
    "CAMERA",
    "CAMERA_PERIOD",
    "DEPTH_FOV",
    "DEPTH_MAX",
    "Camera",
    "CameraSettings",
    "depth_frame",
]

CAMERA = "/camera"
CAMERA_PERIOD = 0.2
#: The depth camera's horizontal field of view and its mount (as in /tf_static: 0.1 m ahead, 0.2 m up).
DEPTH_FOV = math.radians(60)
CAMERA_AHEAD = 0.1
CAMERA_HEIGHT = 0.2
#: Farther than this the depth camera sees nothing: 0, as depth cameras report "no reading" in 16UC1.
DEPTH_MAX = 10.0


class CameraSettings:
    """Size of the synthetic camera frames."""

    def __init__(self, width: int = 160, height: int = 120) -> None:
        self.width = width
        self.height = height


def depth_frame(x: float, y: float, theta: float, width: int, height: int) -> bytes:
    """A 16UC1 depth image (millimetres, little-endian) of the room from a camera at (x, y) looking along
    ``theta``: walls and pillar in each column, the floor below the horizon and the ceiling above it."""
    focal = (width / 2) / math.tan(DEPTH_FOV / 2)
    cx, cy = (width - 1) / 2, (height - 1) / 2
    walls: list[float] = []
    for column in range(width):
        offset = math.atan2(cx - column, focal)
        walls.append(ray_distance(x, y, theta + offset) * math.cos(offset))
    wall_row = _millimetres(walls)
    rows: list[array.array[int]] = []
    widest = max(walls)
    for row in range(height):
        below = row - cy
        if below > 0:
            plane = CAMERA_HEIGHT * focal / below
        elif below < 0:
            plane = (CEILING_HEIGHT - CAMERA_HEIGHT) * focal / -below
        else:
            plane = math.inf
        rows.append(wall_row if plane >= widest else _millimetres([min(w, plane) for w in walls]))
    data = array.array("H")
    for values in rows:
        data.extend(values)
    if sys.byteorder == "big":
        data.byteswap()
    return data.tobytes()


def _millimetres(depths: list[float]) -> array.array[int]:
    return array.array("H", (round(d * 1000) if d <= DEPTH_MAX else 0 for d in depths))


class Camera:
    """The colour camera paints turtlesim's background with moving bars; the depth camera sees the room."""

    def __init__(
        self, kit: NodeKit, settings: CameraSettings, background: Callable[[], tuple[int, int, int]]
    ) -> None:
        self.kit = kit
        self.settings = settings
        self.background = background

    def build(self) -> None:
        kit = self.kit
        image = kit.msg_type("sensor_msgs", "Image")
        raw = kit.publisher(CAMERA, "/camera/image_raw", image)
        compressed = kit.publisher(
            CAMERA, "/camera/image_raw/compressed", kit.msg_type("sensor_msgs", "CompressedImage")
        )
        depth = kit.publisher(CAMERA, "/camera/depth/image_raw", image)
        if raw or compressed or depth:
            kit.loops.append(self._loop)

    async def _loop(self) -> None:
        kit = self.kit
        world = kit.world
        while True:
            await asyncio.sleep(CAMERA_PERIOD)
            raw_wanted = kit.wants("/camera/image_raw")
            png_wanted = kit.wants("/camera/image_raw/compressed")
            depth_wanted = kit.wants("/camera/depth/image_raw")
            if not (raw_wanted or png_wanted or depth_wanted):
                continue
            width, height = self.settings.width, self.settings.height
            header = kit.header("camera")
            if raw_wanted or png_wanted:
                world.camera_frames += 1
                pixels = self._frame(world.camera_frames, width, height)
                if raw_wanted:
                    kit.publish(
                        "/camera/image_raw",
                        {
                            "header": header,
                            "height": height,
                            "width": width,
                            "encoding": "rgb8",
                            "is_bigendian": 0,
                            "step": width * 3,
                            "data": base64.b64encode(pixels).decode("ascii"),
                        },
                        complete=True,
                    )
                if png_wanted:
                    png = encode_png(width, height, pixels)
                    kit.publish(
                        "/camera/image_raw/compressed",
                        {"header": header, "format": "png", "data": base64.b64encode(png).decode("ascii")},
                        complete=True,
                    )
            if depth_wanted:
                turtle = world.turtle
                x = turtle.x + CAMERA_AHEAD * math.cos(turtle.theta)
                y = turtle.y + CAMERA_AHEAD * math.sin(turtle.theta)
                depth = depth_frame(x, y, turtle.theta, width, height)
                world.depth_frames += 1
                kit.publish(
                    "/camera/depth/image_raw",
                    {
                        "header": header,
                        "height": height,
                        "width": width,
                        "encoding": "16UC1",
                        "is_bigendian": 0,
                        "step": width * 2,
                        "data": base64.b64encode(depth).decode("ascii"),
                    },
                    complete=True,
                )
            world.notify()

    def _frame(self, frame: int, width: int, height: int) -> bytes:
        """turtlesim's background with a white bar moving right and a yellow one moving down."""
        background = bytes(self.background())
        bar = max(1, width // 16)
        x0 = (frame * 4) % width
        row = bytearray(background * width)
        for x in range(x0, min(x0 + bar, width)):
            row[x * 3 : x * 3 + 3] = b"\xff\xff\xff"
        band_row = bytes(b"\xff\xd0\x00" * width)
        band = max(1, height // 12)
        y0 = (frame * 3) % height
        y1 = min(y0 + band, height)
        return bytes(row) * y0 + band_row * (y1 - y0) + bytes(row) * (height - y1)
