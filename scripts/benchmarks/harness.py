"""What every item shares, by concern, and the run's context (:class:`Context`).

The harness is split by concern; this module gathers their names, so an item imports what it needs from one
place:

* ``constants.py``: the repository's paths, the console script, the simulated robot's services and topics;
* ``figures.py``: the plan (how many of everything), medians and p90, rows, ratios and verdicts;
* ``machine.py``: the speed probe, what this machine is, a process's CPU seconds and peak RSS;
* ``bridge.py``: the simulated robot's process, a raw rosbridge connection, the bridge measured;
* ``sessions.py``: MCP sessions (the SDK's client on stdio, JSON-RPC lines on the pipes) with our server and
  the bare reference server;
* ``timing.py``: subjects timed in interleaved rotated blocks, calls locked to a publisher's ticks.

Only the package's public ways in are used: the console script ``rosbridge-mcp-server`` (as an MCP host starts
it), ``python -m rosbridge_mcp_server.sim`` (the simulated robot), MCP over stdio (the SDK's client, or
JSON-RPC lines written on the server's pipes) and the rosbridge protocol over a raw WebSocket. The few figures
that measure an internal part on its own import it from :mod:`benchmarks.internals`, which says which.
"""

from __future__ import annotations

import dataclasses
from typing import IO, TYPE_CHECKING

import psutil

from benchmarks.bridge import (
    Bridge,
    RawBridge,
    free_port,
    simulated_robot,
    simulated_robot_command,
    simulated_robot_process,
    tail,
    wait_for_port,
)
from benchmarks.constants import (
    ADD_TWO_INTS,
    BARE,
    BARE_SERVER,
    CAMERA_SIZE,
    CAMERA_TOPIC,
    CHATTER,
    CMD_VEL,
    CONSOLE_SCRIPT,
    FAST_TOPIC,
    FULL_HD,
    MIB,
    OURS_SDK_STDIO,
    REPO,
    SERVERS,
    SLOW_SERVICE,
    SLOW_SERVICE_SECONDS,
    TOOL_PAUSE,
    log,
)
from benchmarks.figures import (
    FULL,
    QUICK,
    Plan,
    Row,
    Stats,
    mib,
    ms,
    ratio_row,
    timing_row,
    verdict,
)
from benchmarks.machine import (
    cpu_seconds,
    cpu_speed_probe,
    describe_machine,
    peak_reset,
    peak_resettable,
    peak_rss,
    wall_time,
)
from benchmarks.sessions import (
    RawPipeClient,
    Served,
    bare_server_command,
    ctx_graph_has,
    our_server_command,
    our_server_on_sdk_stdio_command,
    publish_service_arguments,
    raw_pipe_client,
    serve_mcp,
)
from benchmarks.timing import (
    Metronome,
    Subject,
    interleave,
    phase_locked,
    raw_first_message,
)

if TYPE_CHECKING:
    from benchmarks.internals import RosbridgeClient

__all__ = [
    "ADD_TWO_INTS",
    "BARE",
    "BARE_SERVER",
    "CAMERA_SIZE",
    "CAMERA_TOPIC",
    "CHATTER",
    "CMD_VEL",
    "CONSOLE_SCRIPT",
    "FAST_TOPIC",
    "FULL",
    "FULL_HD",
    "MIB",
    "OURS_SDK_STDIO",
    "QUICK",
    "REPO",
    "SERVERS",
    "SLOW_SERVICE",
    "SLOW_SERVICE_SECONDS",
    "TOOL_PAUSE",
    "Bridge",
    "Context",
    "Metronome",
    "Plan",
    "RawBridge",
    "RawPipeClient",
    "Row",
    "Served",
    "Stats",
    "Subject",
    "bare_server_command",
    "cpu_seconds",
    "cpu_speed_probe",
    "ctx_graph_has",
    "describe_machine",
    "free_port",
    "interleave",
    "log",
    "mib",
    "ms",
    "our_server_command",
    "our_server_on_sdk_stdio_command",
    "peak_reset",
    "peak_resettable",
    "peak_rss",
    "phase_locked",
    "publish_service_arguments",
    "ratio_row",
    "raw_first_message",
    "raw_pipe_client",
    "serve_mcp",
    "simulated_robot",
    "simulated_robot_command",
    "simulated_robot_process",
    "tail",
    "timing_row",
    "verdict",
    "wait_for_port",
    "wall_time",
]


@dataclasses.dataclass
class Context:
    """Everything the items share: the plan, the bridge, the open connections and the raw samples."""

    plan: Plan
    bridge: Bridge
    raw: RawBridge
    client: RosbridgeClient
    ours: Served
    reference: Served  # the bare server with the reference tools, on our stdio transport
    reference_sdk: Served  # the same on the SDK's stdio transport
    ours_sdk: Served  # our server on the SDK's stdio transport
    errlog: IO[str]
    bridge_process: psutil.Process | None = None  # the simulated robot, when we started it
    samples: dict[str, list[float]] = dataclasses.field(default_factory=dict)
    cpu_per_call: dict[str, dict[str, float | None]] = dataclasses.field(default_factory=dict)
    startup_rss: dict[str, Stats] = dataclasses.field(default_factory=dict)
    ros_mcp: str | None = None  # --ros-mcp: the Python of a venv with ros-mcp, the peer of item 15
    node: str | None = None  # --node: the node item 15's get_node_info asks about on a --url bridge
