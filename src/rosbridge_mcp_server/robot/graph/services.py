"""Services and their types: rosapi's ``service_type``, one at a time or a few side by side, or the type a
ROS 2 bridge names when it refuses a probe call (:mod:`..known_types`); the per-node services every ROS node
offers are typed from their names."""

from __future__ import annotations

import logging
from dataclasses import dataclass

from rosbridge_mcp_server.errors import RequestTimeoutError, ServiceError
from rosbridge_mcp_server.robot.graph.rosapi import ConnectionKnowledge, Rosapi, bounded_map, strings
from rosbridge_mcp_server.robot.known_types import (
    PROBE_CONCURRENCY,
    PROBE_FIELD,
    PROBE_SECONDS,
    infrastructure_types,
    service_type_from_refusal,
)

__all__ = ["ServiceEntry", "Services"]

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ServiceEntry:
    """A service and its type (``""`` when rosapi could not tell)."""

    name: str
    type: str


class Services:
    """Service look-ups through rosapi and probe calls, with the types learnt kept for the connection."""

    def __init__(self, rosapi: Rosapi) -> None:
        self._rosapi = rosapi
        self._client = rosapi.client
        # The last listing whose services were all typed: (the connection's knowledge, its names, entries).
        # The same names on the same connection list the same entries, so a call reuses it.
        self._listing: tuple[ConnectionKnowledge, tuple[str, ...], tuple[ServiceEntry, ...]] | None = None

    @property
    def _known(self) -> ConnectionKnowledge:
        return self._rosapi.known

    async def service_names(self) -> list[str]:
        """Every service name, sorted."""
        await self._rosapi.ros_info()  # forgets what an earlier connection knew
        values = await self._rosapi.call("services")
        names = sorted(set(strings(values.get("services"))))
        self._known.service_names = tuple(names)
        return names

    async def service_names_seen(self) -> tuple[str, ...] | None:
        """The names of the last service listing on this connection, without asking (None before the first).

        Only a guess at what the next listing will say, to start work that the listing then confirms.
        """
        await self._rosapi.ros_info()
        return self._known.service_names

    async def service_type(self, service: str, *, cached: bool = False) -> str:
        """The type of ``service``, or ``""`` when rosapi does not know it.

        With ``cached``, a type already seen on this connection is reused, saving a round trip per call;
        callers forget it (:meth:`forget_service`) when the service turns out to be gone, and ask afresh
        when the cached type disagrees with what they expect.
        """
        await self._rosapi.ros_info()  # forgets what an earlier connection knew
        if cached and (known := self._known.service_types.get(service)):
            return known
        values = await self._rosapi.call("service_type", {"service": service})
        found = values.get("type")
        found = found if isinstance(found, str) else ""
        if found:
            if self._known.service_types.get(service) != found:
                self._listing = None
            self._known.service_types[service] = found
        else:
            self.forget_service(service)
        return found

    def forget_service(self, service: str) -> None:
        """Drop the cached type of ``service`` (it went away, or was offered anew)."""
        self._known.service_types.pop(service, None)
        self._listing = None

    async def _service_type_or_blank(self, service: str) -> str:
        try:
            return await self.service_type(service)
        except (ServiceError, RequestTimeoutError) as exc:
            _log.info("no type for service %s: %s", service, exc)
            return ""

    async def services(self) -> tuple[ServiceEntry, ...]:
        """Every service with its type (``""`` where a look-up failed).

        A service's type cannot change while it exists, so each is looked up once per connection and kept
        until the service is gone from the list; the per-node services every ROS node offers are typed from
        their names (:func:`infrastructure_types`) without asking.
        """
        info = await self._rosapi.ros_info()
        names = await self.service_names()
        last = self._listing
        if last is not None and last[0] is self._known and last[1] == tuple(names):
            return last[2]
        known, listed = self._known.service_types, self._known.listed_types
        for cache in (known, listed):
            for gone in cache.keys() - set(names):
                del cache[gone]
        fixed = infrastructure_types(names, info.version)
        missing = self._untyped(names, fixed)
        if missing and info.version == 2 and await self._refuses_unknown_fields():
            await bounded_map(self._listed_type, missing, PROBE_CONCURRENCY)
        elif missing:
            await bounded_map(self._service_type_or_blank, missing)
        entries = tuple(
            ServiceEntry(name, fixed.get(name) or known.get(name) or listed.get(name, "")) for name in names
        )
        typed = all(entry.type for entry in entries)
        self._listing = (self._known, tuple(names), entries) if typed else None
        return entries

    async def learn_service_types(self, limit: int = 256) -> int:
        """Ask rosapi, one service at a time, for the types a first listing would look up; how many it learnt.

        Run in the background when a connection opens (:mod:`..warm_up`), so the model's first
        ``list_services`` finds them known, and ``publish_service`` skips its type look-up. One call at a
        time keeps out of the way of the model's own calls (rosapi answers one call at a time; 0.11.17 is
        slower with several), and rosapi's ``service_type`` leaves nothing in the bridge's log, where a probe
        call leaves an error line. A look-up that times out ends it (:class:`RequestTimeoutError`).
        """
        info = await self._rosapi.ros_info()
        names = await self.service_names()
        learnt = 0
        for name in self._untyped(names, infrastructure_types(names, info.version))[:limit]:
            # Re-checked each time: a listing running meanwhile may have typed it already.
            if name in self._known.service_types or name in self._known.listed_types:
                continue
            # A refusal is passed over; a timeout ends it all (rosapi is stuck: the next would wait as long).
            try:
                if await self.service_type(name):
                    learnt += 1
            except ServiceError as exc:
                _log.info("no type for service %s: %s", name, exc)
        return learnt

    def _untyped(self, names: list[str], fixed: dict[str, str]) -> list[str]:
        """The services among *names* whose type neither their name fixes nor this connection knows."""
        known, listed = self._known.service_types, self._known.listed_types
        return [name for name in names if name not in known and name not in listed and name not in fixed]

    async def _refuses_unknown_fields(self) -> bool:
        """Whether this bridge refuses a request with a field no message has, before calling anything.

        Every rosbridge we know does ("Message type X_Request does not have a field ..."); it is checked once
        per connection on rosapi's harmless ``get_time`` before any other service is probed that way.
        """
        if self._known.refuses_unknown_fields is None:
            try:
                await self._client.call_service("/rosapi/get_time", {PROBE_FIELD: 0}, timeout=PROBE_SECONDS)
            except ServiceError as exc:
                self._known.refuses_unknown_fields = "does not have a field" in exc.message
            except RequestTimeoutError:
                self._known.refuses_unknown_fields = False
            else:
                self._known.refuses_unknown_fields = False
        return self._known.refuses_unknown_fields

    async def _listed_type(self, service: str) -> None:
        """A service's type for the listing, from the bridge's refusal of a probe call; rosapi if none.

        rosbridge 2.1.0 answers such a probe in ~2-12 ms without creating a ROS client, where each rosapi
        ``service_type`` call creates one and about a quarter of them take ~90 ms
        (docs/rosbridge-behaviour.md).
        The type is only shown: checking a request still asks rosapi, so a misread refusal can never make
        rosapi describe a type it cannot load (that ends rosapi 2.1.0).
        """
        try:
            await self._client.call_service(service, {PROBE_FIELD: 0}, timeout=PROBE_SECONDS)
        except ServiceError as exc:
            found = service_type_from_refusal(exc.message)
            if found:
                self._known.listed_types[service] = found
                return
        except RequestTimeoutError:
            pass  # a glob-denied service gets no answer at all; rosapi may still know its type
        await self._service_type_or_blank(service)
