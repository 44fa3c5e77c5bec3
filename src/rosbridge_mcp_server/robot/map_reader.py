"""Reading the robot's map: one ``nav_msgs/OccupancyGrid`` from its topic, decoded off the event loop.

The map is asked for as CBOR when the bridge can send it so (the dialect's ``compression_for``; an
OccupancyGrid has no fixed-size array): one binary frame whose cells arrive as bytes (2.25 M cells: 44 ms
against 1.7 s as JSON on rosbridge 2.1.0); a bridge that ignores the request sends JSON, decoded the same.
When none came and the bridge drops large CBOR frames (ROS 2: a map above the connection's fragment size,
10 MB by default, ~10 M cells), it is asked for once more as JSON, which arrives in fragments: a silent map
topic costs two timeouts there. The one map reader of ``view_map`` and of navigation (``navigation.survey``).
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

from rosbridge_mcp_server.robot.listening import listen
from rosbridge_mcp_server.robot.messages import short_type_name
from rosbridge_mcp_server.robot.occupancy import Grid, MapError, decode_grid

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = ["GRID_TYPE", "MapReading", "read_map", "receive_map"]

GRID_TYPE = "nav_msgs/OccupancyGrid"
#: A map this small fits one CBOR frame of any bridge (rosbridge fragments at 10 MB by default, and setups
#: that lower it keep it far above 50 kB): it was not dropped for its size.
_CBOR_DROPPED_CELLS = 50_000


@dataclass(frozen=True)
class MapReading:
    """The map heard (``None``: nothing arrived within the wait, or the waits), and how it came when that
    took a second wait."""

    grid: Grid | None
    note: str | None = None


async def receive_map(client: RosbridgeClient, topic: str, msg_type: str, timeout: float) -> MapReading:
    """The latest map on *topic* (of type *msg_type*), CBOR first; :class:`MapError` when it is not a usable
    grid."""
    dialect = await client.dialect()
    compression = dialect.compression_for(fixed_size_arrays=False)
    message = await _one(client, topic, msg_type, timeout, compression)
    note = None
    if message is None and compression is not None and dialect.drops_large_cbor:
        message = await _one(client, topic, msg_type, timeout, None)
        if message is not None:
            note = _second_wait(message, timeout)
    if message is None:
        return MapReading(None)
    return MapReading(await asyncio.to_thread(decode_grid, message), note)


async def read_map(
    client: RosbridgeClient, graph: RosGraph, topic: str, timeout: float
) -> tuple[Grid | None, str | None]:
    """The latest map on *topic*, its type checked in the graph first, or why there is none."""
    msg_type = await graph.topic_type(topic)
    if not msg_type:
        return None, f"no map: {topic} is not in the robot's graph (is the map server running?)"
    if short_type_name(msg_type) != GRID_TYPE:
        return None, f"no map: {topic} carries {msg_type}, not {GRID_TYPE}"
    try:
        reading = await receive_map(client, topic, msg_type, timeout)
    except MapError as exc:
        return None, f"no usable map on {topic}: {exc}"
    if reading.grid is None:
        return None, f"no map: nothing arrived on {topic} within {timeout:g} s"
    return reading.grid, None


async def _one(
    client: RosbridgeClient, topic: str, msg_type: str, timeout: float, compression: Literal["cbor"] | None
) -> dict[str, Any] | None:
    heard = await listen(
        client, topic, msg_type, count=1, duration=None, first_timeout=timeout, compression=compression
    )
    return heard.messages[0].message if heard.messages else None


def _second_wait(message: dict[str, Any], timeout: float) -> str:
    """Why the map came only on the second (JSON) wait, judged by its size."""
    cells = len(message.get("data") or ()) if isinstance(message, dict) else 0
    if cells < _CBOR_DROPPED_CELLS:
        # Far under the fragment size: CBOR was not dropped; the map came later than the first wait.
        return (
            f"The map ({cells} cells) did not arrive within {timeout:g} s and came on a second wait: its "
            "publisher does not latch it (map_server does), so a new subscriber waits for its next one."
        )
    return (
        f"The map did not arrive as CBOR within {timeout:g} s (rosbridge drops CBOR frames above its "
        "fragment size, 10 MB by default); it was read as JSON, which is slower."
    )
