"""``rosbridge-mcp-server`` with stopwatches around its layers: a profiling aid for ``decompose.py``.

It runs the unchanged server (the console script's ``main``) after wrapping three coroutines with timers:

* ``ToolCalls.call_tool`` (``server/tool_calls.py``) — everything the server does for one tool call after the
  SDK has read and parsed the request, up to the result it hands back to the SDK;
* ``RosbridgeClient.call_service`` — each rosbridge round trip made inside that;
* the stdio transport is our own (or, with ``--sdk-stdio``, the MCP SDK's worker-thread one).

At exit it writes the samples, in seconds, as JSON to the file named by ``BENCH_TIMINGS``.
"""

from __future__ import annotations

import atexit
import collections
import functools
import json
import os
import sys
import time
from collections.abc import Awaitable, Callable
from typing import Any

from rosbridge_mcp_server import server as cli
from rosbridge_mcp_server.cli import main
from rosbridge_mcp_server.client import RosbridgeClient
from rosbridge_mcp_server.server.tool_calls import ToolCalls

__all__: list[str] = []

_samples: dict[str, list[float]] = collections.defaultdict(list)


def _timed(key: str, method: Callable[..., Awaitable[Any]]) -> Callable[..., Awaitable[Any]]:
    @functools.wraps(method)
    async def timed(*args: Any, **kwargs: Any) -> Any:
        began = time.perf_counter()
        try:
            return await method(*args, **kwargs)
        finally:
            _samples[key].append(time.perf_counter() - began)

    return timed


def _dump() -> None:
    target = os.environ.get("BENCH_TIMINGS")
    if target:
        with open(target, "w") as out:
            json.dump(_samples, out)


if __name__ == "__main__":
    ToolCalls.call_tool = _timed("handler", ToolCalls.call_tool)  # type: ignore[method-assign]
    RosbridgeClient.call_service = _timed("rosbridge", RosbridgeClient.call_service)  # type: ignore[method-assign]
    if "--sdk-stdio" in sys.argv:
        sys.argv.remove("--sdk-stdio")
        from ours_sdk_stdio import _serve_through_the_sdk  # this script's own folder is first on sys.path

        cli.serve_stdio = _serve_through_the_sdk  # type: ignore[assignment]
    atexit.register(_dump)
    main()
