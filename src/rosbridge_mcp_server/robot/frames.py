"""Listening to ``/tf`` and ``/tf_static`` until a transform between two frames can be answered.

``/tf_static`` is latched (ROS 1) / transient-local (ROS 2), so its links arrive as soon as we subscribe;
``/tf`` links arrive at the publishers' rates. Both subscriptions are closed afterwards.

A robot under a namespace (``robot/namespaces.py``) has its tf on ``<namespace>/tf`` and
``<namespace>/tf_static`` (its frames unprefixed, as the simulated fleet and most multi-robot Nav2 setups
remap it), or shares the root ``/tf`` with its frames prefixed (``robot2/base_link``): both are handled, a
frame not heard of being looked for under the namespace's prefix too. With no namespace given and no ``/tf``
at the root, the one namespace with a tf is used (several: ``SeveralNamespacesError``).
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

from rosbridge_mcp_server.errors import RequestTimeoutError
from rosbridge_mcp_server.robot.namespaces import SeveralNamespacesError, find_namespace, namespace_name
from rosbridge_mcp_server.robot.occupancy import Pose2D
from rosbridge_mcp_server.robot.transforms import FrameTree, Lookup, TransformError

if TYPE_CHECKING:
    from collections.abc import Callable

    from rosbridge_mcp_server.client import RosbridgeClient
    from rosbridge_mcp_server.robot.graph import RosGraph

__all__ = ["TF_TOPICS", "FoundTransform", "look_up_transform", "planar_pose", "tf_topics"]

TF_TOPICS = ("/tf", "/tf_static")
#: On a tf shared by several robots, how long a look-up waits for the robot's prefixed frames before it
#: answers with a plain frame of that name (another robot's, or one frame all share, such as ``map``).
SHARED_SETTLE = 1.0


def tf_topics(namespace: str) -> tuple[str, str]:
    """``/tf`` and ``/tf_static`` under *namespace* (``""``: the root ones)."""
    return f"{namespace}/tf", f"{namespace}/tf_static"


@dataclass(frozen=True)
class FoundTransform:
    """A look-up and how old its newest moving link was when answered (``None``: static links only)."""

    lookup: Lookup
    age: float | None
    waited: float
    #: The robot's namespace whose tf answered (``""``: the root's), and the sentence saying it was found.
    namespace: str = ""
    note: str | None = None


async def _tf_present(graph: RosGraph, namespace: str) -> dict[str, str]:
    types = {topic: await graph.topic_type(topic) for topic in tf_topics(namespace)}
    return {topic: msg_type for topic, msg_type in types.items() if msg_type}


async def _sources(graph: RosGraph, namespace: str | None) -> tuple[str, dict[str, str], str | None]:
    """(namespace, tf topic → type, note): the robot's tf topics (the root's when it has none of its own),
    found when no namespace is given."""
    wanted = "" if namespace is None else namespace_name(namespace)
    present = await _tf_present(graph, wanted)
    note = None
    if not present and namespace is None:
        found = await find_namespace(graph, None, "/tf", kind="topic", present=False)
        if not found.namespace:
            found = await find_namespace(graph, None, "/tf_static", kind="topic", present=False)
        if found.namespace:
            wanted, note = found.namespace, found.note
            present = await _tf_present(graph, wanted)
    elif not present and wanted:
        present = await _tf_present(graph, "")  # one /tf shared, the robot's frames prefixed
    if not present:
        where = " nor ".join(tf_topics(wanted)) + (" (nor the root's /tf)" if wanted else "")
        raise TransformError(f"Neither {where} is in the ROS graph: nothing publishes transforms.")
    return wanted, present, note


def _named(tree: FrameTree, frame: str, prefix: str, *, shared: bool) -> str:
    """*frame* under the namespace's prefix (``robot2/base_link``) when that is known and the tf is shared
    by several robots (or the plain frame is not known), else *frame*."""
    prefixed = f"{prefix}/{frame.lstrip('/')}"
    known = prefix and not frame.lstrip("/").startswith(f"{prefix}/") and tree.knows(prefixed)
    return prefixed if known and (shared or not tree.knows(frame)) else frame


async def look_up_transform(
    client: RosbridgeClient,
    graph: RosGraph,
    target: str,
    source: str,
    *,
    timeout: float,
    namespace: str | None = "",
) -> FoundTransform:
    """``target ← source`` from the links heard within ``timeout``; else :class:`TransformError`.

    *namespace*: the robot's (``""``: the root's tf; ``None``: found, see the module's docstring)."""
    namespace, present, note = await _sources(graph, namespace)
    prefix = namespace.strip("/")
    shared = bool(namespace) and not any(topic.startswith(f"{namespace}/") for topic in present)
    tree = FrameTree()
    start = time.monotonic()
    settle = start + min(SHARED_SETTLE, timeout) if shared else start
    changed = asyncio.Event()

    async def pump(topic: str, msg_type: str) -> None:
        async with client.subscribe(topic, msg_type, max_queue=100) as sub:
            while True:
                message = await sub.get()
                static = topic.endswith("/tf_static")
                if tree.add_message(message, static=static, received=time.monotonic()):
                    changed.set()

    tasks = [asyncio.create_task(pump(topic, msg_type)) for topic, msg_type in present.items()]

    def names() -> tuple[str, str]:
        return _named(tree, target, prefix, shared=shared), _named(tree, source, prefix, shared=shared)

    try:
        found = await _wait_for(tree, names, changed, tasks, settle=settle, deadline=start + timeout)
    finally:
        for task in tasks:
            task.cancel()
        # Shielded unsubscribes run in each task's own `async with` exit.
        await asyncio.gather(*tasks, return_exceptions=True)
    if isinstance(found, TransformError):
        on = f" on {' and '.join(present)}" if namespace else ""
        raise TransformError(f"Within {timeout:g} s{on}: {found}") from None
    now = time.monotonic()
    age = None if found.newest_received is None else now - found.newest_received
    return FoundTransform(found, age, now - start, namespace, note)


async def planar_pose(
    client: RosbridgeClient,
    graph: RosGraph,
    target: str,
    source: str,
    timeout: float,
    *,
    namespace: str | None = "",
    topic: str = "",
) -> Pose2D | str:
    """Where *source* is in *target* (x, y, yaw) from ``/tf`` and ``/tf_static``, or why it is not known.

    The robot's *namespace*'s tf; with none (``None``) and no tf at the root, the robot's whose namespace
    holds *topic* (``/robot2/map``: ``/robot2/tf``), or the one robot's with a tf."""
    if source == target:
        return Pose2D(0.0, 0.0, 0.0)
    try:
        found = await look_up_transform(client, graph, target, source, timeout=timeout, namespace=namespace)
    except SeveralNamespacesError as exc:
        owners = [ns for ns in exc.namespaces if topic.startswith(f"{ns}/")]
        if not owners:
            return str(exc)
        return await planar_pose(client, graph, target, source, timeout, namespace=max(owners, key=len))
    except TransformError as exc:
        return str(exc)
    return found.lookup.transform.planar()


async def _wait_for(
    tree: FrameTree,
    names: Callable[[], tuple[str, str]],
    changed: asyncio.Event,
    tasks: list[asyncio.Task[None]],
    *,
    settle: float,
    deadline: float,
) -> Lookup | TransformError:
    """The look-up of *names* once the links connect them (a plain frame, not the robot's prefixed one, only
    from *settle* on), else the last reason it could not be made."""
    last_error = TransformError("no link was heard")
    while True:
        wanted = names()
        try:
            found = tree.lookup(*wanted)
        except TransformError as exc:
            last_error = exc
            until = deadline
        else:
            prefixed = all("/" in name for name in wanted)
            if time.monotonic() >= settle or prefixed:
                return found
            until = settle  # a plain frame: the robot's prefixed one may still come
        left = min(until, deadline) - time.monotonic()
        if left <= 0 and time.monotonic() >= deadline:
            return last_error
        changed.clear()
        with contextlib.suppress(TimeoutError):
            async with asyncio.timeout(max(left, 0)):
                await _first_of(changed, tasks)


async def _first_of(changed: asyncio.Event, tasks: list[asyncio.Task[None]]) -> None:
    """Wait for a new link, or for a listener that failed (its error is raised)."""
    waiter = asyncio.create_task(changed.wait())
    try:
        done, _ = await asyncio.wait([waiter, *tasks], return_when=asyncio.FIRST_COMPLETED)
    finally:
        waiter.cancel()
    for task in done:
        if task is not waiter and task.exception() is not None:
            error = task.exception()
            if isinstance(error, RequestTimeoutError):
                continue
            assert error is not None
            raise error
