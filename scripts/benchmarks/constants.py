"""What every item shares by name: the repository's paths, the console script, the simulated robot's
services, topics and camera, the log."""

from __future__ import annotations

import logging
from pathlib import Path

log = logging.getLogger("bench")

REPO = Path(__file__).resolve().parents[2]
SERVERS = Path(__file__).resolve().parent / "servers"
BARE_SERVER = SERVERS / "bare_server.py"
OURS_SDK_STDIO = SERVERS / "ours_sdk_stdio.py"
CONSOLE_SCRIPT = "rosbridge-mcp-server"

#: What the simulated robot offers for items 3-5 (and a rosbridge given with --url may not).
ADD_TWO_INTS = "/add_two_ints"
SLOW_SERVICE = "/slow_service"
SLOW_SERVICE_SECONDS = 0.05
FAST_TOPIC = "/fast_counter"
#: The camera of items 5 and 9 (the simulated robot's, at this size; item 9 also starts one at full HD).
CAMERA_TOPIC = "/camera/image_raw"
CAMERA_SIZE = "640x480"
FULL_HD = "1920x1080"
#: Item 9: a live 10 Hz topic, and a velocity topic for the publish stream.
CHATTER = "/chatter"
CMD_VEL = "/turtle1/cmd_vel"

MIB = 1024 * 1024

#: The rows of tool calls made by JSON-RPC lines on the pipes instead of the MCP SDK's client.
BARE = "the same called by JSON-RPC lines (the server alone, without the MCP client SDK's work)"
#: An MCP round trip's worth of idle before a floor call (the no-op tool's median on this machine): a tool's
#: request always reaches the bridge after one, and rosbridge 2.1.0 answers a request that follows a short
#: pause ~9 ms later than one sent back to back (docs/rosbridge-behaviour.md).
TOOL_PAUSE = 0.001
