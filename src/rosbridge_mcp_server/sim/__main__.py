"""``rosbridge-sim-robot`` / ``python -m rosbridge_mcp_server.sim``: serve the simulated robot standalone."""

from __future__ import annotations

import argparse
import asyncio
import logging
import signal
import sys
from typing import NoReturn

from rosbridge_mcp_server.sim.nodes.arm import ARM_FAULTS
from rosbridge_mcp_server.sim.nodes.nav2.health import FAULTS, check_faults
from rosbridge_mcp_server.sim.player import PlayError
from rosbridge_mcp_server.sim.robot import ROS2_DISTROS, WORLDS, SimulatedRobot

__all__ = ["build_parser", "main", "run"]

PROG = "rosbridge-sim-robot"


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> NoReturn:
        """A bad flag is one line on stderr and exit code 2 (no usage dump)."""
        self.exit(2, f"{self.prog}: error: {message} (see --help)\n")


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be > 0: {text!r}")
    return value


def _non_negative_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"must be >= 0: {text!r}")
    return value


def _latencies(text: str) -> tuple[float, ...]:
    return tuple(_non_negative_float(part) for part in text.split(","))


def _robots(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
    if not 1 <= value <= 100:
        raise argparse.ArgumentTypeError(f"must be 1-100: {value}")
    return value


def _port(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a port number: {text!r}") from None
    if not 0 <= value <= 65535:
        raise argparse.ArgumentTypeError(f"port out of range 0-65535: {value}")
    return value


def build_parser() -> argparse.ArgumentParser:
    """The command line of the simulated robot."""
    parser = _Parser(
        prog=PROG,
        description="A simulated robot behind a rosbridge v2 WebSocket server (no ROS needed).",
    )
    parser.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1)")
    parser.add_argument("--port", type=_port, default=9090, help="port to listen on (default 9090; 0 = any)")
    parser.add_argument(
        "--dialect",
        choices=["ros2", "ros1"],
        default="ros2",
        help="ros2 (Jazzy-like, default) or ros1 (Noetic)",
    )
    parser.add_argument(
        "--world",
        choices=WORLDS,
        default="turtle",
        help="turtle (the small demo, default), nav2 (a Nav2-scale mobile robot: ~36 nodes, 14 actions) "
        "or arm (the turtle with a 6-joint arm and a gripper under ros2_control; on ROS 1 ros_control)",
    )
    parser.add_argument(
        "--robots",
        type=_robots,
        default=1,
        metavar="N",
        help="nav2 only: N robots on one graph, under /robot1 ... /robotN (default 1, no namespace)",
    )
    parser.add_argument(
        "--fault",
        default="",
        metavar="NAME[,NAME...]",
        help=f"nav2 or arm: break the robot on purpose (nav2: {', '.join(FAULTS)}; "
        f"arm: {', '.join(ARM_FAULTS)})",
    )
    parser.add_argument(
        "--in-order",
        action="store_true",
        help="ros2 only: Humble's and 2.1.0's defaults, each connection's operations strictly in order",
    )
    parser.add_argument(
        "--distro",
        choices=ROS2_DISTROS,
        help="ros2 only: the distro get_ros_version names (default humble with --in-order, else jazzy)",
    )
    parser.add_argument(
        "--rosapi",
        choices=["newest", "2.1.0"],
        default="newest",
        help="ros2 only: which rosapi to behave like (default newest; 2.1.0 as on the Jazzy/Kilted labs)",
    )
    parser.add_argument(
        "--server",
        choices=["rosbridge_suite", "rs"],
        default="rosbridge_suite",
        help="ros2 only: which bridge to behave like (rs: rosbridge-server-rs 0.1.6)",
    )
    parser.add_argument(
        "--rosapi-latency",
        type=_latencies,
        default=(0.0,),
        metavar="SECONDS[,SECONDS...]",
        help="each rosapi call takes this long, one at a time; several values are taken in turn (default 0)",
    )
    parser.add_argument(
        "--no-node-services",
        action="store_true",
        help="leave out every node's parameter / type description (ros2) or logger (ros1) services",
    )
    parser.add_argument("--play", metavar="FILE.mcap", help="play an MCAP recording's topics in real time")
    parser.add_argument("--loop", action="store_true", help="with --play: play the recording over and over")
    parser.add_argument("--fast-topic", action="store_true", help="publish /fast_counter at 1 kHz")
    parser.add_argument(
        "--action-step", type=_positive_float, default=0.2, help="seconds per /fibonacci step (default 0.2)"
    )
    parser.add_argument(
        "--slow-service-seconds",
        type=_non_negative_float,
        default=3.0,
        help="how long /slow_service takes (default 3)",
    )
    parser.add_argument(
        "--camera-size", default="160x120", help="camera frame WIDTHxHEIGHT (default 160x120)"
    )
    parser.add_argument(
        "--map-cells", type=int, default=242, help="/map side in cells (default 242: 0.05 m cells)"
    )
    parser.add_argument(
        "--log-level", default="INFO", choices=["DEBUG", "INFO", "WARNING", "ERROR"], help="stderr log level"
    )
    return parser


async def _serve(robot: SimulatedRobot) -> None:
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, stop.set)
    await robot.start()
    try:
        await stop.wait()
    finally:
        await robot.stop()


def run(argv: list[str] | None = None) -> int:
    """Parse ``argv``, serve until Ctrl-C / SIGTERM; returns the exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.in_order and args.dialect != "ros2":
        parser.error("--in-order models Humble's rosbridge and needs --dialect ros2")
    if args.dialect != "ros2" and (
        args.distro is not None or args.rosapi != "newest" or args.server != "rosbridge_suite"
    ):
        parser.error("--distro, --rosapi and --server are ROS 2 settings and need --dialect ros2")
    if args.server == "rs" and (args.in_order or args.rosapi != "newest"):
        parser.error("--server rs runs calls side by side with its newer rosapi: no --in-order, no --rosapi")
    if args.robots > 1 and args.world != "nav2":
        parser.error("--robots needs --world nav2")
    faults = tuple(f.strip() for f in args.fault.split(",") if f.strip())
    if faults and args.world not in ("nav2", "arm"):
        parser.error("--fault needs --world nav2 or --world arm")
    unknown = [f for f in faults if f not in ARM_FAULTS]
    if args.world == "arm" and unknown:
        parser.error(f"--fault: unknown arm fault {', '.join(unknown)}; choose from {', '.join(ARM_FAULTS)}")
    try:
        if args.world == "nav2":
            faults = check_faults(faults, ros2=args.dialect == "ros2")
    except ValueError as exc:
        parser.error(f"--fault: {exc}")
    try:
        width_text, height_text = args.camera_size.lower().split("x")
        width, height = int(width_text), int(height_text)
        if width <= 0 or height <= 0:
            raise ValueError
    except ValueError:
        parser.error(f"--camera-size must look like 160x120, not {args.camera_size!r}")
    if args.loop and args.play is None:
        parser.error("--loop needs --play FILE.mcap")
    if args.map_cells < 8:
        parser.error(f"--map-cells must be at least 8, not {args.map_cells}")
    logging.basicConfig(
        level=args.log_level, stream=sys.stderr, format="%(asctime)s %(levelname)s %(name)s: %(message)s"
    )
    try:
        robot = _robot(args, width, height, faults)
    except PlayError as exc:
        print(f"{PROG}: --play: {exc}", file=sys.stderr)
        return 2
    try:
        asyncio.run(_serve(robot))
    except OSError as exc:
        print(f"{PROG}: cannot serve on {args.host}:{args.port}: {exc.strerror or exc}", file=sys.stderr)
        return 1
    return 0


def _robot(args: argparse.Namespace, width: int, height: int, faults: tuple[str, ...]) -> SimulatedRobot:
    return SimulatedRobot(
        dialect=args.dialect,
        in_order=args.in_order,
        distro=args.distro,
        rosapi=args.rosapi,
        server=args.server,
        rosapi_latency=args.rosapi_latency,
        node_services=not args.no_node_services,
        host=args.host,
        port=args.port,
        fast_topic=args.fast_topic,
        action_step=args.action_step,
        slow_service_seconds=args.slow_service_seconds,
        camera_width=width,
        camera_height=height,
        map_cells=args.map_cells,
        world=args.world,
        robots=args.robots,
        faults=faults,
        play=args.play,
        play_loop=args.loop,
    )


def main() -> None:
    """Console-script entry point."""
    raise SystemExit(run())


if __name__ == "__main__":
    main()
