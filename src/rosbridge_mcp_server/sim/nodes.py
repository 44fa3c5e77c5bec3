"""The world's own nodes: turtlesim, a talker, a camera, a 1 kHz counter, services, and the ROS plumbing.

Each node registers its topics and services on the graph and runs its periodic publisher as an asyncio
task. Types come from the interface registry in the dialect's spelling; a type the registry lacks is
logged and that piece of the world is left out rather than failing the whole robot.
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import logging
import math
import time
from collections.abc import Awaitable, Callable
from typing import Any, Literal

from rosbridge_mcp_server.sim.actions import FIBONACCI_NODE, ActionlibFibonacciServer, FibonacciServer
from rosbridge_mcp_server.sim.bridge import Bridge
from rosbridge_mcp_server.sim.graph import ROSBRIDGE_NODE, ServiceEntry
from rosbridge_mcp_server.sim.interfaces import InterfaceError
from rosbridge_mcp_server.sim.png import encode_png
from rosbridge_mcp_server.sim.rosapi import ROSAPI_NODE, Rosapi

__all__ = ["CameraSettings", "WorldNodes"]

log = logging.getLogger("rosbridge_mcp_server.sim")

TURTLESIM = "/turtlesim"
TALKER = "/talker"
ADD_TWO_INTS = "/add_two_ints_server"
CONTROLLER = "/robot_controller"
CAMERA = "/camera"
FAST = "/fast_publisher"

TURTLE_PERIOD = 1.0 / 25  # pose at 25 Hz
COMMAND_HOLD = 1.0  # a velocity command holds this long, then the turtle stops
CHATTER_PERIOD = 0.1
FAST_PERIOD = 0.001
CAMERA_PERIOD = 0.2
INT64_RANGE = 2**64

ServiceFn = Callable[[dict[str, Any]], Awaitable[dict[str, Any]]]


class CameraSettings:
    """Size of the synthetic camera frame."""

    def __init__(self, width: int = 160, height: int = 120) -> None:
        self.width = width
        self.height = height


class WorldNodes:
    """Builds the world on a bridge and runs its periodic publishers."""

    def __init__(
        self,
        bridge: Bridge,
        *,
        fast_topic: bool,
        action_step: float,
        slow_service_seconds: float,
        camera: CameraSettings,
        port: int,
    ) -> None:
        self.bridge = bridge
        self.ros2 = bridge.config.dialect == "ros2"
        self.fast_topic = fast_topic
        self.action_step = action_step
        self.slow_service_seconds = slow_service_seconds
        self.camera = camera
        self.port = port
        self.types: dict[str, str] = {}
        self._loops: list[Callable[[], Awaitable[None]]] = []
        self._tasks: list[asyncio.Task[None]] = []
        self.fibonacci2: FibonacciServer | None = None
        self.fibonacci1: ActionlibFibonacciServer | None = None
        self._seq = 0

    # --- helpers --------------------------------------------------------------------------------------------

    def _type(self, ros2_name: str, ros1_name: str, kind: Literal["msg", "srv", "action"]) -> str | None:
        name = ros2_name if self.ros2 else ros1_name
        try:
            return self.bridge.registry.resolve(name, kind)
        except InterfaceError as exc:
            log.warning("left out of the world (type %s unknown): %s", name, exc)
            return None

    def _stamp(self, seconds: float | None = None) -> dict[str, int]:
        now = time.time() if seconds is None else seconds
        sec = int(now)
        nsec = int((now - sec) * 1e9)
        return {"sec": sec, "nanosec": nsec} if self.ros2 else {"secs": sec, "nsecs": nsec}

    def _header(self, frame_id: str) -> dict[str, Any]:
        header: dict[str, Any] = {"stamp": self._stamp(), "frame_id": frame_id}
        if not self.ros2:
            self._seq += 1
            header = {"seq": self._seq, **header}
        return header

    def _service(self, node: str, name: str, service_type: str | None, handler: ServiceFn) -> None:
        if service_type is None:
            return
        self.bridge.graph.add_service(ServiceEntry(name, service_type, node, handler))

    def _publisher(self, node: str, topic: str, msg_type: str | None) -> bool:
        if msg_type is None:
            return False
        self.bridge.graph.add_publisher(node, topic, msg_type)
        self.types[topic] = msg_type
        return True

    def _publish(self, topic: str, partial: dict[str, Any], *, complete: bool = False) -> None:
        """Publish if anyone listens. ``complete`` messages (every field, wire form) skip the inbound
        conversion, which costs tens of milliseconds for a large image's byte list."""
        msg_type = self.types.get(topic)
        if msg_type is None or not self.bridge.has_subscribers(topic):
            return
        if complete:
            self.bridge.publish(topic, msg_type, partial)
        else:
            self.bridge.publish_json(topic, msg_type, partial)

    # --- building -------------------------------------------------------------------------------------------

    def build(self) -> None:
        """Register every node, topic, service, action and parameter of the world."""
        self._plumbing()
        self.bridge.add_client_topics()
        self._turtlesim()
        self._talker()
        self._services()
        self._camera()
        if self.fast_topic:
            self._fast()
        self._fibonacci()
        Rosapi(self.bridge)
        self._parameters()

    def _plumbing(self) -> None:
        """What every ROS graph has: ``/rosout``, ROS 2 ``/parameter_events`` and per-node services."""
        graph = self.bridge.graph
        nodes = [
            TURTLESIM,
            TALKER,
            ADD_TWO_INTS,
            CONTROLLER,
            CAMERA,
            FIBONACCI_NODE,
            ROSAPI_NODE,
            ROSBRIDGE_NODE,
        ]
        if self.fast_topic:
            nodes.append(FAST)
        log_type = self._type("rcl_interfaces/msg/Log", "rosgraph_msgs/Log", "msg")
        if self.ros2:
            nodes.append("/rosapi_params")
            events_type = self._type("rcl_interfaces/msg/ParameterEvent", "", "msg")
            parameter_services = [
                ("describe_parameters", "rcl_interfaces/srv/DescribeParameters"),
                ("get_parameter_types", "rcl_interfaces/srv/GetParameterTypes"),
                ("get_parameters", "rcl_interfaces/srv/GetParameters"),
                ("list_parameters", "rcl_interfaces/srv/ListParameters"),
                ("set_parameters", "rcl_interfaces/srv/SetParameters"),
                ("set_parameters_atomically", "rcl_interfaces/srv/SetParametersAtomically"),
            ]
            if not self.bridge.config.in_order:
                # Since Iron every node also offers ~/get_type_description (Humble's do not).
                parameter_services.append(
                    ("get_type_description", "type_description_interfaces/srv/GetTypeDescription")
                )
            for node in nodes:
                graph.node(node)
                if log_type:
                    graph.add_publisher(node, "/rosout", log_type)
                if events_type:
                    graph.add_publisher(node, "/parameter_events", events_type)
                if node == "/rosapi_params":
                    continue
                for leaf, service_type in parameter_services:
                    # Listed like a real node's; they answer with default (empty) responses.
                    graph.add_service(
                        ServiceEntry(f"{node}/{leaf}", service_type, node, self._empty_response)
                    )
        else:
            nodes.append("/rosout")
            for node in nodes:
                graph.node(node)
                if log_type and node != "/rosout":
                    graph.add_publisher(node, "/rosout", log_type)
                for leaf, service_type in (
                    ("get_loggers", "roscpp/GetLoggers"),
                    ("set_logger_level", "roscpp/SetLoggerLevel"),
                ):
                    graph.add_service(
                        ServiceEntry(f"{node}/{leaf}", service_type, node, self._empty_response)
                    )
            if log_type:
                graph.add_subscriber("/rosout", "/rosout", log_type)
                graph.add_publisher("/rosout", "/rosout_agg", log_type)

    @staticmethod
    async def _empty_response(request: dict[str, Any]) -> dict[str, Any]:
        return {}

    def _turtlesim(self) -> None:
        twist = self._type("geometry_msgs/msg/Twist", "geometry_msgs/Twist", "msg")
        if twist is not None:
            self.bridge.graph.add_subscriber(TURTLESIM, "/turtle1/cmd_vel", twist, self._on_cmd_vel)
        self._publisher(TURTLESIM, "/turtle1/pose", self._type("turtlesim/msg/Pose", "turtlesim/Pose", "msg"))
        self._publisher(
            TURTLESIM, "/turtle1/color_sensor", self._type("turtlesim/msg/Color", "turtlesim/Color", "msg")
        )
        empty = self._type("std_srvs/srv/Empty", "std_srvs/Empty", "srv")
        self._service(TURTLESIM, "/reset", empty, self._reset)
        self._service(TURTLESIM, "/clear", empty, self._empty_response)
        self._service(
            TURTLESIM,
            "/turtle1/teleport_absolute",
            self._type("turtlesim/srv/TeleportAbsolute", "turtlesim/TeleportAbsolute", "srv"),
            self._teleport_absolute,
        )
        self._service(
            TURTLESIM,
            "/turtle1/teleport_relative",
            self._type("turtlesim/srv/TeleportRelative", "turtlesim/TeleportRelative", "srv"),
            self._teleport_relative,
        )
        self._loops.append(self._turtle_loop)

    def _talker(self) -> None:
        if self._publisher(TALKER, "/chatter", self._type("std_msgs/msg/String", "std_msgs/String", "msg")):
            self._loops.append(self._chatter_loop)

    def _services(self) -> None:
        self._service(
            ADD_TWO_INTS,
            "/add_two_ints",
            self._type("example_interfaces/srv/AddTwoInts", "rospy_tutorials/AddTwoInts", "srv"),
            self._add_two_ints,
        )
        self._service(
            CONTROLLER,
            "/set_enabled",
            self._type("std_srvs/srv/SetBool", "std_srvs/SetBool", "srv"),
            self._set_enabled,
        )
        self._service(
            CONTROLLER,
            "/slow_service",
            self._type("std_srvs/srv/Trigger", "std_srvs/Trigger", "srv"),
            self._slow,
        )

    def _camera(self) -> None:
        raw = self._publisher(
            CAMERA, "/camera/image_raw", self._type("sensor_msgs/msg/Image", "sensor_msgs/Image", "msg")
        )
        compressed = self._publisher(
            CAMERA,
            "/camera/image_raw/compressed",
            self._type("sensor_msgs/msg/CompressedImage", "sensor_msgs/CompressedImage", "msg"),
        )
        if raw or compressed:
            self._loops.append(self._camera_loop)

    def _fast(self) -> None:
        if self._publisher(
            FAST, "/fast_counter", self._type("std_msgs/msg/UInt64", "std_msgs/UInt64", "msg")
        ):
            self._loops.append(self._fast_loop)

    def _fibonacci(self) -> None:
        if self.ros2:
            action_type = self._type("example_interfaces/action/Fibonacci", "", "action")
            if action_type is not None:
                self.fibonacci2 = FibonacciServer(self.bridge, "/fibonacci", action_type, self.action_step)
            return
        if self._type(
            "actionlib_tutorials/FibonacciActionGoal", "actionlib_tutorials/FibonacciActionGoal", "msg"
        ):
            self.fibonacci1 = ActionlibFibonacciServer(
                self.bridge, "/fibonacci", "actionlib_tutorials", self.action_step
            )
            self._loops.append(self.fibonacci1.run)

    def _parameters(self) -> None:
        params = self.bridge.world.params
        config = self.bridge.config
        if self.ros2:
            for node in self.bridge.graph.node_names():
                if node != "/rosapi_params":
                    params[f"{node}:use_sim_time"] = False
            params.update(
                {
                    "/turtlesim:background_r": 69,
                    "/turtlesim:background_g": 86,
                    "/turtlesim:background_b": 255,
                    "/rosbridge_websocket:port": self.port,
                    "/rosbridge_websocket:address": "127.0.0.1",
                    "/rosbridge_websocket:max_message_size": config.max_message_size or 0,
                    "/rosbridge_websocket:call_services_in_new_thread": not config.in_order,
                    "/rosbridge_websocket:send_action_goals_in_new_thread": not config.in_order,
                    "/rosbridge_websocket:default_call_service_timeout": config.default_service_timeout,
                    "/rosapi:topics_glob": "[*]",
                    "/rosapi:services_glob": "[*]",
                    "/rosapi:params_glob": "[*]",
                    "/robot_controller:slow_service_seconds": self.slow_service_seconds,
                    "/fibonacci_server:step_seconds": self.action_step,
                }
            )
        else:
            # In the order the real parameter server lists them (roscore's, the world's, then what
            # rosbridge_websocket.launch sets, with its values; get_param_names is not sorted on ROS 1).
            params.update(
                {
                    "/run_id": "5a1e5c8e-0000-4000-8000-000000000000",
                    "/rosversion": "1.16.0\n",
                    "/rosdistro": "noetic\n",
                    "/robot_controller/slow_service_seconds": self.slow_service_seconds,
                    "/turtlesim/background_r": 69,
                    "/turtlesim/background_g": 86,
                    "/turtlesim/background_b": 255,
                    "/fibonacci_server/step_seconds": self.action_step,
                    "/rosbridge_websocket/authenticate": False,
                    "/rosbridge_websocket/port": self.port,
                    "/rosbridge_websocket/address": "127.0.0.1",
                    "/rosbridge_websocket/retry_startup_delay": 5,
                    "/rosbridge_websocket/fragment_timeout": 600,
                    "/rosbridge_websocket/delay_between_messages": 0,
                    "/rosbridge_websocket/max_message_size": "None",
                    "/rosbridge_websocket/unregister_timeout": 10,
                    "/rosbridge_websocket/use_compression": False,
                    "/rosbridge_websocket/websocket_ping_interval": 0,
                    "/rosbridge_websocket/websocket_ping_timeout": 30,
                    "/rosbridge_websocket/websocket_external_port": "None",
                    "/rosbridge_websocket/topics_glob": "[*]",
                    "/rosbridge_websocket/services_glob": "[*]",
                    "/rosbridge_websocket/params_glob": "[*]",
                    "/rosbridge_websocket/bson_only_mode": False,
                    "/rosbridge_websocket/actual_port": self.port,
                    "/rosapi/topics_glob": "[*]",
                    "/rosapi/services_glob": "[*]",
                    "/rosapi/params_glob": "[*]",
                }
            )

    def background(self) -> tuple[int, int, int]:
        """turtlesim's background colour from its parameters (the camera paints with it too)."""
        params = self.bridge.world.params
        sep = ":" if self.ros2 else "/"
        values = []
        for channel, default in (("r", 69), ("g", 86), ("b", 255)):
            value = params.get(f"/turtlesim{sep}background_{channel}", default)
            values.append(
                int(value) % 256
                if isinstance(value, int | float) and not isinstance(value, bool)
                else default
            )
        return values[0], values[1], values[2]

    # --- running --------------------------------------------------------------------------------------------

    def start(self) -> None:
        """Start every periodic publisher."""
        for loop in self._loops:
            self._tasks.append(asyncio.create_task(self._guard(loop)))

    async def _guard(self, loop: Callable[[], Awaitable[None]]) -> None:
        try:
            await loop()
        except asyncio.CancelledError:
            raise
        except Exception:
            log.exception("world loop %s failed", getattr(loop, "__name__", loop))

    async def stop(self) -> None:
        """Stop them, and any goal still running."""
        for task in self._tasks:
            task.cancel()
        for task in self._tasks:
            with contextlib.suppress(asyncio.CancelledError):
                await task
        self._tasks.clear()
        if self.fibonacci2 is not None:
            await self.fibonacci2.close()

    # --- turtlesim ------------------------------------------------------------------------------------------

    def _on_cmd_vel(self, msg: dict[str, Any], _source: int) -> None:
        world = self.bridge.world
        if not world.enabled:
            log.info("cmd_vel ignored: the robot is disabled (/set_enabled)")
            return
        turtle = world.turtle
        turtle.linear = float(msg.get("linear", {}).get("x", 0.0))
        turtle.angular = float(msg.get("angular", {}).get("z", 0.0))
        turtle.command_time = time.monotonic()
        turtle.commands += 1
        world.notify()

    async def _turtle_loop(self) -> None:
        world = self.bridge.world
        last = time.monotonic()
        while True:
            await asyncio.sleep(TURTLE_PERIOD)
            now = time.monotonic()
            turtle = world.turtle
            if (turtle.linear or turtle.angular) and now - turtle.command_time > COMMAND_HOLD:
                turtle.linear = turtle.angular = 0.0
            turtle.step(now - last)
            last = now
            self._publish(
                "/turtle1/pose",
                {
                    "x": turtle.x,
                    "y": turtle.y,
                    "theta": turtle.theta,
                    "linear_velocity": turtle.linear,
                    "angular_velocity": turtle.angular,
                },
            )
            r, g, b = self.background()
            self._publish("/turtle1/color_sensor", {"r": r, "g": g, "b": b})
            world.notify()

    async def _reset(self, request: dict[str, Any]) -> dict[str, Any]:
        self.bridge.world.turtle.reset()
        self.bridge.world.notify()
        return {}

    async def _teleport_absolute(self, request: dict[str, Any]) -> dict[str, Any]:
        turtle = self.bridge.world.turtle
        turtle.x, turtle.y, turtle.theta = float(request["x"]), float(request["y"]), float(request["theta"])
        self.bridge.world.notify()
        return {}

    async def _teleport_relative(self, request: dict[str, Any]) -> dict[str, Any]:
        turtle = self.bridge.world.turtle
        turtle.theta = math.remainder(turtle.theta + float(request["angular"]), math.tau)
        turtle.x += math.cos(turtle.theta) * float(request["linear"])
        turtle.y += math.sin(turtle.theta) * float(request["linear"])
        self.bridge.world.notify()
        return {}

    # --- other nodes ----------------------------------------------------------------------------------------

    async def _chatter_loop(self) -> None:
        world = self.bridge.world
        while True:
            await asyncio.sleep(CHATTER_PERIOD)
            world.chatter_count += 1
            self._publish("/chatter", {"data": f"Hello World: {world.chatter_count}"})

    async def _fast_loop(self) -> None:
        """1 kHz by an absolute schedule: a late wake-up publishes the missed messages at once."""
        world = self.bridge.world
        start = time.monotonic()
        sent = 0
        while True:
            due = int((time.monotonic() - start) / FAST_PERIOD) + 1
            if due - sent > 100:
                sent = due - 100  # far behind (a stalled loop): catch up at most 100 ms worth
            while sent < due:
                sent += 1
                world.fast_count += 1
                self._publish("/fast_counter", {"data": world.fast_count})
            await asyncio.sleep(max(0.0, start + sent * FAST_PERIOD - time.monotonic()))

    async def _camera_loop(self) -> None:
        world = self.bridge.world
        while True:
            await asyncio.sleep(CAMERA_PERIOD)
            raw_wanted = self.bridge.has_subscribers("/camera/image_raw")
            png_wanted = self.bridge.has_subscribers("/camera/image_raw/compressed")
            if not (raw_wanted or png_wanted):
                continue
            world.camera_frames += 1
            width, height = self.camera.width, self.camera.height
            pixels = self._frame(world.camera_frames, width, height)
            header = self._header("camera")
            if raw_wanted:
                self._publish(
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
                self._publish(
                    "/camera/image_raw/compressed",
                    {"header": header, "format": "png", "data": base64.b64encode(png).decode("ascii")},
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

    async def _add_two_ints(self, request: dict[str, Any]) -> dict[str, Any]:
        total = int(request["a"]) + int(request["b"])
        # int64 arithmetic wraps, as in the C++ example server.
        total = (total + INT64_RANGE // 2) % INT64_RANGE - INT64_RANGE // 2
        return {"sum": total}

    async def _set_enabled(self, request: dict[str, Any]) -> dict[str, Any]:
        world = self.bridge.world
        world.enabled = bool(request["data"])
        if not world.enabled:
            world.turtle.linear = world.turtle.angular = 0.0
        world.notify()
        return {"success": True, "message": "robot enabled" if world.enabled else "robot disabled"}

    async def _slow(self, request: dict[str, Any]) -> dict[str, Any]:
        await asyncio.sleep(self.slow_service_seconds)
        return {"success": True, "message": f"done after {self.slow_service_seconds:g} s"}
