"""The demo's settings (``--demo``, ``--demo-dialect``, ``--demo-world``, ``--demo-robots``,
``--demo-fault``): the command line's own, not the robot's. With them the CLI starts a simulated robot
and points the robot's :class:`~rosbridge_mcp_server.config.Config` at it."""

from __future__ import annotations

import contextlib
import logging
from collections.abc import AsyncIterator, Sequence
from dataclasses import dataclass, replace
from typing import Literal

from rosbridge_mcp_server.config import Config, ConfigError

__all__ = ["DemoDialect", "DemoSettings", "DemoWorld", "demo_robot", "demo_settings"]

DemoDialect = Literal["ros1", "ros2"]
DemoWorld = Literal["turtle", "nav2", "arm"]
_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class DemoSettings:
    """The simulated robot ``--demo`` starts."""

    dialect: DemoDialect = "ros2"
    #: The turtle (default), a Nav2-scale mobile robot (``robots`` of them), or the turtle with an arm.
    world: DemoWorld = "turtle"
    robots: int = 1
    #: Faults the Nav2 robot or the arm is broken with (``--demo-fault``), checked by the simulated robot.
    faults: tuple[str, ...] = ()


def demo_settings(
    demo: bool,
    *,
    dialect: str = "ros2",
    world: str = "turtle",
    robots: int = 1,
    faults: str | None = None,
    fleet: Sequence[object] = (),
) -> DemoSettings | None:
    """The demo's settings, checked; ``None`` without ``--demo``. :class:`ConfigError` names a bad one."""
    if dialect not in ("ros1", "ros2"):
        raise ConfigError(f"--demo-dialect must be ros1 or ros2, not {dialect!r}")
    if world not in ("turtle", "nav2", "arm"):
        raise ConfigError(f"--demo-world must be turtle, nav2 or arm, not {world!r}")
    if not 1 <= robots <= 100 or (robots > 1 and world != "nav2"):
        raise ConfigError(
            f"--demo-robots must be 1-100 and more than 1 needs --demo-world nav2, not {robots}"
        )
    names = tuple(f.strip() for f in (faults or "").split(",") if f.strip())
    if names and world not in ("nav2", "arm"):
        raise ConfigError("--demo-fault needs --demo-world nav2 or arm")
    if not demo:
        return None
    if fleet:
        raise ConfigError(
            "--demo runs one simulated robot; it cannot be combined with --robot / --robots. To try a fleet "
            "on simulated robots, start two (`rosbridge-sim-robot --port 9091` and "
            "`rosbridge-sim-robot --port 9092`) and give --robot a=ws://127.0.0.1:9091 "
            "--robot b=ws://127.0.0.1:9092; or --demo "
            "--demo-world nav2 --demo-robots 2 for two namespaced robots on one bridge"
        )
    settings = DemoSettings(
        dialect="ros1" if dialect == "ros1" else "ros2",
        world="nav2" if world == "nav2" else "arm" if world == "arm" else "turtle",
        robots=robots,
        faults=names,
    )
    if settings.faults:
        _check_faults(settings)
    return settings


def _check_faults(settings: DemoSettings) -> None:
    # Imported here: the simulated robot is only needed with --demo.
    from rosbridge_mcp_server.sim.nodes.arm import ARM_FAULTS  # noqa: PLC0415
    from rosbridge_mcp_server.sim.nodes.nav2.health import check_faults  # noqa: PLC0415

    if settings.world == "arm":
        unknown = [f for f in settings.faults if f not in ARM_FAULTS]
        if unknown:
            raise ConfigError(
                f"--demo-fault: unknown arm fault {', '.join(unknown)}; choose from {', '.join(ARM_FAULTS)}"
            )
        return
    try:
        check_faults(settings.faults, ros2=settings.dialect == "ros2")
    except ValueError as exc:
        raise ConfigError(f"--demo-fault: {exc}") from None


@contextlib.asynccontextmanager
async def demo_robot(config: Config, demo: DemoSettings | None) -> AsyncIterator[Config]:
    """With *demo*: a simulated robot on a free local port, and ``config`` pointed at it."""
    if demo is None:
        yield config
        return
    # Imported here: the simulated robot is only needed with --demo.
    from rosbridge_mcp_server.sim import SimulatedRobot  # noqa: PLC0415

    # The simulated robot logs like a rosbridge server, errors for expected misses included (e.g. ROS 1 has no
    # /rosapi/get_ros_version); that log belongs to the robot, so it is shown only when debugging.
    if config.log_level != "DEBUG":
        logging.getLogger("rosbridge_mcp_server.sim").setLevel(logging.CRITICAL)
    async with SimulatedRobot(
        dialect=demo.dialect, port=0, world=demo.world, robots=demo.robots, faults=demo.faults
    ) as robot:
        _log.info("demo mode: simulated ROS %s %s robot at %s", demo.dialect[-1], demo.world, robot.url)
        yield replace(config, url=robot.url)
