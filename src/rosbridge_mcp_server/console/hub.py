"""What the console shows and what its buttons do, without the web: state snapshots, changes, E-STOP, camera.

:class:`ConsoleHub` gathers each robot's connection, streams and goals, the audit (newest first), the
confirmations waiting for the person and the latched e-stop into one JSON-ready snapshot, and tells waiters
(the page's event streams) when it changes. Audit lines and the operator's changes are pushed at once; the
connection, streams and goals are looked at four times a second and pushed when they differ. The camera and
the map panel (``mapview.py``) listen only while a page is open: when the last page's event stream closes,
the camera is turned off and the map panel stops listening.
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import json
import logging
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rosbridge_mcp_server.console.feedback import feedback_text
from rosbridge_mcp_server.console.mapview import MapPanel, Picture, trying_again
from rosbridge_mcp_server.errors import RosbridgeError
from rosbridge_mcp_server.robot.approval import Act
from rosbridge_mcp_server.robot.messages import short_type_name
from rosbridge_mcp_server.robot.names import absolute_name
from rosbridge_mcp_server.safety import PRESSER_NAMES, Audit, AuditEntry, Operator, Presser, emergency_stop

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.session import RobotSession

__all__ = [
    "AUDIT_KEPT",
    "CAMERA_FPS",
    "CAMERA_MAX_SIZE",
    "ConsoleHub",
    "RobotView",
    "default_camera",
    "summary_text",
]

_log = logging.getLogger("rosbridge_mcp_server.console")

#: Audit lines the page shows (and a new page gets at once).
AUDIT_KEPT = 50
#: The camera's frame budget: at most this many frames a second, at most this many pixels on the long side.
CAMERA_FPS = 4.0
CAMERA_MAX_SIZE = 480
#: How often the connection, streams and goals are looked at (they have no change signal of their own).
LOOK_EVERY = 0.25
#: Longest payload text in an audit line on the page.
PAYLOAD_SHOWN = 240
#: The E-STOP button as the stop's presser (also the tool column of its audit lines), and how the answers of
#: what it stopped name it.
ESTOP_PRESSER: Presser = "console"
ESTOP_BY = PRESSER_NAMES[ESTOP_PRESSER]
_IMAGE_TYPES = ("sensor_msgs/Image", "sensor_msgs/CompressedImage")


@dataclass
class RobotView:
    """One robot as the console sees it: its session (client, graph, goals, what this server set going on it)
    and its audit."""

    name: str
    session: RobotSession
    audit: Audit


class ConsoleHub:
    """The console's state and actions for ``robots`` (their audits merged) and the ``operator``.

    E-STOP stops every robot; the camera and the image-topic picker use the first robot.
    """

    def __init__(self, robots: Sequence[RobotView], operator: Operator) -> None:
        if not robots:
            raise ValueError("the console needs at least one robot")
        self.robots = list(robots)
        self.operator = operator
        #: The MCP tasks running now, a row each (the server sets it when it serves tasks).
        self.tasks: Callable[[], list[dict[str, Any]]] = list
        self._entries: deque[dict[str, Any]] = deque(maxlen=AUDIT_KEPT)
        self._version = 0
        self._changed = asyncio.Event()
        self._closed = False
        self._live: Any = None
        first = self.robots[0].session
        self._graph = first.graph
        self.camera_topic: str | None = None
        self.camera_status = "off"
        self.frame: Picture | None = None
        self._frames = 0
        self._camera_task: asyncio.Task[None] | None = None
        self._pushes = 0
        self.viewers = 0
        self.map = MapPanel(first.client, self._graph, self.changed, self._pushed)
        #: Since when (local wall-clock time, HH:MM:SS) each robot has not been connected.
        self._down_since: dict[str, str] = {}
        for robot in self.robots:
            robot.audit.listen(self._on_audit)
        operator.listen(self.changed)

    # --- changes -------------------------------------------------------------------------------------------

    @property
    def version(self) -> int:
        return self._version

    @property
    def closed(self) -> bool:
        return self._closed

    def changed(self) -> None:
        """Something the page shows changed: wake every waiter."""
        self._version += 1
        self._wake()

    def _pushed(self) -> None:
        """A new pose or map picture (not part of the snapshot): wake every waiter."""
        self._pushes += 1
        self._wake()

    def _wake(self) -> None:
        event, self._changed = self._changed, asyncio.Event()
        event.set()

    def marks(self) -> tuple[int, int, int]:
        """What a waiter has seen: the state's version, the camera's frames, the pose's and map's pushes."""
        return (self._version, self._frames, self._pushes)

    async def wait_changed(self, seen: tuple[int, int, int], timeout: float) -> bool:
        """Wait until anything is newer than ``seen`` (:meth:`marks`); ``False`` after ``timeout``."""
        event = self._changed
        if self.marks() != seen or self._closed:
            return True
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(timeout):
                await event.wait()
                return True
        return False

    def close(self) -> None:
        """The console is going away: end the event streams and the camera."""
        self._closed = True
        if self._camera_task is not None:
            self._camera_task.cancel()
        self.map.stop()
        self.changed()

    def page_opened(self) -> None:
        """A page's event stream opened: the map panel listens while any is open."""
        self.viewers += 1
        if self.viewers == 1 and not self._closed:
            self.map.start()

    def page_closed(self) -> None:
        """A page's event stream closed; with the last one the camera and the map panel stop listening."""
        self.viewers = max(0, self.viewers - 1)
        if self.viewers == 0:
            if self.camera_topic is not None:
                self.show_camera(None)
            self.map.stop()

    async def look(self) -> None:
        """Push the connection, streams and goals when they change; runs until cancelled."""
        while not self._closed:
            live = self._live_state()
            if live != self._live:
                self._live = live
                self.changed()
            await asyncio.sleep(LOOK_EVERY)

    # --- the snapshot --------------------------------------------------------------------------------------

    def snapshot(self) -> dict[str, Any]:
        """Everything the page shows but the camera frame, JSON-ready."""
        latched = self.operator.latched
        return {
            "robots": self._live_state(),
            "tasks": self.tasks(),
            "estop": {"latched": latched is not None, "by": latched},
            "pending": [
                {
                    "id": pending.id,
                    "tool": pending.act.tool,
                    "kind": pending.act.kind,
                    "name": pending.act.name,
                    "type": pending.act.type,
                    "question": pending.question,
                    "asked_at": pending.asked_at,
                    "by_link": pending.by_link,
                }
                for pending in self.operator.pending
            ],
            "audit": list(reversed(self._entries)),
            "camera": {"topic": self.camera_topic, "status": self.camera_status},
            "map": self.map.state(),
            # The camera and the map panel show the first robot: while it is down, their pictures are old.
            "stale_since": self._down_since.get(self.robots[0].name),
        }

    def frame_event(self) -> dict[str, Any] | None:
        return None if self.frame is None else self.frame.event()

    @property
    def frames(self) -> int:
        return self._frames

    def _live_state(self) -> list[dict[str, Any]]:
        now = time.monotonic()
        robots = []
        for robot in self.robots:
            client = robot.session.client
            facts = client.session_facts
            info = facts.info if facts is not None else None
            ros = None
            if info is not None:
                ros = f"ROS {info.version}" + (f" {info.distro}" if info.distro else "")
                self._down_since.pop(robot.name, None)
            else:
                self._down_since.setdefault(robot.name, time.strftime("%H:%M:%S"))
            robots.append(
                {
                    "name": robot.name,
                    "url": client.url,
                    "connected": info is not None,
                    "down_since": self._down_since.get(robot.name),
                    "ros": ros,
                    "streams": [
                        {"topic": s.topic, "type": s.type, "stopping": s.stop_requested.is_set()}
                        for s in robot.session.activity.streams
                    ],
                    "goals": [
                        {
                            "action": goal.action,
                            "goal_id": goal.goal_id,
                            "seconds": round(now - goal.started, 1),
                            "feedback_count": goal.feedback_count,
                            "last_feedback": (
                                feedback_text(goal.last_feedback[-1]) if goal.last_feedback else None
                            ),
                            "cancel_requested": goal.cancel_requested,
                        }
                        for goal in robot.session.goals.running()
                    ],
                }
            )
        return robots

    def _on_audit(self, entry: AuditEntry) -> None:
        keys = ("time", "robot", "caller", "tool", "kind", "name", "type", "outcome", "detail")
        shown = {key: entry.get(key) for key in keys}
        shown["payload"] = None if entry.get("payload") is None else _short(entry["payload"])
        shown["rate_hz"] = entry.get("rate_hz")
        shown["duration"] = entry.get("duration")
        self._entries.append(shown)
        self.changed()

    # --- what the buttons do -------------------------------------------------------------------------------

    async def estop(self) -> list[dict[str, Any]]:
        """E-STOP: latch first (nothing new is approved), then stop_robot on every robot; audited."""
        self.operator.latch("console")
        # Before anything awaits: every robot's calls that began before the press send nothing more.
        for robot in self.robots:
            robot.session.gate.stop(ESTOP_BY)
        reports = []
        for robot in self.robots:
            report = await emergency_stop(robot.session, by=ESTOP_PRESSER)
            for topic, type_name, message in report.zero_messages:
                robot.audit.write(Act(ESTOP_PRESSER, "topic", topic, type_name, message), "e-stop")
            for action, goal_id in report.goals:
                cancel = {"cancel": goal_id or "all"}
                robot.audit.write(Act(ESTOP_PRESSER, "action", action, "", cancel), "e-stop")
            if not report.did_anything:
                robot.audit.write(Act(ESTOP_PRESSER, "topic", "", "", None), "e-stop: nothing to stop")
            reports.append(
                {
                    "robot": robot.name,
                    "streams_stopped": report.streams_stopped,
                    "zeroed_topics": report.zeroed_topics,
                    "held_topics": report.held_topics,
                    "goals_cancelled": report.goals_cancelled,
                    "cancels": report.cancel_lines(),
                    "failures": report.failures,
                }
            )
        self.changed()
        return reports

    def release(self) -> bool:
        """Release the latched e-stop; ``False`` when it was not latched."""
        released = self.operator.release("console")
        if released:
            for robot in self.robots:
                robot.audit.write(Act("console", "topic", "", "", None), "e-stop released")
        return released

    # --- the camera ----------------------------------------------------------------------------------------

    async def image_topics(self) -> list[str]:
        """The image topics the first robot's graph lists (for the page's picker)."""
        topics = await self._graph.topics()
        return sorted(t.name for t in topics if short_type_name(t.type) in _IMAGE_TYPES)

    async def default_camera(self, topics: Sequence[str] | None = None) -> str | None:
        """The camera a person most likely wants first: see :func:`default_camera`."""
        return default_camera(await self.image_topics() if topics is None else topics)

    def show_camera(self, topic: str | None) -> None:
        """Show ``topic`` (``None``: no camera); a bad name is refused with :class:`RosbridgeError`."""
        name = absolute_name(topic, "topic") if topic else None
        if self._camera_task is not None:
            self._camera_task.cancel()
            self._camera_task = None
        if self.camera_topic is not None or name is not None:
            self.frame = None
        self.camera_topic = name
        self.frame = None
        self.camera_status = "off" if name is None else "starting"
        if name is not None:
            self._camera_task = asyncio.create_task(self._camera(name), name=f"console camera {name}")
        self.changed()

    async def _camera(self, topic: str) -> None:
        from rosbridge_mcp_server.pictures.images import ImageError  # noqa: PLC0415 - on first use

        client = self.robots[0].session.client
        while True:
            try:
                await self._frames_of(client, topic)
            except RosbridgeError as exc:
                self._camera_said(trying_again(exc))
            except ImageError as exc:
                self._camera_said(f"cannot show this frame: {exc}")
            # Not a sync: how soon to try again after the robot or the topic failed.
            await asyncio.sleep(2.0)

    async def _frames_of(self, client: RosbridgeClient, topic: str) -> None:
        msg_type = await self._graph.topic_type(topic)
        if not msg_type:
            self._camera_said(f"{topic} is not in the robot's graph yet")
            return
        compressed = short_type_name(msg_type) == _IMAGE_TYPES[1]
        if short_type_name(msg_type) not in _IMAGE_TYPES:
            self._camera_said(f"{topic} carries {msg_type}, not an image")
            return
        throttle = int(1000 / CAMERA_FPS)
        async with client.subscribe(
            topic, msg_type, throttle_rate=throttle, queue_length=1, max_queue=1
        ) as subscription:
            self._camera_said("waiting for a frame")
            while True:
                message = await subscription.get()
                frame = await asyncio.to_thread(_encode, message, compressed)
                self._frames += 1
                self.frame = Picture(self._frames, topic, "image/jpeg", *frame)
                self.camera_status = "live"
                self.changed()
                # The frame budget: the bridge throttles too, but a bridge that ignores it must not flood.
                await asyncio.sleep(1 / CAMERA_FPS)

    def _camera_said(self, status: str) -> None:
        self.camera_status = status
        self.changed()


#: Words in a topic name that mean a picture for machines, not people (depth, infrared, disparity, masks).
_NOT_FOR_PEOPLE = ("depth", "disparity", "/ir/", "infra", "mask", "confidence", "points", "segment")


def default_camera(topics: Sequence[str]) -> str | None:
    """The colour camera when there is one: a name without depth/infrared/..., preferring ``color``/``rgb``,
    then the raw image over its compressed copy, then the shortest name; ``None`` when there is no topic."""

    def rank(name: str) -> tuple[int, int, int, int, str]:
        lower = name.lower()
        machine = any(word in lower for word in _NOT_FOR_PEOPLE)
        colour = "color" in lower or "colour" in lower or "rgb" in lower
        compressed = lower.endswith(("/compressed", "/compresseddepth", "/theora"))
        return (machine, not colour, compressed, len(name), name)

    return min(topics, key=rank, default=None)


def _encode(message: dict[str, Any], compressed: bool) -> tuple[str, int, int]:
    from rosbridge_mcp_server.pictures.images import decode_compressed, decode_raw, encode_picture  # noqa: PLC0415 - on first use

    picture = decode_compressed(message) if compressed else decode_raw(message)
    encoded = encode_picture(picture, CAMERA_MAX_SIZE, "jpeg")
    return base64.b64encode(encoded.data).decode("ascii"), encoded.width, encoded.height


def _short(value: Any) -> str:
    text = json.dumps(value, ensure_ascii=False, default=str)
    return text if len(text) <= PAYLOAD_SHOWN else f"{text[:PAYLOAD_SHOWN]}… ({len(text)} characters)"


def summary_text(snapshot: dict[str, Any], audit_lines: int = 5) -> str:
    """The snapshot as a few lines for a model: connection, the latch, what waits and runs, the last calls."""
    lines = []
    for robot in snapshot["robots"]:
        state = f"connected ({robot['ros']})" if robot["connected"] else "not connected"
        running = f"; {len(robot['streams'])} stream(s), {len(robot['goals'])} goal(s) running"
        lines.append(f"{robot['name']} at {robot['url']}: {state}{running}")
    if snapshot["estop"]["latched"]:
        lines.append("E-STOP is latched on the operator console: acting calls are refused until released.")
    if snapshot["pending"]:
        waiting = ", ".join(f"{p['tool']} on {p['name']}" for p in snapshot["pending"])
        lines.append(f"Waiting for the person's confirmation: {waiting}.")
    for entry in snapshot["audit"][:audit_lines]:
        lines.append(f"{entry['time']} {entry['tool']} {entry['name'] or '-'}: {entry['outcome']}")
    if not snapshot["audit"]:
        lines.append("No acting call yet.")
    return "\n".join(lines)
