"""What is wrong with the robot: diagnostics, logs, streams, tf, lifecycle and the graph, looked at at once.

:func:`diagnose` asks rosapi for the topics, nodes and services, then listens to the streams that matter,
``/tf`` and ``/tf_static`` and ``/diagnostics`` side by side for :data:`WINDOW` seconds while it asks every
lifecycle node its state and the graph who publishes and reads the key topics; the log and the diagnostics
since the server connected come from the session's :class:`~rosbridge_mcp_server.robot.log_keeper.LogKeeper`.
Each area becomes :class:`Finding`\\ s (a problem or a warning, what it is about, and what to call next) and a
line of what was checked; an area the robot does not have (no ``/rosout``, no ``/diagnostics``, no lifecycle
services, ROS 1's missing lifecycle) says so and the others are reported.

The areas:

* ``diagnostics``: the latest status per name and hardware id: ERROR is a problem, WARN and STALE warnings;
* ``logs``: errors (problems) and warnings since the server connected, folded;
* ``streams``: the sensors, odometry, joint states, camera (its ``camera_info`` when it has one, else the
  image, compressed when offered) and ``/tf``: a topic a node publishes that sends nothing in the window is a
  problem; a rate under half the one this session measured before a warning;
* ``tf``: dynamic transforms stamped over a second before the newest one, a frame with two parents, no path
  along map → odom → base (``base_footprint`` or ``base_link``), for the root's ``/tf`` and for each robot's
  namespace with its own (``/robot2/tf``, ``robot/namespaces.py``), each tree on its own;
* ``lifecycle`` (ROS 2): every node offering ``get_state`` that is not active is a problem;
* ``graph``: nodes gone since the last look (the first look is when the server connected), a ``cmd_vel``
  nobody reads (nothing drives), a key stream a node reads that nobody publishes;
* ``arm`` (where ros2_control's ``…/list_controllers`` is served): a controller not active is a problem, a
  joint at a limit of the URDF (``/robot_description``, fingers left out) a warning (``robot/arm/health.py``);
  a silent ``/joint_states`` is the streams area's.
"""

from __future__ import annotations

import asyncio
import contextlib
import enum
import itertools
import time
from collections import Counter
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, Final, Literal

from rosbridge_mcp_server.errors import Advice, Advised, RosbridgeError
from rosbridge_mcp_server.robot.arm.controllers import Controller, list_controllers
from rosbridge_mcp_server.robot.arm.health import controller_faults, limit_faults
from rosbridge_mcp_server.robot.diagnostics import StatusBoard
from rosbridge_mcp_server.robot.log_keeper import DIAGNOSTICS_TOPICS
from rosbridge_mcp_server.robot.logs import level_rank
from rosbridge_mcp_server.robot.namespaces import namespaces_with
from rosbridge_mcp_server.robot.nodes import node_names
from rosbridge_mcp_server.robot.text import NAME_CHARS, is_frame_name, is_graph_name, shown
from rosbridge_mcp_server.robot.wording import counted

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient, Subscription
    from rosbridge_mcp_server.robot.graph import RosGraph
    from rosbridge_mcp_server.robot.log_keeper import LogKeeper

__all__ = [
    "AREAS",
    "FOCUSES",
    "WINDOW",
    "Diagnosis",
    "Finding",
    "Look",
    "Step",
    "UnknownFocusError",
    "areas_for",
    "diagnose",
]

#: Seconds the streams, tf and diagnostics are listened to.
WINDOW: Final = 1.0
#: A dynamic transform stamped this long before the newest one is stale.
STALE_TRANSFORM: Final = 1.0
AREAS: Final = ("graph", "lifecycle", "diagnostics", "streams", "tf", "logs", "arm")
#: What a ``focus`` narrows to: areas, and for ``navigation`` and ``sensors`` the kinds of streams.
FOCUSES: Final[dict[str, tuple[tuple[str, ...], frozenset[str] | None]]] = {
    "navigation": (("graph", "lifecycle", "streams", "tf", "logs"), frozenset({"scan", "odom", "tf"})),
    "sensors": (("diagnostics", "streams"), None),
    **{area: ((area,), None) for area in AREAS},
    "arm": (("arm", "streams"), frozenset({"joints"})),
}
#: At most this many key topics are measured (the most important kinds first).
MAX_STREAMS: Final = 16
MAX_LOG_FINDINGS: Final = 5
MAX_STATUS_FINDINGS: Final = 20

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
_TWISTS: Final = ("Twist", "TwistStamped")
_BRIDGE_NODES: Final = ("/rosbridge_websocket", "/rosapi", "/rosapi_params")
_ACTIVE: Final = 3


class UnknownFocusError(Advised, ValueError):
    """A ``focus`` that is no area, no focus word and no node of the graph."""


class Look(enum.Enum):
    """What to look at next about a finding; the diagnose tool says which call does it."""

    #: A node's log, from info up (names: the node).
    NODE_LOG = enum.auto()
    #: The whole log, from info up (instead of a node's, when the node's name cannot go into a call).
    LOG = enum.auto()
    #: The nodes of the graph.
    NODES = enum.auto()
    #: Who publishes and reads a topic (names: the topic).
    TOPIC = enum.auto()
    #: How a lifecycle node is activated, in words: an act on the robot, never a call built from its name.
    ACTIVATE = enum.auto()
    #: One node's topics and services (names: the node; none: the node named before).
    NODE = enum.auto()
    #: One message of a topic (names: the topic).
    ONE_MESSAGE = enum.auto()
    #: A message of a topic, waiting a while for it (names: the topic).
    WAIT_MESSAGE = enum.auto()
    #: A topic's stamps over a few seconds (names: the topic).
    STAMPS = enum.auto()
    #: One transform (names: target frame, source frame).
    TRANSFORM = enum.auto()
    #: One transform, waiting a while for it (names: target frame, source frame).
    TRANSFORM_WAIT = enum.auto()
    #: A diagnostics topic's messages until every status on it has come round (names: the topic, how many
    #: statuses it carries): publishers take turns on one topic, so one message is most likely another's OK.
    STATUSES = enum.auto()
    #: The arm: its joints, limits, state and controllers.
    ARM = enum.auto()
    #: Activate a controller through its controller manager (names: the manager, the controller).
    ACTIVATE_CONTROLLER = enum.auto()


@dataclass(frozen=True)
class Step:
    """One thing to look at next: what, the names it involves, and why (said after it, may be empty)."""

    look: Look
    names: tuple[str, ...] = ()
    why: str = ""


@dataclass(frozen=True)
class Finding:
    """One thing wrong: a problem or a warning, its area, what it is about (a topic, frame pair, node or
    status name), one sentence, what to look at next, the nodes it concerns, and details."""

    severity: Literal["problem", "warning"]
    area: str
    subject: str
    summary: str
    next: tuple[Step, ...]
    nodes: tuple[str, ...] = ()
    details: dict[str, Any] = field(default_factory=dict)


@dataclass
class Diagnosis:
    """The findings, the worst first, what each area checked (or why it could not), and how long it took."""

    findings: list[Finding]
    checked: dict[str, str]
    unavailable: dict[str, str]
    seconds: float
    streams: dict[str, float | None] = field(default_factory=dict)
    frames: list[str] = field(default_factory=list)
    #: How many more of an area's things were left out of its findings: "diagnostics" statuses not OK,
    #: "logs" groups of warnings and errors (the tool says where to read them).
    left_out: dict[str, int] = field(default_factory=dict)

    @property
    def problems(self) -> int:
        return sum(1 for f in self.findings if f.severity == "problem")

    @property
    def warnings(self) -> int:
        return sum(1 for f in self.findings if f.severity == "warning")


def areas_for(
    focus: str | None, nodes: Iterable[str]
) -> tuple[tuple[str, ...], frozenset[str] | None, str | None]:
    """(areas, stream kinds or None for all, node or None) for *focus*; :class:`UnknownFocusError` names the
    choices."""
    if not focus:
        return AREAS, None, None
    wanted = focus.strip()
    if wanted.lower() in FOCUSES:
        areas, kinds = FOCUSES[wanted.lower()]
        return areas, kinds, None
    node = wanted if wanted.startswith("/") else f"/{wanted}"
    known = set(nodes)
    if node in known:
        return AREAS, None, node
    raise UnknownFocusError(
        f"focus {focus!r} is neither one of {', '.join(FOCUSES)} nor a node of the graph (e.g. "
        f"{', '.join(sorted(known)[:3]) or '/amcl'})"
    ).advise(Advice.NODES)


# --- the look --------------------------------------------------------------------------------------------


@dataclass
class _Heard:
    """Messages of one subscription in the window."""

    topic: str
    times: list[float] = field(default_factory=list)
    messages: list[dict[str, Any]] = field(default_factory=list)
    keep: bool = False

    @property
    def rate(self) -> float | None:
        if len(self.times) < 2:
            return None
        span = self.times[-1] - self.times[0]
        return (len(self.times) - 1) / span if span > 0 else None


async def _listen(
    client: RosbridgeClient, topics: Mapping[str, tuple[str, bool]], window: float
) -> dict[str, _Heard]:
    """Every topic (name → (type, keep the messages)) at once for *window* seconds."""
    heard = {topic: _Heard(topic, keep=keep) for topic, (_, keep) in topics.items()}
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
        end = time.monotonic() + window

        async def drain(sub: Subscription) -> None:
            record = heard[sub.topic]
            while True:
                left = end - time.monotonic()
                if left <= 0:
                    return
                try:
                    msg = await sub.get(left)
                except RosbridgeError:
                    return
                record.times.append(time.monotonic())
                if record.keep:
                    record.messages.append(msg)

        await asyncio.gather(*(drain(sub) for sub in subs))
    return heard


def _short(type_name: str) -> str:
    return type_name.rsplit("/", 1)[-1]


def _parent(name: str) -> str:
    return name.rsplit("/", 1)[0] or "/"


def _tf_namespaces(topics: Mapping[str, str]) -> list[str]:
    """The namespaces with a tf of their own (``""``: the root's ``/tf``), root first."""
    names = list(topics)
    found = set(namespaces_with(names, "/tf")) | set(namespaces_with(names, "/tf_static"))
    root = [""] if "/tf" in topics or "/tf_static" in topics else []
    return root + sorted(found)


def _key_streams(
    topics: Mapping[str, str], kinds: frozenset[str] | None, left_out: dict[str, int] | None = None
) -> dict[str, str]:
    """topic → kind of the streams worth measuring (how many more there were: *left_out* ``streams``)."""
    chosen: dict[str, str] = {}
    infos = {_parent(t) for t, ty in topics.items() if _short(ty) == "CameraInfo"}
    for topic, type_name in topics.items():
        kind = _KINDS.get(_short(type_name))
        if kind is None or "/_" in topic:
            continue
        if _short(type_name) in ("Image", "CompressedImage"):
            if _parent(topic) in infos or _parent(_parent(topic)) in infos:
                continue  # its camera_info says the same at a fraction of the bytes
            if _short(type_name) == "Image" and f"{topic}/compressed" in topics:
                continue
        chosen[topic] = kind
    for namespace in _tf_namespaces(topics):
        if f"{namespace}/tf" in topics:
            chosen[f"{namespace}/tf"] = "tf"
    if kinds is not None:
        chosen = {t: k for t, k in chosen.items() if k in kinds}
    ordered = sorted(chosen, key=lambda t: (_KIND_ORDER.index(chosen[t]), t))
    if left_out is not None and len(ordered) > MAX_STREAMS:
        left_out["streams"] = len(ordered) - MAX_STREAMS
    return {t: chosen[t] for t in ordered[:MAX_STREAMS]}


async def diagnose(
    client: RosbridgeClient,
    graph: RosGraph,
    keeper: LogKeeper | None,
    *,
    focus: str | None = None,
    window: float = WINDOW,
    namespace: str | None = None,
) -> Diagnosis:
    """Look at the robot once (see the module docstring); :class:`UnknownFocusError` for a bad *focus*.

    *namespace* (``""``: the root) narrows the streams and tf to one robot of several on the bridge."""
    began = time.monotonic()
    dialect = await graph.dialect()
    entries, listed = await asyncio.gather(graph.topics(), node_names(graph))
    # Names the robot's graph gives are robot text: shown escaped and capped (a real name is unchanged).
    topics = {shown(e.name, NAME_CHARS): shown(e.type, NAME_CHARS) for e in entries}
    nodes = [shown(node, NAME_CHARS) for node in listed]
    #: The names a suggested call may use: those of the graph, now or at the last look.
    known = {*nodes, *topics, *(keeper.nodes_seen or () if keeper is not None else ())}
    areas, kinds, focus_node = areas_for(focus, nodes)
    ros2 = dialect.version == 2
    checked: dict[str, str] = {}
    left_out: dict[str, int] = {}
    unavailable: dict[str, str] = {}
    findings: list[Finding] = []
    frames: set[str] = set()

    tf_spaces = _tf_namespaces(topics)
    streams_of = topics
    if namespace is not None:
        tf_spaces = [space for space in tf_spaces if space == namespace]
        if namespace:
            streams_of = {t: ty for t, ty in topics.items() if t.startswith(f"{namespace}/")}
    streams = _key_streams(streams_of, kinds, left_out) if "streams" in areas or "tf" in areas else {}
    if "streams" not in areas:
        streams = {t: k for t, k in streams.items() if k == "tf"}
        left_out.pop("streams", None)
    listen: dict[str, tuple[str, bool]] = {t: (topics[t], k == "tf") for t, k in streams.items()}
    if "tf" in areas:
        for space in tf_spaces:
            for topic in (f"{space}/tf", f"{space}/tf_static"):
                if topic in topics:
                    listen[topic] = (topics[topic], True)
    if "diagnostics" in areas:
        for topic in DIAGNOSTICS_TOPICS:
            if topic in topics:
                listen[topic] = (topics[topic], True)
    if "arm" in areas:
        for topic in _ARM_TOPICS:
            if topic in topics:
                listen[topic] = (topics[topic], True)

    async def details(wanted: list[str]) -> dict[str, tuple[tuple[str, ...], tuple[str, ...]]]:
        found = await asyncio.gather(*(graph.topic_details(t) for t in wanted), return_exceptions=True)
        out = {}
        for topic, got in zip(wanted, found, strict=True):
            if not isinstance(got, BaseException):
                out[topic] = (_names(got.publishers), _names(got.subscribers))
        return out

    drives = [t for t in topics if t.rsplit("/", 1)[-1] == "cmd_vel" and _short(topics[t]) in _TWISTS]

    async def lifecycle() -> dict[str, str] | None:
        if "lifecycle" not in areas or not ros2:
            return None
        services = await graph.service_names()
        getters = [s for s in services if s.endswith("/get_state") and is_graph_name(s)]
        if focus_node is not None:
            getters = [s for s in getters if s == f"{focus_node}/get_state"]

        async def state(service: str) -> str:
            try:
                values = await client.call_service(service, {}, timeout=window + 1.0)
            except RosbridgeError as exc:
                return f"no answer ({shown(exc, 300)})"
            current = values.get("current_state", {}) if isinstance(values, dict) else {}
            label = current.get("label") if isinstance(current, dict) else None
            ident = current.get("id") if isinstance(current, dict) else None
            if ident == _ACTIVE:
                return "active"
            return shown(label or ident or "unknown", 60)

        states = await asyncio.gather(*(state(s) for s in getters))
        return {s.removesuffix("/get_state"): st for s, st in zip(getters, states, strict=True)}

    # Who publishes and reads a stream is asked only of the silent ones, after the look (a healthy robot's
    # look costs no more rosapi calls than the cmd_vel topics'; ROS 1 would open a lane for each).
    heard, pubsub, states, arm = await asyncio.gather(
        _listen(client, listen, window),
        details(drives if "graph" in areas else []),
        lifecycle(),
        _controllers(client, graph, window) if "arm" in areas else _nothing(),
    )
    silent = [t for t in streams if t in heard and not heard[t].times]
    if silent and ("graph" in areas or "streams" in areas):
        pubsub = {**pubsub, **await details(silent)}

    if "graph" in areas:
        findings += _graph(
            keeper, nodes=nodes, topics=topics, pubsub=pubsub, streams=streams, checked=checked
        )
    if "lifecycle" in areas:
        if not ros2:
            unavailable["lifecycle"] = "ROS 1 has no lifecycle nodes"
        elif not states:
            unavailable["lifecycle"] = "no node offers lifecycle services (get_state)"
        else:
            findings += _lifecycle(states, checked)
    if "diagnostics" in areas:
        board = keeper.board if keeper is not None else StatusBoard()
        for topic in DIAGNOSTICS_TOPICS:
            if topic in heard:
                for at, msg in zip(heard[topic].times, heard[topic].messages, strict=True):
                    board.add_message(msg, topic, time.time() - (time.monotonic() - at))
        if not any(t in topics for t in DIAGNOSTICS_TOPICS):
            unavailable["diagnostics"] = "the robot has no /diagnostics topic"
        else:
            findings += _diagnostics(board, checked, left_out)
    if "streams" in areas:
        findings += _streams(
            keeper, streams=streams, heard=heard, pubsub=pubsub, window=window, checked=checked
        )
    if "tf" in areas:
        if not tf_spaces and namespace:
            unavailable["tf"] = f"the robot has no {namespace}/tf or {namespace}/tf_static topic"
        elif not tf_spaces:
            unavailable["tf"] = "the robot has no /tf or /tf_static topic, at the root or under a namespace"
        else:
            frames = _tf_trees(
                heard, topics=topics, namespaces=tf_spaces, window=window, checked=checked, findings=findings
            )
    if "logs" in areas:
        if keeper is None or keeper.absent:
            unavailable["logs"] = "the robot has no /rosout topic"
        elif keeper.source is None:
            unavailable["logs"] = (
                "the log subscription is not open yet (the server connects in the background)"
            )
        else:
            findings += _logs(keeper, checked, left_out)
    if "arm" in areas:
        findings += _arm(arm, heard, checked, unavailable, asked=focus is not None)
    if focus_node is not None:
        findings = [f for f in findings if focus_node in f.nodes or f.subject == focus_node]
    findings = [_checked_steps(f, known) for f in findings]
    order = {area: i for i, area in enumerate(AREAS)}
    findings.sort(key=lambda f: (f.severity != "problem", order.get(f.area, 99)))
    rates = {t: heard[t].rate if t in heard else None for t in streams}
    diagnosis = Diagnosis(
        findings, checked, unavailable, time.monotonic() - began, streams=rates, left_out=left_out
    )
    diagnosis.frames = sorted(frames)
    return diagnosis


def _names(names: Iterable[str]) -> tuple[str, ...]:
    return tuple(shown(name, NAME_CHARS) for name in names)


#: The looks whose names are graph names (nodes, topics); the transforms' are tf frames.
_FRAME_LOOKS: Final = frozenset({Look.TRANSFORM, Look.TRANSFORM_WAIT})


def _checked_steps(finding: Finding, known: set[str]) -> Finding:
    """*finding* with only the steps whose names may go into a call: a graph name the graph has (*known*)
    and that passes the strict check, or a plain frame name. Anyone on the graph writes the names a log line
    or a transform carries; such a name is shown, never made into a call (a node's log then becomes the whole
    log; a step left with nothing becomes ``list_nodes``)."""

    def usable(step: Step) -> bool:
        if step.look in _FRAME_LOOKS:
            return all(is_frame_name(name) for name in step.names)
        if step.look is Look.ACTIVATE_CONTROLLER:  # (the manager, a controller's plain name: said in words)
            manager, controller = step.names
            return is_graph_name(manager) and manager in known and is_graph_name(f"/{controller}")
        if step.look is Look.STATUSES:  # (topic, how many statuses it carries: our count, not robot text)
            topic, count = step.names
            return is_graph_name(topic) and topic in known and count.isdigit()
        return all(is_graph_name(name) and name in known for name in step.names)

    steps = tuple(
        step if usable(step) else Step(Look.LOG, (), step.why) if step.look is Look.NODE_LOG else None
        for step in finding.next
    )
    kept = tuple(step for step in steps if step is not None) or (Step(Look.NODES),)
    return finding if kept == finding.next else replace(finding, next=kept)


# --- the areas ---------------------------------------------------------------------------------------------

#: What the arm area listens to: the URDF (latched) and the joint state.
_ARM_TOPICS: Final = ("/robot_description", "/joint_states")
_Controllers = tuple[str, tuple[Controller, ...] | str] | None


async def _nothing() -> None:
    return None


async def _controllers(client: RosbridgeClient, graph: RosGraph, window: float) -> _Controllers:
    """(the manager, its controllers or why they could not be read); ``None`` without a controller manager."""
    services = [s for s in await graph.service_names() if s.endswith("/list_controllers")]
    if not services:
        return None
    manager = min(services, key=lambda s: (s != "/controller_manager/list_controllers", s))
    manager = manager.removesuffix("/list_controllers")
    try:
        return manager, await list_controllers(client, manager, timeout=window + 1.0)
    except RosbridgeError as exc:
        return manager, f"list_controllers failed ({str(exc)[:120]})"


def _arm(
    arm: _Controllers,
    heard: Mapping[str, _Heard],
    checked: dict[str, str],
    unavailable: dict[str, str],
    *,
    asked: bool,
) -> list[Finding]:
    description, states = (
        heard[t].messages[-1] if t in heard and heard[t].messages else None for t in _ARM_TOPICS
    )
    if arm is None and states is None:
        if asked:
            unavailable["arm"] = "no controller manager (…/list_controllers) and no /joint_states"
        return []
    out: list[Finding] = []
    parts = []
    if arm is not None:
        manager, controllers = arm
        if isinstance(controllers, str):
            parts.append(controllers)
        else:
            active = sum(1 for c in controllers if c.active)
            parts.append(f"{active} of {len(controllers)} controllers active")
            for fault in controller_faults(manager, controllers):
                steps = (Step(Look.ACTIVATE_CONTROLLER, (manager, fault.subject)), Step(Look.ARM))
                out.append(
                    Finding("problem", "arm", fault.subject, fault.summary, steps, (manager,), fault.details)
                )
    limits, what = limit_faults(description.get("data") if isinstance(description, dict) else None, states)
    parts.append(what)
    out += [Finding("warning", "arm", f.subject, f.summary, (Step(Look.ARM),), (), f.details) for f in limits]
    checked["arm"] = "; ".join(parts)
    return out


def _others(names: Iterable[str]) -> tuple[str, ...]:
    return tuple(n for n in names if n not in _BRIDGE_NODES)


def _graph(
    keeper: LogKeeper | None,
    *,
    nodes: list[str],
    topics: Mapping[str, str],
    pubsub: Mapping[str, tuple[tuple[str, ...], tuple[str, ...]]],
    streams: Mapping[str, str],
    checked: dict[str, str],
) -> list[Finding]:
    out: list[Finding] = []
    now = set(nodes)
    if keeper is not None and keeper.nodes_seen is not None:
        since = time.strftime("%H:%M:%S", time.localtime(keeper.nodes_seen_at or time.time()))
        for node in sorted(keeper.nodes_seen - now):
            out.append(
                Finding(
                    "problem",
                    "graph",
                    node,
                    f"Node {node} is gone: in the graph at {since}, not now (crashed? stopped?).",
                    (Step(Look.NODE_LOG, (node,), "for its last words"), Step(Look.NODES)),
                    nodes=(node,),
                    details={"seen_at": since},
                )
            )
        keeper.nodes_seen, keeper.nodes_seen_at = now, time.time()
    for topic, (pubs, subs) in pubsub.items():
        if topic.rsplit("/", 1)[-1] == "cmd_vel" and _short(topics.get(topic, "")) in _TWISTS:
            if not _others(subs):
                out.append(
                    Finding(
                        "problem",
                        "graph",
                        topic,
                        f"Nothing reads {topic}: no node would drive the robot (is the base driver or "
                        "twist_mux running?).",
                        (Step(Look.TOPIC, (topic,)),),
                        nodes=_others(pubs),
                    )
                )
        elif topic in streams and not _others(pubs) and _others(subs):
            readers = _others(subs)
            out.append(
                Finding(
                    "problem",
                    "graph",
                    topic,
                    f"Nobody publishes {topic}, which {', '.join(readers[:4])} read.",
                    (Step(Look.TOPIC, (topic,)), Step(Look.NODES)),
                    nodes=readers,
                )
            )
    checked["graph"] = f"{counted(len(nodes), 'node')}, {counted(len(topics), 'topic')}"
    return out


def _lifecycle(states: Mapping[str, str], checked: dict[str, str]) -> list[Finding]:
    out = []
    for node, state in sorted(states.items()):
        if state == "active":
            continue
        summary = (
            f"Lifecycle node {node} did not answer get_state: {state.removeprefix('no answer (')[:-1]}"
            if state.startswith("no answer (")
            else f"Lifecycle node {node} is {state}, not active: it does none of its work."
        )
        out.append(
            Finding(
                "problem",
                "lifecycle",
                node,
                summary,
                (Step(Look.NODE_LOG, (node,), "for why"), Step(Look.ACTIVATE)),
                nodes=(node,),
                details={"state": state},
            )
        )
    active = sum(1 for s in states.values() if s == "active")
    checked["lifecycle"] = f"{active} of {len(states)} lifecycle nodes active"
    return out


def _diagnostics(board: StatusBoard, checked: dict[str, str], left_out: dict[str, int]) -> list[Finding]:
    out = []
    statuses = board.statuses()
    not_ok = [s for s in statuses if s.level != 0]
    on_topic = Counter(s.topic for s in statuses)
    for status in not_ok[:MAX_STATUS_FINDINGS]:
        severity: Literal["problem", "warning"] = "problem" if status.level == 2 else "warning"
        hardware = f" ({status.hardware_id})" if status.hardware_id else ""
        values = ", ".join(f"{k}: {v}" for k, v in status.values[:3])
        ago = max(0.0, time.time() - status.received)
        out.append(
            Finding(
                severity,
                "diagnostics",
                status.name,
                f"{status.level_name} {status.name}{hardware}: {status.message or '(no message)'}"
                + (f" [{values}]" if values else "")
                + f" ({ago:.0f} s ago)",
                (Step(Look.STATUSES, (status.topic, str(on_topic[status.topic]))),),
                nodes=(_status_node(status.name),),
                details={
                    "level": status.level_name,
                    "hardware_id": status.hardware_id,
                    "message": status.message,
                    "values": dict(status.values),
                },
            )
        )
    if statuses:
        ok = len(statuses) - len(not_ok)
        more = len(not_ok) - MAX_STATUS_FINDINGS
        checked["diagnostics"] = f"{counted(len(statuses), 'status', 'statuses')}, {ok} OK"
        if more > 0:
            left_out["diagnostics"] = more
    else:
        checked["diagnostics"] = "no status has arrived yet"
    return out


def _status_node(name: str) -> str:
    """diagnostic_updater names a status ``node: task``: the node, for a focus on it."""
    node = name.split(":", 1)[0].strip()
    return node if node.startswith("/") else f"/{node}"


def _streams(
    keeper: LogKeeper | None,
    *,
    streams: Mapping[str, str],
    heard: Mapping[str, _Heard],
    pubsub: Mapping[str, tuple[tuple[str, ...], tuple[str, ...]]],
    window: float,
    checked: dict[str, str],
) -> list[Finding]:
    out = []
    flowing = 0
    for topic in streams:
        record = heard.get(topic)
        if record is None:
            continue
        pubs = _others(pubsub.get(topic, ((), ()))[0])
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
                    f"arrived in {window:g} s"
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


@dataclass
class _Edge:
    parent: str
    static: bool
    stamp: float | None


def _seconds(stamp: Any) -> float | None:
    if not isinstance(stamp, Mapping):
        return None
    sec = stamp.get("sec", stamp.get("secs"))
    nsec = stamp.get("nanosec", stamp.get("nsecs", 0))
    if isinstance(sec, int | float) and isinstance(nsec, int | float):
        return float(sec) + float(nsec) / 1e9
    return None


def _edges(heard: Mapping[str, _Heard], namespace: str = "") -> tuple[dict[str, _Edge], dict[str, set[str]]]:
    """child → its latest edge, and child → every parent seen, on *namespace*'s tf."""
    edges: dict[str, _Edge] = {}
    parents: dict[str, set[str]] = {}
    for topic in (f"{namespace}/tf_static", f"{namespace}/tf"):
        record = heard.get(topic)
        if record is None:
            continue
        for msg in record.messages:
            for t in msg.get("transforms") or []:
                if not isinstance(t, Mapping):
                    continue
                got = t.get("header")
                header: Mapping[str, Any] = got if isinstance(got, Mapping) else {}
                parent = shown(header.get("frame_id", ""), NAME_CHARS).lstrip("/")
                child = shown(t.get("child_frame_id", ""), NAME_CHARS).lstrip("/")
                if not parent or not child:
                    continue
                parents.setdefault(child, set()).add(parent)
                stamp = _seconds(header.get("stamp"))
                old = edges.get(child)
                if old is None or old.stamp is None or (stamp is not None and stamp >= old.stamp):
                    edges[child] = _Edge(parent, topic.endswith("/tf_static"), stamp)
    return edges, parents


def _ancestors(frame: str, edges: Mapping[str, _Edge]) -> list[str]:
    chain = [frame]
    while chain[-1] in edges and len(chain) < 100:
        parent = edges[chain[-1]].parent
        if parent in chain:
            break
        chain.append(parent)
    return chain


def _tf_trees(
    heard: Mapping[str, _Heard],
    *,
    topics: Mapping[str, str],
    namespaces: list[str],
    window: float,
    checked: dict[str, str],
    findings: list[Finding],
) -> set[str]:
    """Each namespace's tf tree looked at on its own (its findings say whose tf), the frames seen."""
    frames: set[str] = set()
    said: list[str] = []
    for namespace in namespaces:
        own = {t: ty for t, ty in topics.items() if namespace and t.startswith(f"{namespace}/")}
        found, seen, what = _tf(heard, own if namespace else topics, window, namespace)
        findings += found
        frames |= {f"{namespace}:{frame}" if namespace else frame for frame in seen}
        said.append(f"{namespace}/tf: {what}" if namespace or len(namespaces) > 1 else what)
    checked["tf"] = "; ".join(said)
    return frames


def _tf(
    heard: Mapping[str, _Heard], topics: Mapping[str, str], window: float, namespace: str = ""
) -> tuple[list[Finding], set[str], str]:
    """One tf tree (the root's, or a namespace's): findings, frames, and what was checked."""
    out: list[Finding] = []
    edges, parents = _edges(heard, namespace)
    tf_topic = f"{namespace}/tf"
    whose = f" (tf of {namespace})" if namespace else ""
    ns = (namespace,) if namespace else ()
    frames = set(edges) | {e.parent for e in edges.values()}
    for child, found in sorted(parents.items()):
        if len(found) > 1:
            out.append(
                Finding(
                    "problem",
                    "tf",
                    child,
                    f"Frame {child} has {len(found)} parents ({', '.join(sorted(found))}): two nodes publish "
                    f"it, and tf keeps jumping between them{whose}.",
                    (Step(Look.TOPIC, (tf_topic,), "to see who publishes"),),
                )
            )
    stamps = [e.stamp for e in edges.values() if not e.static and e.stamp is not None]
    newest = max(stamps, default=None)
    if newest is not None:
        for child, edge in sorted(edges.items()):
            if edge.static or edge.stamp is None or newest - edge.stamp <= STALE_TRANSFORM:
                continue
            out.append(
                Finding(
                    "problem",
                    "tf",
                    f"{namespace}{' ' if namespace else ''}{edge.parent} -> {child}",
                    f"Transform {edge.parent} → {child} is stale: stamped {newest - edge.stamp:.1f} s before "
                    f"the newest transform{whose}.",
                    (Step(Look.TRANSFORM, (edge.parent, child, *ns)),),
                )
            )
    base = next((f for f in ("base_footprint", "base_link") if f in frames), None)
    has_map = any(t.rsplit("/", 1)[-1] == "map" and _short(ty) == "OccupancyGrid" for t, ty in topics.items())
    has_odometry = any(_short(ty) == "Odometry" for ty in topics.values())
    chain = [f for f, expected in (("map", has_map), ("odom", has_odometry)) if f in frames or expected]
    if base is None and "odom" in frames:
        out.append(
            Finding(
                "problem",
                "tf",
                f"{namespace}{' ' if namespace else ''}odom -> base",
                f"No base frame (base_footprint or base_link) in tf{whose}: the robot's own frame is "
                "missing.",
                (Step(Look.TRANSFORM_WAIT, ("odom", "base_link", *ns)),),
            )
        )
    if base is not None:
        chain.append(base)
    for upper, lower in itertools.pairwise(chain):
        if upper in _ancestors(lower, edges):
            continue
        subject = f"{namespace}{' ' if namespace else ''}{upper} -> {lower}"
        if any(f.subject == subject for f in out):
            continue  # already said: stale
        if upper not in frames:
            who = (
                "is localization, e.g. amcl, running?"
                if upper == "map"
                else "is odometry, e.g. the EKF or the base driver, running?"
            )
            summary = (
                f"No {upper} frame in tf{whose}: nothing published {upper} → {lower} in {window:g} s ({who})."
            )
        else:
            parent = edges[lower].parent if lower in edges else None
            root = _ancestors(lower, edges)[-1]
            summary = (
                f"No transform path {upper} → {lower} in {window:g} s: {lower} "
                + (f"hangs under {parent} (tree root {root})" if parent else "has no parent")
                + f", cut off from {upper}{whose}. Whatever publishes {upper} → {lower} stopped."
            )
        out.append(
            Finding(
                "problem",
                "tf",
                subject,
                summary,
                (Step(Look.TRANSFORM_WAIT, (upper, lower, *ns)),),
            )
        )
    roots = sorted({_ancestors(f, edges)[-1] for f in frames})
    what = (
        f"{counted(len(frames), 'frame')}, root{'s' if len(roots) != 1 else ''} {', '.join(roots) or 'none'}"
    )
    return out, frames, what


def _logs(keeper: LogKeeper, checked: dict[str, str], left_out: dict[str, int]) -> list[Finding]:
    out = []
    now = time.time()
    folds = keeper.ring.tally.folds()
    for entry in folds[:MAX_LOG_FINDINGS]:
        severity: Literal["problem", "warning"] = (
            "problem" if level_rank(entry.level) >= level_rank("error") else "warning"
        )
        out.append(
            Finding(
                severity,
                "logs",
                entry.node,
                entry.describe(now),
                (Step(Look.NODE_LOG, (entry.node,)),),
                nodes=(entry.node,),
                details={"level": entry.level, "count": entry.count, "text": entry.text},
            )
        )
    since = time.strftime("%H:%M:%S", time.localtime(keeper.listening_since or now))
    errors = sum(f.count for f in folds if level_rank(f.level) >= level_rank("error"))
    warnings = sum(f.count for f in folds if f.level == "warn")
    if len(folds) > MAX_LOG_FINDINGS:
        left_out["logs"] = len(folds) - MAX_LOG_FINDINGS
    checked["logs"] = (
        f"{counted(errors, 'error')}, {counted(warnings, 'warning')} since {since} "
        f"({counted(len(keeper.ring), 'line')} kept)"
    )
    return out


def _plural(count: int, word: str) -> str:
    return counted(count, word)
