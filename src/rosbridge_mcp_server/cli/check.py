"""``rosbridge-mcp-server check``: a diagnosis of the connection to rosbridge, for a person at a terminal.

It is not the MCP server, so it writes to stdout. It says whether the bridge is reachable (and if not, what to
try), which ROS and distro it runs, whether rosapi answers, and tests what the tools rely on rather than
trusting version names: that a geometry_msgs/Twist passes our check against this rosapi's TypeDefs, whether a
slow service call holds up later calls on its connection (measured with a service of its own, offered for
about a second), and whether an action server's type can be found. Exit code 0 when healthy, 1 when not.
"""

from __future__ import annotations

import asyncio
from fnmatch import fnmatchcase
from typing import TextIO
from urllib.parse import urlsplit

from rosbridge_mcp_server import __version__
from rosbridge_mcp_server.cli.demo import DemoSettings
from rosbridge_mcp_server.client import BridgeCapabilities, Dialect, RosbridgeClient, RosInfo
from rosbridge_mcp_server.client.ordering import call_ordering
from rosbridge_mcp_server.config import Config, plain_text_warning
from rosbridge_mcp_server.errors import NotConnectedError, RosbridgeError
from rosbridge_mcp_server.robot.graph import RosGraph
from rosbridge_mcp_server.robot.messages import find_problems, typedefs_from_rosapi
from rosbridge_mcp_server.robot.names import did_you_mean
from rosbridge_mcp_server.robot.wording import counted
from rosbridge_mcp_server.safety.bridge_globs import bridge_arguments
from rosbridge_mcp_server.safety.policy import Policy

__all__ = ["run_check", "unreachable_advice"]

_OK = "ok  "
_BAD = "FAIL"
_NOTE = "note"
_WARN = "warn"


def unreachable_advice(url: str, reason: str | None) -> list[str]:
    """What to try when nothing answers at ``url``, most likely cause first."""
    parts = urlsplit(url)
    host = parts.hostname or "?"
    secure = parts.scheme == "wss"
    port = parts.port or (443 if secure else 80)
    text = (reason or "").lower()
    advice: list[str] = []
    if "refused" in text or "connect call failed" in text:
        advice.append(f"Nothing listens on {host}:{port}: is rosbridge running, and on this port?")
    elif "name" in text and ("resolution" in text or "not known" in text or "resolve" in text):
        advice.append(f"The host name {host!r} does not resolve: check the spelling, or use the IP address.")
    elif "timed out" in text or "timeout" in text:
        advice.append(
            f"{host}:{port} did not answer in time: check the address, that the robot is on this network, "
            "and that no firewall blocks the port."
        )
    if "invalidstatus" in text or "rejected websocket" in text:
        advice.append(
            f"Something at {host}:{port} answers HTTP but refused the WebSocket upgrade: is this rosbridge's "
            "port, and is the URL path right? rosbridge serves at / unless its url_path is set."
        )
    elif secure and (not text or any(word in text for word in ("ssl", "tls", "certificate", "handshake"))):
        advice.append("The TLS handshake failed: if rosbridge runs without TLS, use ws:// instead of wss://.")
    elif not secure and any(word in text for word in ("invalid http", "valid http", "handshake")):
        advice.append("The server did not answer like a WebSocket server: if it uses TLS, try wss://.")
    advice += [
        "Start rosbridge on the robot: `ros2 launch rosbridge_server rosbridge_websocket_launch.xml` (ROS "
        "2) or `roslaunch rosbridge_server rosbridge_websocket.launch` (ROS 1).",
        f"Check host and port: ROSBRIDGE_HOST / ROSBRIDGE_PORT (or ROSBRIDGE_URL); now {url}. rosbridge's "
        "default port is 9090.",
        f"Check that a firewall lets TCP port {port} through (e.g. `nc -vz {host} {port}`).",
        "Check ws:// versus wss://: rosbridge speaks plain ws:// unless it was started with TLS.",
    ]
    return advice


def _count(number: int, noun: str) -> str:
    return counted(number, noun)


def _features(info: RosInfo) -> list[tuple[str, str]]:
    """What follows from the ROS version alone (the probes below test the rest)."""
    if info.version == 1:
        return [
            (_NOTE, "actions: over actionlib topics (ROS 1 rosbridge has no action ops)"),
            (
                _NOTE,
                "service calls: ROS 1 rosbridge has no timeout field; this server applies its own deadline",
            ),
        ]
    return [
        (_NOTE, "actions: native action ops (send_action_goal; rosbridge 2.0.0 and later)"),
        (
            _NOTE,
            "service calls: this server keeps its own deadline (rosbridge reads the timeout field only from "
            "Humble 2.0.1 / Jazzy 2.2.0 on)",
        ),
    ]


async def _message_check(graph: RosGraph, info: RosInfo) -> tuple[str, str]:
    """Whether a valid geometry_msgs/Twist passes our check against this rosapi's TypeDefs."""
    twist = Dialect.for_version(info.version).message_type("geometry_msgs/Twist")
    try:
        raw = await graph.rosapi("message_details", {"type": twist})
    except RosbridgeError as exc:
        return _NOTE, f"messages: rosapi cannot describe {twist} ({exc}); publish_topic sends unchecked"
    typedefs = typedefs_from_rosapi(raw)
    if not typedefs:
        return _NOTE, f"messages: rosapi does not describe {twist}; publish_topic sends messages unchecked"
    problems = find_problems(
        {"linear": {"x": 0.5}, "angular": {"z": 0.2}}, twist, typedefs, ros_version=info.version
    )
    if problems:
        return (
            _BAD,
            f"messages: a valid {twist} fails our check ({problems[0]}): publish_topic would refuse it",
        )
    listed = raw.get("typedefs") or [{}]
    names = listed[0].get("fieldnames") if isinstance(listed[0], dict) else None
    slots = isinstance(names, list) and bool(names) and all(str(n).startswith("_") for n in names)
    how = " (rosapi names fields _linear, _angular: read as linear, angular)" if slots else ""
    return _OK, f"messages: a {twist} is checked before it is published{how}"


async def _ordering_check(
    config: Config, client: RosbridgeClient, info: RosInfo, caps: BridgeCapabilities
) -> tuple[str, str]:
    """Calls queue behind a slow one or not, measured, and whether the client treats the bridge so."""
    try:
        queued = await call_ordering(
            config.url,
            info.version,
            timeout=max(config.request_timeout, 5.0),
            ssl_context=config.ssl_context(),
            headers=config.headers,
        )
    except (RosbridgeError, TimeoutError, OSError, LookupError, ValueError) as exc:
        return _NOTE, f"could not measure whether calls queue behind a slow one ({type(exc).__name__}: {exc})"
    # The client measures the same in the background after connecting; compare with its conclusion.
    if await client.ordering_known(max(config.request_timeout, 5.0)):
        lanes = not client.calls_share_connection
    else:
        lanes = caps.calls_may_queue
    if info.version == 1:
        how = "rosbridge 0.11 runs each call in a thread of its own"
    elif caps.status_replies:
        how = "from the bridge's status answers"
    else:
        how = "measured on connecting"
    if queued and not lanes:
        return (
            _BAD,
            "a slow service call holds up later calls on its connection, yet this server took the bridge to "
            "run them side by side: its tools would wait behind a slow call",
        )
    if queued:
        return (
            _OK,
            "concurrency: a slow service call holds up later calls on its connection (the bridge handles one "
            "connection strictly in order): this server gives each call a connection of its own",
        )
    if lanes:
        return (
            _NOTE,
            "concurrency: calls on one connection run side by side (measured now), but this server could not "
            "tell and gives each call a connection of its own (safe, a little slower)",
        )
    return (
        _OK,
        f"concurrency: calls on one connection run side by side (measured now; the server knew: {how})",
    )


def _bridge_lines(info: RosInfo, caps: BridgeCapabilities) -> list[tuple[str, str]]:
    """Which bridge this looks like, and how goals are cancelled on it, as judged from its answers."""
    if info.version == 1:
        return [(_NOTE, "cancel path: a goal's cancel is published on <action>/cancel (actionlib)")]
    if caps.status_replies:
        implementation = (
            "implementation: answers a refused op with an error status (rosbridge-server-rs does; "
            "rosbridge_suite never)"
        )
        foreign = (
            "it refused to cancel a goal this connection did not start, so another client's goal is "
            "cancelled by its UUID through <action>/_action/cancel_goal, not by its rosbridge id"
        )
    else:
        implementation = "implementation: answers like rosbridge_suite (no status ops)"
        foreign = (
            "a goal another client started is cancelled by its rosbridge id from any connection, or by its "
            "UUID through <action>/_action/cancel_goal"
        )
    return [
        (_NOTE, implementation),
        (
            _NOTE,
            "cancel path: a goal publish_action started is cancelled on the main connection and on its own "
            f"(each bridge acts on one of them); {foreign}",
        ),
    ]


async def _action_check(graph: RosGraph, info: RosInfo, actions: list[str]) -> tuple[str, str]:
    """Whether the type of an action server can be found, as list_actions needs."""
    if not actions:
        return _NOTE, "action types: no action server to try"
    try:
        found = await graph.action_type(actions[0])
    except RosbridgeError as exc:
        return _NOTE, f"action types: looking up {actions[0]} failed ({exc})"
    if not found:
        return (
            _NOTE,
            f"action types: this bridge cannot tell the type of {actions[0]}; list_actions shows it untyped "
            "and publish_action needs the type from the model",
        )
    return _OK, f"action types: known ({actions[0]} is {found})"


def policy_names_check(policy: Policy, present: dict[str, list[str]]) -> list[tuple[str, str]]:
    """A warning for each allow pattern of *policy* that names nothing on this robot (``present``: the
    names of each kind, e.g. ``{"topics": [...]}``): every act it was written for would be refused.
    Parameters are left out: listing them all costs a call per node."""
    lines: list[tuple[str, str]] = []
    for section, names in present.items():
        allow = getattr(policy, section).allow
        for pattern in allow or ():
            if not any(fnmatchcase(name, pattern) for name in names):
                noun = section.removesuffix("s")
                hint = did_you_mean(pattern, names, cutoff=0.6)
                text = f"policy [{section}] allow {pattern!r} matches no {noun} on this robot"
                lines.append((_WARN, f"{text}, so acts meant for it will be refused.{hint}"))
    return lines


def bridge_glob_lines(policy: Policy, ros_version: int) -> list[str]:
    """The rosbridge launch arguments that hold *policy*'s allow lists at the bridge too, as ``check``'s
    lines (none when the policy has no allow list)."""
    globs = bridge_arguments(policy, ros_version)
    if not globs.arguments:
        return []
    lines = [
        f"[{_NOTE}] rosbridge can refuse what the policy's allow lists do not name by itself too (defence in "
        "depth; docs/deployment.md). Launch it with:",
        f"    {globs.launch(ros_version)}",
    ]
    if ros_version == 2 and "topics_glob" in globs.arguments:
        lines += ["  or, on rosbridge 4.2 and later:", f"    {globs.launch(ros_version, split_topics=True)}"]
    lines += [f"  - {note}" for note in globs.notes]
    lines.append(
        "  - the bridge cannot hold deny lists, velocity caps, confirmations or [navigation]: the server does"
    )
    return [line + "\n" for line in lines]


async def run_check(config: Config, out: TextIO, *, demo: DemoSettings | None = None) -> int:
    """Run the diagnosis against ``config.url`` (the *demo* robot's, with ``--demo``), writing to ``out``; 0
    when healthy, 1 when not."""
    out.write(f"rosbridge-mcp-server {__version__}: checking {config.url}\n")
    if demo is not None:
        _say(out, _NOTE, f"demo mode: this is the built-in simulated ROS {demo.dialect[-1]} robot")
    for line in config.policy.describe():
        _say(out, _NOTE, f"safety {line.strip()}" if not line.startswith(" ") else f"  {line.strip()}")
    warning = plain_text_warning(config.url)
    if warning:
        _say(out, _NOTE, warning)

    async with RosbridgeClient(
        config.url,
        connect_timeout=config.connect_timeout,
        request_timeout=config.request_timeout,
        ssl_context=config.ssl_context(),
        headers=config.headers,
    ) as client:
        try:
            # ros_info() waits for the first connection attempt only, so a refused connection shows at once.
            info = await client.ros_info()
        except NotConnectedError as exc:
            _say(out, _BAD, f"cannot reach rosbridge at {config.url}: {exc.reason or 'no connection'}")
            out.write("What to try:\n")
            for line in unreachable_advice(config.url, exc.reason):
                out.write(f"  - {line}\n")
            return 1
        _say(out, _OK, f"rosbridge reachable at {config.url}")
        distro = info.distro or ("unknown distro" if info.version == 2 else "Melodic/Noetic line")
        _say(out, _OK, f"ROS {info.version} ({distro})")
        out.writelines(bridge_glob_lines(config.policy, info.version))
        return await _check_graph(config, client, info, out)


def _say(out: TextIO, mark: str, text: str) -> None:
    out.write(f"[{mark}] {text}\n")


async def _check_graph(config: Config, client: RosbridgeClient, info: RosInfo, out: TextIO) -> int:
    """What rosapi, the messages, the bridge, call ordering and actions say, the graph counted, and the
    policy's names checked against it; the verdict last."""
    graph = RosGraph(client)
    try:
        topics, services, actions = await asyncio.gather(
            graph.topics(), graph.service_names(), graph.action_names()
        )
    except RosbridgeError as exc:
        _say(out, _BAD, f"rosapi does not answer: {exc}")
        return 1
    _say(out, _OK, "rosapi answers")
    results = _features(info)
    results.append(await _message_check(graph, info))
    caps = await client.capabilities()
    results += _bridge_lines(info, caps)
    results.append(await _ordering_check(config, client, info, caps))
    results.append(await _action_check(graph, info, actions))
    for mark, text in results:
        _say(out, mark, text)
    counts = [
        _count(len(topics), "topic"),
        _count(len(services), "service"),
        _count(len(actions), "action server"),
    ]
    _say(out, _OK, ", ".join(counts))
    present = {"topics": [t.name for t in topics], "services": list(services), "actions": list(actions)}
    warnings = policy_names_check(config.policy, present)
    for mark, text in warnings:
        _say(out, mark, text)
    if any(mark == _BAD for mark, _ in results):
        out.write("Not healthy: see the FAIL lines above.\n")
        return 1
    if warnings:
        out.write("Healthy: the MCP server can use this bridge, but see the warn lines about the policy.\n")
    else:
        out.write("Healthy: the MCP server can use this bridge.\n")
    return 0
