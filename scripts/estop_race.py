"""E-STOP races against any rosbridge: a real lab, or the simulated robot in this process.

    uv run python scripts/estop_race.py --races 20                                  # simulated, ROS 2
    uv run python scripts/estop_race.py --dialect ros1 --delay 0.15 --races 20     # simulated, slow link
    uv run python scripts/estop_race.py --url ws://127.0.0.1:9090 --dialect ros1 --races 10 --observe 1.5

Each race is what ``tests/console/test_console_estop_race.py`` runs (the harness is shared): through the
served console and an MCP session, a 10 Hz ``publish_topic`` stream on /turtle1/cmd_vel and a /fibonacci
goal start; E-STOP is pressed over HTTP at moments spread over their first 1.1 s after the console shows one
of them allowed; then a raw rosbridge socket on the robot (no proxy) counts the motion commands and the goal
feedback that came after E-STOP answered (after a marker published once the answer came), and on the
simulated robot the robot's own record counts them too. ``--delay`` puts a proxy that holds every frame that
long each way between the server and the bridge. A real robot's turtle is driven at 1 m/s for up to ~1 s per
race: use it on a lab, not a robot in a room. Figures go to stdout; the exit status is 1 when anything came
after E-STOP.
"""

from __future__ import annotations

import argparse
import asyncio
import collections
import logging
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "console"))

from race_harness import RaceResult, race_console, run_race

from rosbridge_mcp_server.sim import SimulatedRobot


async def races(args: argparse.Namespace) -> list[RaceResult]:
    sim = None
    url = args.url
    if url is None:
        sim = SimulatedRobot(dialect=args.dialect, action_step=0.05)
        await sim.start()
        url = sim.url
    results: list[RaceResult] = []
    try:
        async with race_console(
            url, args.dialect, args.delay, world=sim.world if sim else None, observe=args.observe
        ) as race:
            for index in range(args.races):
                result = await run_race(race, press_after=(index % 10) * 0.12)
                results.append(result)
                print(
                    f"race {index + 1}: press +{(index % 10) * 0.12:.2f} s, after E-STOP answered "
                    f"{result.watcher_commands_after} commands / {result.watcher_feedback_after} goal "
                    f"feedback seen on the raw socket; E-STOP stopped {result.estop['streams_stopped']} and "
                    f"goals {result.estop['goals_cancelled']}",
                    file=sys.stderr,
                )
            seen = collections.Counter(topic for topic, _ in race.watcher.frames)
            print(f"all the raw socket saw, by topic: {dict(seen)}", file=sys.stderr)
    finally:
        if sim is not None:
            await sim.stop()
    return results


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--url", help="a rosbridge to race against (default: a simulated robot here)")
    parser.add_argument("--dialect", choices=["ros1", "ros2"], default="ros2")
    parser.add_argument("--races", type=int, default=20)
    parser.add_argument("--delay", type=float, default=0.0, help="seconds each frame is held each way")
    parser.add_argument(
        "--observe", type=float, default=0.3, help="seconds to watch for late traffic (a real goal: 1.5)"
    )
    args = parser.parse_args()
    logging.basicConfig(level=logging.ERROR, stream=sys.stderr)
    results = asyncio.run(races(args))
    commands = sum(r.watcher_commands_after for r in results)
    feedback = sum(r.watcher_feedback_after for r in results)
    robot_commands = sum(r.commands_after for r in results)
    robot_progress = sum(r.goal_progress_after for r in results)
    named = sum(1 for r in results if r.estop["streams_stopped"])
    cancelled = sum(1 for r in results if r.estop["goals_cancelled"])
    where = args.url or f"the simulated robot ({args.dialect})"
    print(
        f"{where}, link delay {args.delay:g} s: {len(results)} races; after E-STOP answered: {commands} "
        f"motion commands and {feedback} goal feedback on the raw socket"
        + ("" if args.url else f", {robot_commands} commands and {robot_progress} goal steps on the robot")
        + f"; E-STOP named the stream in {named} and cancelled a goal in {cancelled}"
    )
    return 1 if commands or feedback or robot_commands or robot_progress else 0


if __name__ == "__main__":
    sys.exit(main())
