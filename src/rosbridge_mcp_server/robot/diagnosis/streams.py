"""The streams a look listens to: which topics are key (:func:`key_streams`), every topic heard side by side
for the window and the silent ones again (:func:`listening`), and the ``streams`` area's findings
(:func:`stream_findings`)."""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections.abc import AsyncIterator, Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Final

from rosbridge_mcp_server.errors import RosbridgeError
from rosbridge_mcp_server.robot.diagnosis.findings import Finding, Look, Step
from rosbridge_mcp_server.robot.namespaces import namespaces_with

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient, Subscription
    from rosbridge_mcp_server.robot.log_keeper import LogKeeper

__all__ = [
    "AGAIN",
    "BRIDGE_NODES",
    "MAX_STREAMS",
    "TWISTS",
    "Ears",
    "Heard",
    "PubSub",
    "key_streams",
    "listening",
    "others",
    "parent_name",
    "short_type",
    "stream_findings",
    "tf_namespaces",
]

#: At most this many key topics are measured (the most important kinds first).
MAX_STREAMS: Final = 16

_KINDS: Final = {
    "LaserScan": "scan",
    "Odometry": "odom",
    "Imu": "imu",
    "JointState": "joints",
    "CameraInfo": "camera",
    "Image": "camera",
    "CompressedImage": "camera",
}
_KIND_ORDER: Final = ("tf", "scan", "odom", "imu", "joints", "camera")
TWISTS: Final = ("Twist", "TwistStamped")
BRIDGE_NODES: Final = ("/rosbridge_websocket", "/rosapi", "/rosapi_params")
#: topic → (its publishers, its subscribers).
PubSub = Mapping[str, tuple[tuple[str, ...], tuple[str, ...]]]


#: A key stream with a publisher that sent nothing in the window is heard for up to this much longer before it
#: is called silent: a loaded machine or a bridge busy for a moment can hold a healthy stream's messages back
#: (seen: eleven healthy simulated streams silent in 1 s at a load average of 16). So is one that sent one
#: message only (no rate). A look at a healthy robot never waits for it; such a stream costs it once.
AGAIN: Final = 1.0


@dataclass
class Heard:
    """Messages of one subscription in the look, and how long it was heard."""

    topic: str
    times: list[float] = field(default_factory=list)
    messages: list[dict[str, Any]] = field(default_factory=list)
    keep: bool = False
    listened: float = 0.0

    @property
    def rate(self) -> float | None:
        if len(self.times) < 2:
            return None
        span = self.times[-1] - self.times[0]
        return (len(self.times) - 1) / span if span > 0 else None


class Ears:
    """Every topic of a look subscribed at once (:func:`listening`): heard for the window, then the silent
    ones again (:meth:`hear`)."""

    def __init__(self, heard: dict[str, Heard], subs: list[Subscription]) -> None:
        self.heard = heard
        self._subs = subs

    async def hear(self, seconds: float, only: Iterable[str] | None = None) -> None:
        """Record what arrives for *seconds*; with *only*, just those topics, and no longer than until each
        has a rate (two messages)."""
        wanted = None if only is None else set(only)
        chosen = [s for s in self._subs if wanted is None or s.topic in wanted]
        began = time.monotonic()
        end = began + seconds
        enough = asyncio.Event()

        def check() -> None:
            if wanted is not None and all(len(self.heard[s.topic].times) >= 2 for s in chosen):
                enough.set()

        async def drain(sub: Subscription) -> None:
            record = self.heard[sub.topic]
            while (left := end - time.monotonic()) > 0 and not enough.is_set():
                try:
                    msg = await sub.get(left)
                except RosbridgeError:
                    return
                record.times.append(time.monotonic())
                if record.keep:
                    record.messages.append(msg)
                check()

        check()
        await asyncio.gather(*(drain(sub) for sub in chosen))
        spent = time.monotonic() - began
        for sub in chosen:
            self.heard[sub.topic].listened += spent


@contextlib.asynccontextmanager
async def listening(client: RosbridgeClient, topics: Mapping[str, tuple[str, bool]]) -> AsyncIterator[Ears]:
    """Every topic (name → (type, keep the messages)) subscribed at once for a look."""
    heard = {topic: Heard(topic, keep=keep) for topic, (_, keep) in topics.items()}
    async with contextlib.AsyncExitStack() as stack:
        subs: list[Subscription] = []

        async def open_one(topic: str, msg_type: str) -> None:
            sub = client.subscribe(topic, msg_type or None, max_queue=2_000)
            await stack.enter_async_context(sub)
            subs.append(sub)

        results = await asyncio.gather(
            *(open_one(t, ty) for t, (ty, _) in topics.items()), return_exceptions=True
        )
        for result in results:
            if isinstance(result, BaseException) and not isinstance(result, RosbridgeError):
                raise result
        yield Ears(heard, subs)


def short_type(type_name: str) -> str:
    return type_name.rsplit("/", 1)[-1]


def parent_name(name: str) -> str:
    return name.rsplit("/", 1)[0] or "/"


def tf_namespaces(topics: Mapping[str, str]) -> list[str]:
    """The namespaces with a tf of their own (``""``: the root's ``/tf``), root first."""
    names = list(topics)
    found = set(namespaces_with(names, "/tf")) | set(namespaces_with(names, "/tf_static"))
    root = [""] if "/tf" in topics or "/tf_static" in topics else []
    return root + sorted(found)


def key_streams(
    topics: Mapping[str, str], kinds: frozenset[str] | None, left_out: dict[str, int] | None = None
) -> dict[str, str]:
    """topic → kind of the streams worth measuring (how many more there were: *left_out* ``streams``)."""
    chosen: dict[str, str] = {}
    infos = {parent_name(t) for t, ty in topics.items() if short_type(ty) == "CameraInfo"}
    for topic, type_name in topics.items():
        kind = _KINDS.get(short_type(type_name))
        if kind is None or "/_" in topic:
            continue
        if short_type(type_name) in ("Image", "CompressedImage"):
            if parent_name(topic) in infos or parent_name(parent_name(topic)) in infos:
                continue  # its camera_info says the same at a fraction of the bytes
            if short_type(type_name) == "Image" and f"{topic}/compressed" in topics:
                continue
        chosen[topic] = kind
    for namespace in tf_namespaces(topics):
        if f"{namespace}/tf" in topics:
            chosen[f"{namespace}/tf"] = "tf"
    if kinds is not None:
        chosen = {t: k for t, k in chosen.items() if k in kinds}
    ordered = sorted(chosen, key=lambda t: (_KIND_ORDER.index(chosen[t]), t))
    if left_out is not None and len(ordered) > MAX_STREAMS:
        left_out["streams"] = len(ordered) - MAX_STREAMS
    return {t: chosen[t] for t in ordered[:MAX_STREAMS]}


def others(names: Iterable[str]) -> tuple[str, ...]:
    """*names* without the bridge's own nodes."""
    return tuple(n for n in names if n not in BRIDGE_NODES)


def stream_findings(
    keeper: LogKeeper | None,
    *,
    streams: Mapping[str, str],
    heard: Mapping[str, Heard],
    pubsub: PubSub,
    window: float,
    checked: dict[str, str],
) -> list[Finding]:
    out = []
    flowing = 0
    for topic in streams:
        record = heard.get(topic)
        if record is None:
            continue
        pubs = others(pubsub.get(topic, ((), ()))[0])
        rate = record.rate
        before = keeper.rates.get(topic) if keeper is not None else None
        if not record.times:
            if not pubs:
                continue  # nobody publishes it: the graph area says so when someone reads it
            out.append(
                Finding(
                    "problem",
                    "streams",
                    topic,
                    f"{', '.join(pubs[:3])} publish{'es' if len(pubs) == 1 else ''} {topic} but nothing "
                    f"arrived in {round(max(window, record.listened), 1):g} s"
                    + (f" (it ran at {before:.1f} Hz earlier)" if before else "")
                    + ".",
                    (Step(Look.WAIT_MESSAGE, (topic,)), Step(Look.NODE, (pubs[0],))),
                    nodes=pubs,
                    details={"rate_hz": 0.0, "earlier_hz": before},
                )
            )
            continue
        flowing += 1
        if rate is not None and before and rate < before / 2:
            out.append(
                Finding(
                    "warning",
                    "streams",
                    topic,
                    f"{topic} runs at {rate:.1f} Hz, under half the {before:.1f} Hz measured earlier.",
                    (Step(Look.STAMPS, (topic,)),),
                    nodes=pubs,
                    details={"rate_hz": round(rate, 2), "earlier_hz": round(before, 2)},
                )
            )
        if keeper is not None and rate is not None:
            keeper.rates[topic] = rate
    checked["streams"] = f"{flowing} of {len(streams)} key streams flowing in {window:g} s"
    return out
