"""The world's nodes: turtlesim, a talker, a camera, range sensors, services, an action, and the ROS plumbing.

Each node registers its topics and services on the graph and runs its periodic publisher as an asyncio
task. Types come from the interface registry in the dialect's spelling; a type the registry lacks is
logged and that piece of the world is left out rather than failing the whole robot.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from typing import Any

from rosbridge_mcp_server.sim.actions import FIBONACCI_NODE, ActionlibFibonacciServer, FibonacciServer
from rosbridge_mcp_server.sim.bridge import Bridge
from rosbridge_mcp_server.sim.graph import ROSBRIDGE_NODE, ServiceEntry
from rosbridge_mcp_server.sim.nodes.arm import ARM_NODES, ArmWorld
from rosbridge_mcp_server.sim.nodes.arm.model import arm_urdf
from rosbridge_mcp_server.sim.nodes.arm.ros1 import build_ros1
from rosbridge_mcp_server.sim.nodes.camera import CAMERA, Camera, CameraSettings
from rosbridge_mcp_server.sim.nodes.kit import Loop, NodeKit
from rosbridge_mcp_server.sim.nodes.nav2 import Nav2World
from rosbridge_mcp_server.sim.nodes.navigation import MAP_SERVER, PLANNER, MapServer, Planner
from rosbridge_mcp_server.sim.nodes.parameter_services import PARAMETER_SERVICES, ParameterServices
from rosbridge_mcp_server.sim.nodes.room import ROOM_MAP_CELLS
from rosbridge_mcp_server.sim.nodes.sensors import (
    LIDAR,
    ODOMETRY,
    RANGE_MAX,
    ROBOT_STATE_PUBLISHER,
    Lidar,
    RobotState,
    robot_description,
)
from rosbridge_mcp_server.sim.nodes.turtlesim import TURTLESIM, Turtlesim
from rosbridge_mcp_server.sim.rosapi import ROSAPI_NODE, ROSAPI_PARAMS, Rosapi, RosapiOptions

__all__ = ["WorldNodes"]

log = logging.getLogger("rosbridge_mcp_server.sim")

TALKER = "/talker"
ADD_TWO_INTS = "/add_two_ints_server"
CONTROLLER = "/robot_controller"
FAST = "/fast_publisher"

CHATTER_PERIOD = 0.1
FAST_PERIOD = 0.001
INT64_RANGE = 2**64


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
        rosapi: RosapiOptions | None = None,
        node_services: bool = True,
        map_cells: int = ROOM_MAP_CELLS,
        world: str = "turtle",
        robots: int = 1,
        bridge_parameters: bool = True,
        faults: tuple[str, ...] = (),
    ) -> None:
        self.bridge = bridge
        self.kit = NodeKit(bridge)
        self.ros2 = self.kit.ros2
        self.fast_topic = fast_topic
        self.action_step = action_step
        self.slow_service_seconds = slow_service_seconds
        self.port = port
        self.rosapi_options = rosapi or RosapiOptions()
        self.node_services = node_services
        #: rosbridge_suite's bridge and rosapi nodes have parameter services; rosbridge-server-rs's have none.
        self.bridge_parameters = bridge_parameters
        #: Since Iron every ROS 2 node offers ~/get_type_description and declares
        #: start_type_description_service; Humble's do not.
        self.type_descriptions = self.ros2 and bridge.config.distro != "humble"
        self.turtlesim = Turtlesim(self.kit)
        self.camera = Camera(self.kit, camera, self.turtlesim.background)
        self.robot_state = RobotState(self.kit)
        self.lidar = Lidar(self.kit)
        self.map_server = MapServer(self.kit, map_cells)
        self.planner = Planner(self.kit)
        self._tasks: list[asyncio.Task[None]] = []
        self.fibonacci2: FibonacciServer | None = None
        self.fibonacci1: ActionlibFibonacciServer | None = None
        #: The Nav2 world when the robot runs it (``world="nav2"``), else ``None``.
        self.nav2: Nav2World | None = None
        #: The arm when the robot has one (``world="arm"``: the turtle world with an arm), else ``None``.
        self.arm: ArmWorld | None = None
        if world == "arm":
            self.arm = ArmWorld(self.kit, faults)
        elif world == "nav2":
            self.nav2 = Nav2World(
                self.kit,
                robots=robots,
                action_step=action_step,
                type_descriptions=self.type_descriptions,
                faults=faults,
            )
        elif faults:
            raise ValueError("faults need world='nav2' or world='arm'")
        if (robots != 1 and world != "nav2") or world not in ("turtle", "nav2", "arm"):
            raise ValueError(
                f"world must be 'turtle', 'nav2' or 'arm' (robots only with nav2), not {world!r}"
            )

    # --- building -------------------------------------------------------------------------------------------

    def build(self) -> None:
        """Register every node, topic, service, action and parameter of the world."""
        if self.nav2 is not None:
            self.nav2.build()
            self._plumbing()
            self.bridge.add_client_topics()
            self.rosapi = Rosapi(self.bridge, self.rosapi_options)
            self._parameters()
            return
        self._plumbing()
        self.bridge.add_client_topics()
        self.turtlesim.build()
        self._talker()
        self._services()
        self.camera.build()
        self.robot_state.build()
        self.lidar.build()
        self.map_server.build()
        self.planner.build()
        if self.arm is not None:
            self.arm.build()
            if not self.kit.ros2:
                build_ros1(self.arm)
            self.robot_state.extra_description = arm_urdf()
            self.robot_state.extra_static = self.arm.static_transforms()
        if self.fast_topic:
            self._fast()
        self._fibonacci()
        self.rosapi = Rosapi(self.bridge, self.rosapi_options)
        self._parameters()

    def _node_names(self) -> list[str]:
        if self.nav2 is not None:
            return [*self.nav2.node_names, ROSAPI_NODE, ROSBRIDGE_NODE]
        nodes = [
            TURTLESIM,
            TALKER,
            ADD_TWO_INTS,
            CONTROLLER,
            CAMERA,
            ROBOT_STATE_PUBLISHER,
            ODOMETRY,
            LIDAR,
            MAP_SERVER,
            PLANNER,
            FIBONACCI_NODE,
            ROSAPI_NODE,
            ROSBRIDGE_NODE,
        ]
        if self.fast_topic:
            nodes.append(FAST)
        if self.arm is not None:
            nodes.extend(ARM_NODES)
        return nodes

    def _plumbing(self) -> None:
        """What every ROS graph has: ``/rosout``, ROS 2 ``/parameter_events`` and per-node services."""
        graph = self.bridge.graph
        kit = self.kit
        nodes = self._node_names()
        log_type = kit.type("rcl_interfaces/msg/Log", "rosgraph_msgs/Log", "msg")
        if self.ros2:
            nodes.append(ROSAPI_PARAMS)
            events_type = kit.type("rcl_interfaces/msg/ParameterEvent", "", "msg")
            for node in nodes:
                graph.node(node)
                if log_type:
                    graph.add_publisher(node, "/rosout", log_type)
                if events_type:
                    graph.add_publisher(node, "/parameter_events", events_type)
                if not self.node_services:
                    continue
                if node != ROSAPI_PARAMS and (
                    self.bridge_parameters or node not in (ROSBRIDGE_NODE, ROSAPI_NODE)
                ):
                    # rosapi's helper node starts without parameter services.
                    services = ParameterServices(self.bridge.world, node)
                    for leaf, service_type in PARAMETER_SERVICES:
                        graph.add_service(
                            ServiceEntry(f"{node}/{leaf}", service_type, node, getattr(services, leaf))
                        )
                if self.type_descriptions:
                    # Listed like a real node's; it answers with an empty response.
                    graph.add_service(
                        ServiceEntry(
                            f"{node}/get_type_description",
                            "type_description_interfaces/srv/GetTypeDescription",
                            node,
                            self._empty_response,
                        )
                    )
        else:
            nodes.append("/rosout")
            for node in nodes:
                graph.node(node)
                if log_type and node != "/rosout":
                    graph.add_publisher(node, "/rosout", log_type)
                if not self.node_services:
                    continue
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

    def _talker(self) -> None:
        if self.kit.publisher(TALKER, "/chatter", self.kit.msg_type("std_msgs", "String")):
            self.kit.loops.append(self._chatter_loop)

    def _services(self) -> None:
        kit = self.kit
        kit.service(
            ADD_TWO_INTS,
            "/add_two_ints",
            kit.type("example_interfaces/srv/AddTwoInts", "rospy_tutorials/AddTwoInts", "srv"),
            self._add_two_ints,
        )
        kit.service(
            CONTROLLER,
            "/set_enabled",
            kit.type("std_srvs/srv/SetBool", "std_srvs/SetBool", "srv"),
            self._set_enabled,
        )
        kit.service(
            CONTROLLER,
            "/slow_service",
            kit.type("std_srvs/srv/Trigger", "std_srvs/Trigger", "srv"),
            self._slow,
        )

    def _fast(self) -> None:
        if self.kit.publisher(FAST, "/fast_counter", self.kit.msg_type("std_msgs", "UInt64")):
            self.kit.loops.append(self._fast_loop)

    def _fibonacci(self) -> None:
        if self.ros2:
            action_type = self.kit.type("example_interfaces/action/Fibonacci", "", "action")
            if action_type is not None:
                self.fibonacci2 = FibonacciServer(self.bridge, "/fibonacci", action_type, self.action_step)
            return
        if self.kit.type(
            "actionlib_tutorials/FibonacciActionGoal", "actionlib_tutorials/FibonacciActionGoal", "msg"
        ):
            self.fibonacci1 = ActionlibFibonacciServer(
                self.bridge, "/fibonacci", "actionlib_tutorials", self.action_step
            )
            self.kit.loops.append(self.fibonacci1.run)

    def _parameters(self) -> None:
        params = self.bridge.world.params
        config = self.bridge.config
        if self.ros2:
            for node in self.bridge.graph.node_names():
                if node != ROSAPI_PARAMS:
                    params[f"{node}:use_sim_time"] = False
                    if self.type_descriptions:
                        # Declared by every node since Iron (what the Jazzy and Kilted labs list second).
                        params[f"{node}:start_type_description_service"] = True
            if self.nav2 is None:
                params.update(
                    {
                        "/turtlesim:background_r": 69,
                        "/turtlesim:background_g": 86,
                        "/turtlesim:background_b": 255,
                    }
                )
            params.update(
                {
                    # rosbridge_websocket's parameters in the order 2.1.0 declares them (its launch
                    # defaults, as the Kilted lab lists them), then the newer service timeout.
                    "/rosbridge_websocket:use_compression": False,
                    "/rosbridge_websocket:call_services_in_new_thread": not config.in_order,
                    "/rosbridge_websocket:send_action_goals_in_new_thread": not config.in_order,
                    "/rosbridge_websocket:fragment_timeout": 600,
                    "/rosbridge_websocket:delay_between_messages": 0,
                    "/rosbridge_websocket:max_message_size": config.max_message_size or 0,
                    "/rosbridge_websocket:unregister_timeout": 10.0,
                    "/rosbridge_websocket:bson_only_mode": False,
                    "/rosbridge_websocket:topics_glob": "",
                    "/rosbridge_websocket:services_glob": "",
                    "/rosbridge_websocket:params_glob": "",
                    "/rosbridge_websocket:websocket_ping_interval": 0,
                    "/rosbridge_websocket:websocket_ping_timeout": 30,
                    "/rosbridge_websocket:certfile": "",
                    "/rosbridge_websocket:keyfile": "",
                    "/rosbridge_websocket:port": self.port,
                    "/rosbridge_websocket:address": "127.0.0.1",
                    "/rosbridge_websocket:url_path": "/",
                    "/rosbridge_websocket:retry_startup_delay": 5.0,
                    "/rosbridge_websocket:actual_port": self.port,
                    "/rosapi:topics_glob": "[*]",
                    "/rosapi:services_glob": "[*]",
                    "/rosapi:params_glob": "[*]",
                }
            )
            if self.nav2 is None:
                params.update(
                    {
                        "/robot_controller:slow_service_seconds": self.slow_service_seconds,
                        "/fibonacci_server:step_seconds": self.action_step,
                        "/robot_state_publisher:robot_description": robot_description(
                            arm_urdf() if self.arm is not None else ""
                        ),
                        "/robot_state_publisher:publish_frequency": 20.0,
                        "/odometry:odom_frame": "odom",
                        "/odometry:base_frame": "base_link",
                        "/lidar:frame_id": "base_scan",
                        "/lidar:range_max": RANGE_MAX,
                    }
                )
            if self.rosapi_options.release == "newest":
                # rosbridge 2.2.0+ (2.1.0 has no service timeout).
                params["/rosbridge_websocket:default_call_service_timeout"] = config.default_service_timeout
        else:
            # In the order the real parameter server lists them (roscore's, the world's, then what
            # rosbridge_websocket.launch sets, with its values; get_param_names is not sorted on ROS 1).
            params.update(
                {
                    "/run_id": "5a1e5c8e-0000-4000-8000-000000000000",
                    "/rosversion": "1.16.0\n",
                    "/rosdistro": "noetic\n",
                    "/robot_description": robot_description(arm_urdf() if self.arm is not None else ""),
                    "/robot_controller/slow_service_seconds": self.slow_service_seconds,
                    "/turtlesim/background_r": 69,
                    "/turtlesim/background_g": 86,
                    "/turtlesim/background_b": 255,
                    "/fibonacci_server/step_seconds": self.action_step,
                    "/robot_state_publisher/publish_frequency": 20.0,
                    "/odometry/odom_frame": "odom",
                    "/odometry/base_frame": "base_link",
                    "/lidar/frame_id": "base_scan",
                    "/lidar/range_max": RANGE_MAX,
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
            if self.nav2 is not None:
                # The turtle world's own parameters are not on the Nav2 robot.
                turtle_nodes = (
                    "/robot_controller/",
                    "/turtlesim/",
                    "/fibonacci_server/",
                    "/odometry/",
                    "/lidar/",
                )
                for key in [k for k in params if k.startswith(turtle_nodes)]:
                    del params[key]
                params["/robot_description"] = params.pop("/robot_description")
                params.pop("/robot_state_publisher/publish_frequency", None)

    def background(self) -> tuple[int, int, int]:
        """turtlesim's background colour from its parameters."""
        return self.turtlesim.background()

    # --- running --------------------------------------------------------------------------------------------

    def start(self) -> None:
        """Start every periodic publisher."""
        for loop in self.kit.loops:
            self._tasks.append(asyncio.create_task(self._guard(loop)))

    async def _guard(self, loop: Loop) -> None:
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
        if self.nav2 is not None:
            await self.nav2.close()

    # --- other nodes ----------------------------------------------------------------------------------------

    async def _chatter_loop(self) -> None:
        world = self.bridge.world
        while True:
            await asyncio.sleep(CHATTER_PERIOD)
            world.chatter_count += 1
            self.kit.publish("/chatter", {"data": f"Hello World: {world.chatter_count}"})

    async def _fast_loop(self) -> None:
        """1 kHz by an absolute schedule: a late wake-up publishes the missed messages at once."""
        world = self.bridge.world
        loop = asyncio.get_running_loop()
        start = loop.time()
        sent = 0
        while True:
            due = int((loop.time() - start) / FAST_PERIOD) + 1
            if due - sent > 100:
                sent = due - 100  # far behind (a stalled loop): catch up at most 100 ms worth
            while sent < due:
                sent += 1
                world.fast_count += 1
                self.kit.publish("/fast_counter", {"data": world.fast_count})
            await asyncio.sleep(max(0.0, start + sent * FAST_PERIOD - loop.time()))

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
