"""rosbridge's ``protocol.py``: a connection's input buffer, the checks before an op runs, and the dispatch.

Identical in 0.11.17 and on the ros2 branch, except where a comment names one of them.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Awaitable
from typing import Any

from rosbridge_mcp_server.sim.bridge.core import BridgeCore, OpError, OpHandler, status_frame
from rosbridge_mcp_server.sim.connection import Connection

__all__ = ["MAX_INPUT_BUFFER", "Protocol", "ReadingDied"]

log = logging.getLogger("rosbridge_mcp_server.sim")

#: Our bound on a connection's unparsable input (the real buffer is unbounded); Tornado's frame limit.
MAX_INPUT_BUFFER = 10 * 1024 * 1024

#: Ops that run in a task of their own unless the bridge handles each connection in order.
_DETACHABLE = ("call_service", "send_action_goal")


class ReadingDied(Exception):
    """An input that raises outside rosbridge's per-op error handling: the connection's reading ends."""


class Protocol:
    """Turns frames into ops and hands each op to its handler."""

    def __init__(self, core: BridgeCore, ops: dict[str, OpHandler]) -> None:
        self.core = core
        self.ops = ops

    async def incoming(self, conn: Connection, raw: str | bytes = "") -> None:
        """One frame (or a joined fragment message) from a client, through rosbridge's input buffer.

        ``protocol.incoming`` (identical in 0.11.17 and on the ros2 branch) appends the frame to a
        per-connection buffer, takes the whole buffer if it parses as JSON, else the first ``{...}`` in it
        that parses and has an ``op`` (the text before it is thrown away, the rest kept), and calls itself
        again while something is left that differs from what was left last time. So several objects in one
        frame are all handled, one object split over frames is handled once complete, and garbage waits in
        the buffer until a later frame completes something.
        """
        if conn.dead:
            log.debug("client %d: frame ignored (this connection's reading died earlier)", conn.id)
            conn.frames_ignored += 1
            self.core.world.notify()
            return
        if isinstance(raw, bytes):
            if not self.core.ros2:
                # 0.11.17 appends str(payload) of a binary frame, "b'{...}'"; the brace scan finds the object.
                raw = str(raw)
            else:
                try:
                    raw = raw.decode("utf-8")
                except UnicodeDecodeError:
                    log.error("client %d: a binary frame that is not UTF-8 text; ignored", conn.id)
                    return
        conn.buffer += raw
        if len(conn.buffer) > MAX_INPUT_BUFFER:
            # Our own bound: the real buffer grows without limit (and its scan gets slower and slower).
            log.error("client %d: %d characters of unparsable input dropped", conn.id, len(conn.buffer))
            conn.buffer = ""
            return
        while True:
            found, msg = self._take_message(conn)
            if not found:
                return
            try:
                handled = await self.dispatch(conn, msg)
            except ReadingDied as exc:
                conn.dead = True
                log.error(
                    "client %d: %s - the real server's reading thread dies here; every later frame of this "
                    "connection is ignored (the socket stays open)",
                    conn.id,
                    exc,
                )
                return
            if conn.dead or not handled or not conn.buffer or conn.buffer == conn.old_buffer:
                return
            conn.old_buffer = conn.buffer

    @staticmethod
    def _take_message(conn: Connection) -> tuple[bool, Any]:
        """rosbridge's buffer parse: (whether a message was taken, the message)."""
        text = conn.buffer
        try:
            msg = json.loads(text)
        except ValueError:
            pass
        else:
            conn.buffer = ""
            return msg is not None, msg
        decoder = json.JSONDecoder()
        start = text.find("{")
        while start >= 0:
            # The real server tries every '{' with every '}' after it; the only slice that can parse is the
            # one ending where the object that starts here ends, which is what raw_decode finds.
            try:
                obj, end = decoder.raw_decode(text, start)
            except ValueError:
                start = text.find("{", start + 1)
                continue
            if obj.get("op") is not None:
                conn.buffer = text[end:]
            # An object without an op is handled (and logged) but stays in the buffer, as on the real server.
            return True, obj
        return False, None

    async def dispatch(self, conn: Connection, msg: Any) -> bool:
        """rosbridge's ``protocol.incoming`` after parsing: returns False where it returns early.

        The checks before the op runs are outside the server's error handling: what raises there (a JSON
        value that is not an object, ``png`` without ``msg``, ``message_intervall: null``...) ends the
        connection's reading, modelled by :class:`ReadingDied`.
        """
        if not isinstance(msg, str | list | dict):
            raise ReadingDied(f"argument of type {type(msg).__name__!r} is not iterable: {msg!r}")
        mid = None
        if "id" in msg:
            if not isinstance(msg, dict):
                raise ReadingDied(f"{type(msg).__name__} indices must be integers, got 'id' in {msg!r:.200}")
            mid = msg["id"]
        if "op" not in msg:
            log.error(
                "client %d: Received a message without an op.  All messages require 'op' field with value "
                "one of: %s.  Original message was: %.200s",
                conn.id,
                list(self.ops),
                json.dumps(msg),
            )
            return False
        if not isinstance(msg, dict):
            raise ReadingDied(f"{type(msg).__name__} indices must be integers, got 'op' in {msg!r:.200}")
        op = msg["op"]
        try:
            handler = self.ops.get(op)
        except TypeError as exc:
            raise ReadingDied(f"unhashable op {op!r:.200}") from exc
        if handler is None:
            log.error(
                "client %d: Unknown operation: %s.  Allowed operations: %s", conn.id, op, list(self.ops)
            )
            if self.core.config.rs:
                conn.send(status_frame(f"unknown operation: {op}", mid))
            return False
        if "fragment_size" in msg:
            self._set_fragment_size(conn, msg["fragment_size"])
        if "message_intervall" in msg:
            value = msg["message_intervall"]
            # is_number() is float() catching only ValueError: None, lists and objects raise TypeError.
            if value is None or isinstance(value, list | dict):
                raise ReadingDied(f"float() argument must be a string or a real number: {value!r}")
        if "png" in msg and "msg" not in msg:
            raise ReadingDied("KeyError: 'msg' (a 'png' key without 'msg')")
        detached = op in _DETACHABLE and not self.core.config.in_order
        try:
            result = handler(conn, msg)
            if result is None:
                return True
            if detached:
                self.core.spawn(self._guarded(conn, op, mid, result))
            else:
                await result
        except Exception as exc:
            self._failed(conn, op, mid, exc)
        return True

    async def _guarded(self, conn: Connection, op: str, mid: Any, work: Awaitable[None]) -> None:
        try:
            await work
        except Exception as exc:
            self._failed(conn, op, mid, exc)

    def _failed(self, conn: Connection, op: str, mid: Any, exc: Exception) -> None:
        """rosbridge_suite only logs a failed op; rosbridge-server-rs also answers it with an error status."""
        _log_failure(conn, op, mid, exc)
        if self.core.config.rs:
            conn.send(status_frame(str(exc), mid))

    def _set_fragment_size(self, conn: Connection, value: Any) -> None:
        """Any message carrying ``fragment_size`` sets it for the whole connection.

        The value is kept as sent; :meth:`Connection._fragments` gives it Python's semantics (a string
        breaks every later send on 0.11.17).
        """
        if not self.core.ros2:
            conn.fragment_size = value
            return
        if value is None or not isinstance(value, int | float):
            # ROS 2 ≥ 2.0.2 / 2.4.0 / 3.0.0 compare it with max_message_size outside the error handling.
            raise ReadingDied(f"fragment_size must be a number, got {value!r}")
        limit = self.core.config.max_message_size
        conn.fragment_size = min(value, limit) if limit is not None else value


def _log_failure(conn: Connection, op: str, mid: Any, exc: Exception) -> None:
    """rosbridge's protocol catches every exception of an op and only logs ``"<op>: <error>"``."""
    log.error("client %d: %s: %s (id %s)", conn.id, op, exc, mid)
    if not isinstance(exc, OpError):
        log.debug("traceback of that failure", exc_info=exc)
