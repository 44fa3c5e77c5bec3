"""The simulated robot plays a recording (``rosbridge-sim-robot --play FILE.mcap [--loop]``).

Every channel of the MCAP file whose schema the simulator's interface registry knows becomes a topic published
by the player's node (``/rosbag2_player`` on ROS 2, ``/player`` on ROS 1, as ``ros2 bag play`` and ``rosbag
play`` name theirs), with its recorded type, spelled for the dialect: a ``ros2msg`` recording plays on a ROS 1
robot too when the types exist in both. Messages go out in real time, spaced as their log times were; a topic
a world node publishes too is taken over by the recording. A topic with a single message, a map
(``OccupancyGrid``) and ``/tf_static`` are latched, as map_server and tf2's static broadcaster publish them:
a late subscriber gets the latest one played. Decoding uses the ``mcap`` support packages
(``ros2msg``/``cdr``, ``ros1msg``/``ros1``, ``json``), imported only when a recording is played.

The file is read through :mod:`rosbridge_mcp_server.mcapfile`, within the same budget as the server's
``read_recording`` (:data:`PLAY_MEMORY`, :data:`CHECK_SECONDS` to check it at start): a file declaring more
than it holds, a compression bomb, a cut-off record or a schema containing itself is refused with what is
wrong, before playing or (found mid-way in a file with a summary) by ending the pass with an error line.
"""

from __future__ import annotations

import asyncio
import base64
import json
import logging
import time
from array import array
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.mcapfile import (
    Budget,
    DecodeCost,
    McapFile,
    RecordingProblem,
    decode_cost,
    schema_problem,
)
from rosbridge_mcp_server.sim.interfaces import InterfaceError

if TYPE_CHECKING:
    from rosbridge_mcp_server.sim.nodes.kit import NodeKit

__all__ = ["PlayError", "Player"]

log = logging.getLogger("rosbridge_mcp_server.sim")

_MAGIC = b"\x89MCAP0\r\n"
#: The memory one read of the file may hold (the server's decode budget); the seconds checking it may take.
PLAY_MEMORY = 256 * 1024 * 1024
CHECK_SECONDS = 10.0
#: Types played latched whatever their count (map_server, static transforms).
_LATCHED_TYPES = ("nav_msgs/msg/OccupancyGrid", "nav_msgs/OccupancyGrid", "tf2_msgs/msg/TFMessage")


class PlayError(ValueError):
    """The file cannot be played; ``str()`` says why."""


@dataclass
class _Channel:
    topic: str
    type: str
    messages: int


def _plain(value: Any, ros2: bool) -> Any:
    """A decoded message as JSON-like data, byte arrays as base64 and times in the dialect's spelling."""
    if value is None or isinstance(value, bool | int | float | str):
        return value
    if isinstance(value, bytes | bytearray | memoryview):
        return base64.b64encode(bytes(value)).decode()
    if isinstance(value, list | tuple):
        return [_plain(item, ros2) for item in value]
    if isinstance(value, array):
        return value.tolist()
    if isinstance(value, dict):
        return {k: _plain(v, ros2) for k, v in value.items()}
    slots = getattr(type(value), "__slots__", None)
    if slots is None:
        return value.tolist() if hasattr(value, "tolist") else str(value)
    names = [slots] if isinstance(slots, str) else [n for n in slots if not n.startswith("_")]
    out = {name: _plain(getattr(value, name, None), ros2) for name in names}
    keys = set(out)
    if keys in ({"sec", "nanosec"}, {"secs", "nsecs"}):
        sec = out.get("sec", out.get("secs"))
        nsec = out.get("nanosec", out.get("nsecs"))
        return {"sec": sec, "nanosec": nsec} if ros2 else {"secs": sec, "nsecs": nsec}
    return out


def _spelled(schema_name: str, ros2: bool) -> str:
    pkg, _, rest = schema_name.partition("/")
    name = rest.split("/")[-1]
    return f"{pkg}/msg/{name}" if ros2 else f"{pkg}/{name}"


class Player:
    """Plays one MCAP file on the world's bridge."""

    def __init__(self, kit: NodeKit, path: str | Path, *, loop: bool = False) -> None:
        self.kit = kit
        self.path = Path(path)
        self.loop = loop
        self.node = "/rosbag2_player" if kit.ros2 else "/player"
        self.channels: dict[str, _Channel] = {}
        #: Messages published so far, per topic (what a subscriber can count against).
        self.published: dict[str, int] = {}
        self.passes = 0
        self.done = asyncio.Event()

    # --- building -----------------------------------------------------------------------------------------

    def build(self) -> None:
        """Read the file's channels and register the player's topics; :class:`PlayError` if it cannot play."""
        try:
            with self.path.open("rb") as handle:
                if handle.read(len(_MAGIC)) != _MAGIC:
                    raise PlayError(f"{self.path} is not an MCAP file")
        except OSError as exc:
            raise PlayError(f"cannot read {self.path}: {exc.strerror or exc}") from None
        counts, types = self._channels()
        for topic, schema_name in types.items():
            try:
                msg_type = self.kit.bridge.registry.resolve(_spelled(schema_name, self.kit.ros2), "msg")
            except InterfaceError as exc:
                log.warning("not played: %s (%s): %s", topic, schema_name, exc)
                continue
            existing = self.kit.graph.topic_types.get(topic)
            if existing is not None and existing != msg_type:
                log.warning(
                    "not played: %s is %s in the world, %s in the recording", topic, existing, msg_type
                )
                continue
            # A world node publishing the topic stops (its kit forgets the topic): the recording has it.
            self.kit.types.pop(topic, None)
            for node in self.kit.graph.publishers_of(topic):
                self.kit.graph.remove_publisher(node, topic)
            self.kit.graph.add_publisher(self.node, topic, msg_type)
            static = topic.endswith("/tf_static") and "TFMessage" in msg_type
            if counts[topic] == 1 or msg_type in _LATCHED_TYPES[:2] or static:
                self.kit.graph.latched.setdefault(topic, None)
            self.channels[topic] = _Channel(topic, msg_type, counts[topic])
            self.published[topic] = 0
        if not self.channels:
            raise PlayError(f"{self.path} has no topic this simulator can play (types unknown to it)")
        log.info(
            "playing %s: %s",
            self.path.name,
            ", ".join(f"{c.topic} ({c.messages})" for c in self.channels.values()),
        )
        self.kit.loops.append(self._play)

    def _channels(self) -> tuple[dict[str, int], dict[str, str]]:
        """Messages and schema name per topic: from the summary's statistics, else the whole file read through
        once within the budget (so a hostile file is refused before anything plays); a channel whose schema
        cannot be decoded safely is left out, with a warning."""
        counts: dict[str, int] = {}
        try:
            with self.path.open("rb") as handle:
                mcap = McapFile(
                    handle, self.path.stat().st_size, Budget(PLAY_MEMORY, CHECK_SECONDS), self.path.name
                )
                summary = mcap.summary()
                if summary is not None and summary.statistics and summary.statistics.channel_counts:
                    mcap.schemas.update(summary.schemas)
                    mcap.channels.update(summary.channels)
                    declared = summary.statistics.channel_counts
                    counts = {ch.topic: declared.get(cid, 0) for cid, ch in summary.channels.items()}
                else:
                    for channel, _, _ in mcap.messages(wanted=set()):
                        counts[channel.topic] = counts.get(channel.topic, 0) + 1
        except RecordingProblem as exc:
            raise PlayError(f"{self.path} cannot be played: {exc}") from None
        except OSError as exc:
            raise PlayError(f"cannot read {self.path}: {exc.strerror or exc}") from None
        types: dict[str, str] = {}
        for channel in mcap.channels.values():
            schema = mcap.schemas.get(channel.schema_id)
            problem = schema_problem(schema) if schema is not None else None
            if problem:
                log.warning("not played: %s: %s", channel.topic, problem)
                counts.pop(channel.topic, None)
            elif schema is not None and channel.topic in counts:
                types[channel.topic] = schema.name
        return counts, types

    # --- playing ------------------------------------------------------------------------------------------

    async def _play(self) -> None:
        from mcap_ros1.decoder import DecoderFactory as Ros1Factory  # noqa: PLC0415
        from mcap_ros2.decoder import DecoderFactory as Ros2Factory  # noqa: PLC0415

        factories = [Ros2Factory(), Ros1Factory()]
        while True:
            self.passes += 1
            try:
                await self._one_pass(factories)
            except (RecordingProblem, PlayError, OSError) as exc:
                log.error("playing %s stopped: %s", self.path.name, exc)
                self.done.set()
                return
            if not self.loop:
                self.done.set()
                return

    async def _one_pass(self, factories: list[Any]) -> None:
        first: int | None = None
        start = time.monotonic()
        decoders: dict[int, Any] = {}
        costs: dict[int, DecodeCost | str | None] = {}
        with self.path.open("rb") as handle:
            # The time budget is the recording's own length, played in real time: only memory is held to it.
            mcap = McapFile(
                handle, self.path.stat().st_size, Budget(PLAY_MEMORY, float("inf")), self.path.name
            )
            wanted = None
            for channel, log_time, data in mcap.messages(wanted):
                entry = self.channels.get(channel.topic)
                if entry is None or data is None:
                    continue
                if first is None:
                    first = log_time
                wait = start + (log_time - first) / 1e9 - time.monotonic()
                await asyncio.sleep(max(wait, 0))  # also yields to the loop between messages
                decoder = decoders.get(channel.id)
                if decoder is None:
                    decoder = decoders[channel.id] = self._decoder(
                        factories, mcap.schemas.get(channel.schema_id), channel
                    )
                bridge = self.kit.bridge
                if not bridge.has_subscribers(channel.topic) and channel.topic not in self.kit.graph.latched:
                    continue  # nobody listens: nothing goes out, as a real publisher's reaches no one
                if channel.id not in costs:
                    schema = mcap.schemas.get(channel.schema_id)
                    costs[channel.id] = decode_cost(schema) if schema is not None else None
                cost = costs[channel.id]
                if isinstance(cost, DecodeCost) and cost.memory(len(data)) > PLAY_MEMORY:
                    log.error(
                        "playing %s: a message of %d bytes would decode over the memory",
                        channel.topic,
                        len(data),
                    )
                    continue
                try:
                    msg = _plain(decoder(data), self.kit.ros2)
                    bridge.publish_json(channel.topic, entry.type, msg)
                except Exception as exc:  # one bad message costs one log line
                    log.error("playing %s: %s", channel.topic, exc)
                    continue
                self.published[channel.topic] += 1

    @staticmethod
    def _decoder(factories: list[Any], schema: Any, channel: Any) -> Any:
        if channel.message_encoding == "json":
            return json.loads
        for factory in factories:
            decoder = factory.decoder_for(channel.message_encoding, schema)
            if decoder is not None:
                return decoder
        raise PlayError(f"{channel.topic}: cannot decode {channel.message_encoding}")
