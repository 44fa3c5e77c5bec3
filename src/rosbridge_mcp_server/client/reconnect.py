"""When the connect loop tries: backoff between attempts, attempts prompted by calls, the last outcome.

Nothing is queued here: a call that finds no connection prompts an attempt and waits for that one attempt
only, then sends its own request or fails (a stale velocity command is a safety bug).
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import math
import random
from typing import Final
from urllib.parse import urlsplit

#: The backoff's jitter, from a generator of its own: the process's shared `random` state is the host's.
_JITTER = random.Random()

__all__ = ["LOCAL_RECONNECT_MAX", "PROMPT_SPACING", "Attempts", "reconnect_cap"]

#: Longest wait between connection attempts to a bridge on this machine or the local network. An attempt there
#: costs a refused connect (or a few packets), so retrying twice a second is cheap, and the robot is back in
#: use within about half a second of its bridge, however long it was gone.
LOCAL_RECONNECT_MAX: Final = 0.5
#: A call that finds no connection prompts an attempt at once, but not sooner than this after the last one
#: ended (it waits out the rest): a burst of calls against a dead bridge costs at most ten attempts a second.
PROMPT_SPACING: Final = 0.1


def reconnect_cap(url: str, reconnect_max: float) -> float:
    """The longest wait between connection attempts for the bridge at *url*.

    Loopback and local-network hosts (private, link-local and unique-local addresses, ``localhost``, names
    ending in ``.local`` or without a dot) get :data:`LOCAL_RECONNECT_MAX`; other hosts *reconnect_max*, so
    a remote bridge is not tried more than every few seconds, while a tool call still prompts an attempt at
    once. Decided from the URL alone (no name lookup).
    """
    host = (urlsplit(url).hostname or "").rstrip(".").lower()
    try:
        address = ipaddress.ip_address(host)
    except ValueError:
        local = host == "localhost" or host.endswith((".localhost", ".local")) or "." not in host
    else:
        local = address.is_loopback or address.is_private or address.is_link_local
    return min(reconnect_max, LOCAL_RECONNECT_MAX) if local else reconnect_max


class Attempts:
    """The connect loop's schedule and what its last attempt left: exponential backoff from *reconnect_min*
    up to *cap*, cut short when a call prompts an attempt."""

    def __init__(self, reconnect_min: float, cap: float) -> None:
        self.reconnect_min = reconnect_min
        self.cap = cap
        #: Why there is no connection (the last attempt's failure or the session's end); None while connected.
        self.last_reason: str | None = "not started"
        # The last attempt got no WebSocket answer in time (a port that accepts but never completes the
        # handshake, a host that drops packets): calls then fail at once instead of each waiting out the
        # connect timeout again, while the loop keeps trying.
        self.timed_out = False
        self._running = False
        self._done: asyncio.Event | None = None
        # Set by a call that finds no connection: the loop stops waiting and tries at once.
        self._wake = asyncio.Event()
        self._last_end = -math.inf
        self._delay = reconnect_min

    def start(self) -> None:
        """The loop is about to run: an attempt counts as under way already, so a call right after start()
        waits for the first attempt instead of failing."""
        self._done = asyncio.Event()
        self._running = True

    def stop(self) -> None:
        """The client is closing: prompts wake nothing any more."""
        self._running = False

    def begin(self) -> asyncio.Event:
        """An attempt starts now; the event is set when it is over (failed, or its session ended)."""
        self._wake.clear()
        if self._done is None or self._done.is_set():
            self._done = asyncio.Event()
        return self._done

    def failed(self, reason: str | None, *, timed_out: bool = False) -> None:
        self.last_reason = reason
        self.timed_out = timed_out

    def succeeded(self) -> None:
        self.last_reason = None
        self.timed_out = False
        self._delay = self.reconnect_min

    def ended(self, done: asyncio.Event, *, served: bool) -> None:
        """The attempt *done* is over; a failed one (not the end of a session) spaces out the next prompt."""
        if not served:
            self._last_end = asyncio.get_running_loop().time()
        done.set()

    async def pause(self) -> None:
        """Wait out the backoff, or less when a call prompts an attempt."""
        sleep = _JITTER.uniform(self._delay / 2, self._delay)
        self._delay = min(self._delay * 2, self.cap)
        # No attempt is in progress while we wait; a call that needs the connection wakes us (see prompt)
        # instead of failing until the backoff runs out.
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(sleep):
                await self._wake.wait()

    def prompt(self) -> asyncio.Event | None:
        """Wake the loop for an attempt now; the event set when it is done (None: not now)."""
        if not self._running:
            return None
        if asyncio.get_running_loop().time() - self._last_end < PROMPT_SPACING:
            return None
        if self._done is None or self._done.is_set():
            self._done = asyncio.Event()
        self._wake.set()
        return self._done

    async def _prompt_when_spaced(self, deadline: float | None) -> asyncio.Event | None:
        """Prompt an attempt; within :data:`PROMPT_SPACING` of a failed one, once the spacing has passed.

        A call that came right after a failed attempt used to fail at once, so a call made just after the
        bridge came back failed when the loop's last refused attempt was under 0.1 s old (a bridge restarted
        at a random moment: about one call in four). It waits out the rest of the spacing instead (at most
        0.1 s, never past *deadline*): the attempt rate stays bounded, and nothing is queued.
        """
        loop = asyncio.get_running_loop()
        rest = self._last_end + PROMPT_SPACING - loop.time()
        if rest > 0 and self._running and (deadline is None or loop.time() + rest < deadline):
            await asyncio.sleep(rest)
            if self._done is not None and not self._done.is_set():
                return self._done  # the loop started an attempt meanwhile
        return self.prompt()

    async def wait_for_one(self, connect_timeout: float, deadline: float | None) -> None:
        """Wait for the attempt under way, or prompt one and wait for it (at most the connect timeout)."""
        attempt = self._done
        if attempt is None or attempt.is_set():
            attempt = await self._prompt_when_spaced(deadline)
        if attempt is None or attempt.is_set():
            return
        # The attempt is bounded by the connect timeout itself; the margin lets it report why it failed.
        until = asyncio.get_running_loop().time() + connect_timeout + 1.0
        if deadline is not None:
            until = min(until, deadline)
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout_at(until):
                await attempt.wait()
