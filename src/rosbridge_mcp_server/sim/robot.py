"""``SimulatedRobot``: the simulated world behind a rosbridge v2 WebSocket server, for tests and demos."""

from __future__ import annotations

import asyncio
import logging
import ssl as _ssl
from collections.abc import Callable, Sequence
from types import TracebackType
from typing import Literal, Self

from websockets.asyncio.server import Server, ServerConnection, serve

from rosbridge_mcp_server.sim.actions import HostedActionServer
from rosbridge_mcp_server.sim.bridge import Bridge, BridgeConfig
from rosbridge_mcp_server.sim.graph import Graph
from rosbridge_mcp_server.sim.interfaces import InterfaceRegistry
from rosbridge_mcp_server.sim.memory import MemoryClientEnd, MemoryServer
from rosbridge_mcp_server.sim.nodes import CameraSettings, WorldNodes
from rosbridge_mcp_server.sim.nodes.arm import ArmWorld
from rosbridge_mcp_server.sim.nodes.nav2 import Nav2World
from rosbridge_mcp_server.sim.nodes.room import ROOM_MAP_CELLS
from rosbridge_mcp_server.sim.player import Player
from rosbridge_mcp_server.sim.rosapi import ROSAPI_RELEASES, Rosapi, RosapiOptions
from rosbridge_mcp_server.sim.world import World

__all__ = ["DEFAULT_MAX_MESSAGE_SIZE", "ROS2_DISTROS", "WORLDS", "SimulatedRobot"]

log = logging.getLogger("rosbridge_mcp_server.sim")

#: ROS 2 rosbridge's ``max_message_size`` as its launch file sets it (also the initial fragment size).
DEFAULT_MAX_MESSAGE_SIZE = 10_000_000
#: Tornado's default limit for one incoming frame, which rosbridge does not change.
MAX_INCOMING_FRAME = 10 * 1024 * 1024
#: ROS 2 distros the simulated robot can say it runs (``get_ros_version``; Humble has no type descriptions).
ROS2_DISTROS = ("humble", "jazzy", "kilted", "rolling")
#: The worlds the simulated robot can run: the turtle demo (default), a Nav2-scale mobile robot, and the
#: turtle with an arm (ROS 2).
WORLDS = ("turtle", "nav2", "arm")


class SimulatedRobot:
    """A rosbridge v2 server with a small simulated world behind it.

    ``dialect="ros2"`` behaves like a current Jazzy rosbridge (or Humble 2.0.x with ``in_order=True``);
    ``dialect="ros1"`` like rosbridge_suite 0.11.17 on Noetic. Use it as an async context manager; it serves
    on ``host:port`` (port 0 picks a free port, kept across :meth:`stop`/:meth:`start`).

    ``distro`` (ROS 2) is what ``get_ros_version`` says and decides whether nodes offer type descriptions
    (not on Humble); by default Humble when ``in_order``, else Jazzy. ``rosapi="2.1.0"`` behaves like the
    rosapi and ``call_service`` of rosbridge_suite 2.1.0 (underscored TypeDef field names, no
    ``action_type``/``interfaces``, one call at a time, the calls that kill it, no service timeout); with
    ``in_order=True, distro="kilted"`` that is the real 2.1.0 bridge with its default settings.
    ``rosapi_latency`` (seconds, or several taken in turn) makes every rosapi call take that long, one call
    at a time, as a real rosapi serves them. ``node_services=False`` leaves out the parameter / type
    description (ROS 2) and logger (ROS 1) services every real node has. ``map_cells`` is the side of
    ``/map`` in cells (the same room, finer; e.g. 2000 for benchmarks). ``cbor=False`` is a bridge that
    ignores ``compression: "cbor"`` and sends JSON (by default it answers with binary CBOR frames, as
    rosbridge_suite 0.11.17 / 2.x do).

    ``play`` plays an MCAP recording (``sim/player.py``), once or with ``play_loop`` over and over.

    ``world="nav2"`` runs a Nav2-scale mobile robot instead of the turtle (see :mod:`.nodes.nav2`);
    ``world="arm"`` (ROS 2) the turtle with a 6-joint arm and a gripper driven by ros2_control, and its
    faults ``arm-controller-inactive``, ``joint-states-stale`` (see :mod:`.nodes.arm`);
    ``robots=N`` runs N of them under ``/robot1``, ``/robot2``, ... ``faults`` (Nav2 only) breaks it on
    purpose: ``scan-stopped``, ``tf-stale``, ``driver-error``, ``controller-inactive`` (ROS 2),
    ``log-errors``, ``node-gone`` (see :mod:`.nodes.nav2.health`).

    ``server="rs"`` behaves like
    rosbridge-server-rs 0.1.6 (ROS 2): an error ``status`` answers every failed op, only the connection that
    started a goal may cancel it ("unknown active goal" elsewhere), a goal that did not succeed ends with
    ``result: false``, a name missing from the graph without a type is refused with "type is required when
    interface is absent from ROS graph", and neither the bridge nor rosapi has parameter services.
    """

    def __init__(
        self,
        dialect: Literal["ros2", "ros1"] = "ros2",
        *,
        in_order: bool = False,
        distro: str | None = None,
        rosapi: Literal["newest", "2.1.0"] = "newest",
        rosapi_latency: float | Sequence[float] = 0.0,
        node_services: bool = True,
        server: Literal["rosbridge_suite", "rs"] = "rosbridge_suite",
        host: str = "127.0.0.1",
        port: int = 0,
        fast_topic: bool = False,
        action_step: float = 0.2,
        slow_service_seconds: float = 3.0,
        camera_width: int = 160,
        camera_height: int = 120,
        map_cells: int = ROOM_MAP_CELLS,
        max_message_size: int | None = None,
        ssl: _ssl.SSLContext | None = None,
        world: Literal["turtle", "nav2", "arm"] = "turtle",
        robots: int = 1,
        cbor: bool = True,
        faults: Sequence[str] = (),
        play: str | None = None,
        play_loop: bool = False,
    ) -> None:
        if dialect not in ("ros1", "ros2"):
            raise ValueError(f"dialect must be 'ros1' or 'ros2', not {dialect!r}")
        if in_order and dialect != "ros2":
            raise ValueError("in_order models Humble's rosbridge, so it needs dialect='ros2'")
        if map_cells < 8:
            raise ValueError("map_cells must be at least 8")
        if world not in WORLDS:
            raise ValueError(f"world must be one of {', '.join(WORLDS)}, not {world!r}")
        if robots < 1 or (robots > 1 and world != "nav2"):
            raise ValueError(f"robots must be >= 1, and more than one needs world='nav2' (not {robots!r})")
        if action_step <= 0 or slow_service_seconds < 0:
            raise ValueError("action_step must be > 0 and slow_service_seconds >= 0")
        if distro is not None and (dialect != "ros2" or distro not in ROS2_DISTROS):
            raise ValueError(f"distro must be one of {', '.join(ROS2_DISTROS)} (ROS 2 only), not {distro!r}")
        if rosapi not in ROSAPI_RELEASES or (rosapi != "newest" and dialect != "ros2"):
            raise ValueError(f"rosapi must be 'newest' or (ROS 2 only) '2.1.0', not {rosapi!r}")
        if server not in ("rosbridge_suite", "rs") or (
            server == "rs" and (dialect != "ros2" or in_order or rosapi != "newest")
        ):
            raise ValueError(
                f"server must be 'rosbridge_suite' or 'rs' (ROS 2, not in_order, newest rosapi): {server!r}"
            )
        latencies = (rosapi_latency,) if isinstance(rosapi_latency, int | float) else tuple(rosapi_latency)
        if not all(latency >= 0 for latency in latencies):
            raise ValueError("rosapi_latency must be >= 0 seconds")
        if dialect == "ros2":
            config = BridgeConfig(
                dialect="ros2",
                in_order=in_order,
                max_message_size=max_message_size or DEFAULT_MAX_MESSAGE_SIZE,
                # Humble 2.0.x and 2.1.0: no service timeout (forever); Jazzy 2.2.0+: 5 s by default.
                default_service_timeout=0.0 if in_order or rosapi != "newest" else 5.0,
                distro=distro or ("humble" if in_order else "jazzy"),
                # rosbridge_suite 2.1.0's call_service knows no timeout field (it waits as long as it takes).
                timeout_field=rosapi == "newest",
                cbor=cbor,
                server=server,
            )
        else:
            config = BridgeConfig(
                dialect="ros1",
                in_order=False,
                max_message_size=max_message_size,
                default_service_timeout=0.0,
                distro="noetic",
                cbor=cbor,
            )
        self.dialect = dialect
        self.in_order = in_order
        self.rosapi_release = rosapi
        self.host = host
        self.port = port
        # rosbridge serves wss:// when given certfile/keyfile; a server-side context does the same here.
        self.ssl = ssl
        self.world = World(dialect)
        self.graph = Graph()
        self.registry = InterfaceRegistry(dialect, rosapi=rosapi, distro=config.distro)
        self.bridge = Bridge(config, self.registry, self.world, self.graph)
        self._nodes = WorldNodes(
            self.bridge,
            fast_topic=fast_topic,
            action_step=action_step,
            slow_service_seconds=slow_service_seconds,
            camera=CameraSettings(camera_width, camera_height),
            port=port,
            rosapi=RosapiOptions(release=rosapi, latency=latencies),
            node_services=node_services,
            map_cells=map_cells,
            world=world,
            robots=robots,
            bridge_parameters=server != "rs",
            faults=tuple(faults),
        )
        self._nodes.build()
        #: The recording played (``play``: an MCAP file; ``play_loop``: over and over), else ``None``.
        self.player: Player | None = None
        if play is not None:
            self.player = Player(self._nodes.kit, play, loop=play_loop)
            self.player.build()
        self.world_name = world
        self._server: Server | None = None
        self._memory = MemoryServer(self.bridge.serve_connection, MAX_INCOMING_FRAME)

    @property
    def url(self) -> str:
        """``ws://host:port`` of the running server (``wss://`` when it serves TLS)."""
        return f"{'wss' if self.ssl is not None else 'ws'}://{self.host}:{self.port}"

    @property
    def nav2(self) -> Nav2World:
        """The Nav2 world (robots' poses, lifecycle states, the :class:`Surroundings` hook); only with
        ``world="nav2"``."""
        if self._nodes.nav2 is None:
            raise AttributeError("this robot runs the turtle world (world='nav2' has a Nav2 world)")
        return self._nodes.nav2

    @property
    def arm(self) -> ArmWorld:
        """The arm (its joint positions, controllers, faults, the goals that reached it); only with
        ``world="arm"``."""
        if self._nodes.arm is None:
            raise AttributeError("this robot has no arm (world='arm' has one)")
        return self._nodes.arm

    @property
    def rosapi_node(self) -> Rosapi:
        """The rosapi node (e.g. ``rosapi_node.param_node_wait``, ``rosapi_node.dead``)."""
        return self._nodes.rosapi

    @property
    def connection_count(self) -> int:
        """Clients connected right now."""
        return self.bridge.connection_count

    @property
    def running(self) -> bool:
        """Whether the server is accepting connections (on its port, or in memory only)."""
        return self._memory.accepts

    @property
    def listening(self) -> bool:
        """Whether the server listens on a port (:meth:`start` without ``listen=False``)."""
        return self._server is not None

    async def dial_in_memory(self, timeout: float) -> MemoryClientEnd:
        """A connection to this robot's bridge in the same process, no socket: pass the method itself as the
        client's transport (``RosbridgeClient(robot.url, transport=robot.dial_in_memory)``).
        ``ConnectionRefusedError`` while the robot is stopped."""
        return await self._memory.dial(timeout)

    async def start(self, *, listen: bool = True) -> None:
        """Start serving (again, on the same port after :meth:`stop`); ``listen=False`` opens no port: the
        robot is then reached through :meth:`dial_in_memory` alone (:attr:`url` still names port 0)."""
        if self._memory.accepts:
            return
        if not listen:
            self._memory.accepts = True
            self._nodes.start()
            log.info(
                "simulated robot (%s, %s) serving rosbridge v2 in memory",
                self.dialect,
                self.bridge.config.distro,
            )
            return
        self._server = await serve(
            self._handle,
            self.host,
            self.port,
            max_size=MAX_INCOMING_FRAME,
            # rosbridge never pings unless websocket_ping_interval is set, and does not compress.
            ping_interval=None,
            compression=None,
            ssl=self.ssl,
        )
        self.port = self._server.sockets[0].getsockname()[1]
        params = self.world.params
        for key in (
            "/rosbridge_websocket:port",
            "/rosbridge_websocket:actual_port",
            "/rosbridge_websocket/port",
            "/rosbridge_websocket/actual_port",
        ):
            if key in params:
                params[key] = self.port
        self._memory.accepts = True
        self._nodes.start()
        log.info(
            "simulated robot (%s, %s%s%s) serving rosbridge v2 on %s",
            self.dialect,
            self.bridge.config.distro,
            ", in-order" if self.in_order else "",
            f", rosapi {self.rosapi_release}" if self.rosapi_release != "newest" else "",
            self.url,
        )

    async def stop(self) -> None:
        """Stop serving: every client is disconnected and the world's publishers pause.

        Like a rosbridge process that exits, client-advertised services and actions vanish and running goals
        end.
        """
        if not self._memory.accepts:
            return
        server, self._server = self._server, None
        if server is not None:
            server.close(close_connections=True)
        await self._memory.close_all()
        self.bridge.cancel_all()
        if server is not None:
            await server.wait_closed()
        await self._nodes.stop()
        for name in [n for n, e in self.graph.services.items() if e.owner]:
            self.graph.remove_service(name)
        for action_server in list(self.graph.actions.values()):
            if isinstance(action_server, HostedActionServer):
                action_server.remove()
        self.world.notify()
        log.info("simulated robot on %s stopped", self.url)

    async def drop_connections(self) -> None:
        """Close every client socket; the server keeps running, so clients can reconnect."""
        await asyncio.gather(
            *(conn.ws.close(1001, "simulated connection drop") for conn in self.bridge.connections.values())
        )

    async def wait_for(
        self,
        predicate: Callable[[World], object],
        timeout: float = 5.0,
    ) -> None:
        """Wait until ``predicate(world)`` holds (checked on each change); TimeoutError after ``timeout``."""
        await self.world.wait_for(predicate, timeout)

    async def _handle(self, ws: ServerConnection) -> None:
        await self.bridge.serve_connection(ws)

    async def __aenter__(self) -> Self:
        await self.start()
        return self

    async def __aexit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        await self.stop()
