"""rosapi on one client, and what the client's current connection has learnt (what the graph's parts share).

Everything the graph asks is an ordinary ``call_service`` to a ``/rosapi/...`` service on the shared client.
What one connection has learnt (type definitions, the topics it publishes, service and action types) is one
object, replaced whole when the client reports a new connection: a reconnect may be to a robot with other
packages installed.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Awaitable, Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypeVar

from rosbridge_mcp_server.client import BridgeCapabilities, Dialect, RosInfo
from rosbridge_mcp_server.errors import ServiceError
from rosbridge_mcp_server.robot.messages import TypeDef
from rosbridge_mcp_server.robot.text import NAME_CHARS, shown
from rosbridge_mcp_server.robot.wording import full_stop

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient

__all__ = ["ROSAPI_HINT", "ConnectionKnowledge", "Rosapi", "bounded_map", "is_missing_service", "strings"]

ROSAPI_HINT = (
    "rosapi must be running next to rosbridge: the launch files start it (`ros2 launch rosbridge_server "
    "rosbridge_websocket_launch.xml`, `roslaunch rosbridge_server rosbridge_websocket.launch`); "
    "`rosbridge_websocket` run alone does not."
)

# Type look-ups for many names at once (service types, action types) run a few side by side, not more:
# rosbridge 0.11.17 answered 46 service_type calls in ~0.2 s one after another or four at a time, but took
# ~1.1 s eight or more at a time; rosbridge 2.1.0 left a call unanswered with sixteen connections asking.
_LOOKUP_CONCURRENCY = 4

_T = TypeVar("_T")
_R = TypeVar("_R")


def is_missing_service(error: ServiceError) -> bool:
    """The bridge said the service is not in the graph (rosbridge_suite 0.11 and 2.x, rosbridge-server-rs)."""
    return error.not_in_graph


@dataclass
class ConnectionKnowledge:
    """What one connection has learnt about the bridge; replaced whole when the connection changes."""

    typedefs: dict[tuple[str, str], dict[str, TypeDef]] = field(default_factory=dict)
    interfaces: frozenset[str] | None = None
    interfaces_asked: bool = False
    details_values: dict[tuple[str, str], dict[str, Any]] = field(default_factory=dict)
    publishing: dict[str, str] = field(default_factory=dict)
    service_types: dict[str, str] = field(default_factory=dict)
    action_types: dict[str, str] = field(default_factory=dict)
    no_action_type_service: bool = False
    # Types the bridge named when refusing a probe call; only listed, never used to ask rosapi for details.
    listed_types: dict[str, str] = field(default_factory=dict)
    refuses_unknown_fields: bool | None = None
    # The names of the last service listing on this connection (None before the first one).
    service_names: tuple[str, ...] | None = None
    # The last node list and topic list (name, type) this connection saw, each with when (the graph's clock).
    nodes_seen: tuple[float, tuple[str, ...]] | None = None
    topics_seen: tuple[float, tuple[tuple[str, str], ...]] | None = None
    # Topics last seen with subscribers: when, and who.
    subscribers_seen: dict[str, tuple[float, tuple[str, ...]]] = field(default_factory=dict)


class Rosapi:
    """``/rosapi/...`` calls on one client, and what the connection they last went over has learnt."""

    def __init__(self, client: RosbridgeClient, *, clock: Callable[[], float] = time.monotonic) -> None:
        self.client = client
        #: When a listing was seen (seconds; tests give a clock of their own).
        self.clock = clock
        self._cache_owner: RosInfo | None = None
        self._known = ConnectionKnowledge()

    @property
    def known(self) -> ConnectionKnowledge:
        """What this connection has learnt; call :meth:`ros_info` first to forget an earlier connection's."""
        return self._known

    async def ros_info(self) -> RosInfo:
        """The bridge's ROS version and distro (detected by the client once per connection)."""
        return (await self.dialect()).info

    async def dialect(self) -> Dialect:
        """How the bridge spells types and time fields (the client's, one per connection)."""
        dialect = await self.client.dialect()
        # The client makes one RosInfo per connection, so a new object means a new connection.
        if dialect.info is not self._cache_owner:
            self._cache_owner = dialect.info
            self._known = ConnectionKnowledge()
        return dialect

    async def capabilities(self) -> BridgeCapabilities:
        """What the bridge can do (decided once per connection by the client): asked instead of its name."""
        return (await self.dialect()).capabilities

    def saw_nodes(self, names: Iterable[str]) -> None:
        """Note the node list this connection just got (see :meth:`recent_nodes`)."""
        self._known.nodes_seen = (self.clock(), tuple(names))

    def recent_nodes(self, max_age: float) -> tuple[str, ...] | None:
        """The node list this connection saw within the last *max_age* seconds, or None (call :meth:`ros_info`
        first, so an earlier connection's list is forgotten)."""
        seen = self._known.nodes_seen
        return seen[1] if seen is not None and self.clock() - seen[0] <= max_age else None

    async def call(self, name: str, args: dict[str, Any] | None = None) -> dict[str, Any]:
        """Call ``/rosapi/<name>``; a missing rosapi is a :class:`ServiceError` saying how to start it."""
        service = f"/rosapi/{name}"
        try:
            values = await self.client.call_service(service, args or {})
        except ServiceError as exc:
            if is_missing_service(exc):
                raise ServiceError(service, f"{full_stop(exc.message)} {ROSAPI_HINT}") from exc
            raise
        return values if isinstance(values, dict) else {}


def strings(value: Any) -> list[str]:
    """The strings of a rosapi list field (nothing when it is not a list): names and types as the graph gives
    them, shown as robot text (``robot/text.py``: escaped and capped; a real ROS name is unchanged, and one
    holding a newline or a bidi override never was a name anything could be called by)."""
    if not isinstance(value, list):
        return []
    return [shown(item, NAME_CHARS) for item in value if isinstance(item, str)]


async def bounded_map(
    func: Callable[[_T], Awaitable[_R]], items: Iterable[_T], limit: int = _LOOKUP_CONCURRENCY
) -> list[_R]:
    """``func`` of every item, a few side by side, results in the items' order."""
    semaphore = asyncio.Semaphore(limit)

    async def one(item: _T) -> _R:
        async with semaphore:
            return await func(item)

    # A TaskGroup, not gather: when one look-up fails (the connection dropped) the others are cancelled.
    # The caller gets that first failure itself (a NotConnectedError the tool answers), not an ExceptionGroup.
    try:
        async with asyncio.TaskGroup() as group:
            tasks = [group.create_task(one(item)) for item in items]
    except BaseExceptionGroup as failures:
        raise _first_leaf(failures) from None
    return [task.result() for task in tasks]


def _first_leaf(group: BaseExceptionGroup[BaseException]) -> BaseException:
    """The first exception in *group* that is not itself a group."""
    first = group.exceptions[0]
    return _first_leaf(first) if isinstance(first, BaseExceptionGroup) else first
