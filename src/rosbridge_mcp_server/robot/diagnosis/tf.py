"""The ``tf`` area: dynamic transforms stamped over a second before the newest one, a frame with two parents,
no path along map → odom → base (``base_footprint`` or ``base_link``), for the root's ``/tf`` and for each
robot's namespace with its own (``/robot2/tf``, ``robot/namespaces.py``), each tree on its own
(:func:`tf_trees`)."""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Final

from rosbridge_mcp_server.robot.diagnosis.findings import Finding, Look, Step
from rosbridge_mcp_server.robot.diagnosis.streams import short_type
from rosbridge_mcp_server.robot.text import NAME_CHARS, shown
from rosbridge_mcp_server.robot.wording import counted

if TYPE_CHECKING:
    from rosbridge_mcp_server.robot.diagnosis.streams import Heard

__all__ = ["STALE_TRANSFORM", "tf_trees"]

#: A dynamic transform stamped this long before the newest one is stale.
STALE_TRANSFORM: Final = 1.0


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


def _edges(heard: Mapping[str, Heard], namespace: str = "") -> tuple[dict[str, _Edge], dict[str, set[str]]]:
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


def tf_trees(
    heard: Mapping[str, Heard],
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


@dataclass(frozen=True)
class _Tree:
    """One tf tree as heard: child → its latest edge, child → every parent seen, the frames, whose it is."""

    edges: Mapping[str, _Edge]
    parents: Mapping[str, set[str]]
    frames: set[str]
    namespace: str

    @property
    def whose(self) -> str:
        """What a finding adds to say whose tf it is ("" for the root's)."""
        return f" (tf of {self.namespace})" if self.namespace else ""

    @property
    def ns(self) -> tuple[str, ...]:
        """The namespace as a look's last name, when there is one."""
        return (self.namespace,) if self.namespace else ()

    def subject(self, pair: str) -> str:
        """A frame pair as a finding's subject, the namespace first."""
        return f"{self.namespace} {pair}" if self.namespace else pair


def _tf(
    heard: Mapping[str, Heard], topics: Mapping[str, str], window: float, namespace: str = ""
) -> tuple[list[Finding], set[str], str]:
    """One tf tree (the root's, or a namespace's): findings, frames, and what was checked."""
    edges, parents = _edges(heard, namespace)
    tree = _Tree(edges, parents, set(edges) | {e.parent for e in edges.values()}, namespace)
    out = _two_parents(tree) + _stale(tree)
    out += _cut_chain(tree, topics, window, said={f.subject for f in out})
    roots = sorted({_ancestors(f, edges)[-1] for f in tree.frames})
    what = (
        f"{counted(len(tree.frames), 'frame')}, root{'s' if len(roots) != 1 else ''} "
        f"{', '.join(roots) or 'none'}"
    )
    return out, tree.frames, what


def _two_parents(tree: _Tree) -> list[Finding]:
    """A frame two nodes publish, each with its own parent."""
    return [
        Finding(
            "problem",
            "tf",
            child,
            f"Frame {child} has {len(found)} parents ({', '.join(sorted(found))}): two nodes publish "
            f"it, and tf keeps jumping between them{tree.whose}.",
            (Step(Look.TOPIC, (f"{tree.namespace}/tf",), "to see who publishes"),),
        )
        for child, found in sorted(tree.parents.items())
        if len(found) > 1
    ]


def _stale(tree: _Tree) -> list[Finding]:
    """Dynamic transforms stamped over :data:`STALE_TRANSFORM` before the newest one."""
    stamps = [e.stamp for e in tree.edges.values() if not e.static and e.stamp is not None]
    newest = max(stamps, default=None)
    if newest is None:
        return []
    return [
        Finding(
            "problem",
            "tf",
            tree.subject(f"{edge.parent} -> {child}"),
            f"Transform {edge.parent} → {child} is stale: stamped {newest - edge.stamp:.1f} s before "
            f"the newest transform{tree.whose}.",
            (Step(Look.TRANSFORM, (edge.parent, child, *tree.ns)),),
        )
        for child, edge in sorted(tree.edges.items())
        if not edge.static and edge.stamp is not None and newest - edge.stamp > STALE_TRANSFORM
    ]


def _cut_chain(tree: _Tree, topics: Mapping[str, str], window: float, *, said: set[str]) -> list[Finding]:
    """No base frame, or no path along map → odom → base (the map and odom expected where the robot has a map
    or odometry topic); a pair already *said* (stale) is not said again."""
    out: list[Finding] = []
    frames = tree.frames
    base = next((f for f in ("base_footprint", "base_link") if f in frames), None)
    has_map = any(
        t.rsplit("/", 1)[-1] == "map" and short_type(ty) == "OccupancyGrid" for t, ty in topics.items()
    )
    has_odometry = any(short_type(ty) == "Odometry" for ty in topics.values())
    chain = [f for f, expected in (("map", has_map), ("odom", has_odometry)) if f in frames or expected]
    if base is None and "odom" in frames:
        out.append(
            Finding(
                "problem",
                "tf",
                tree.subject("odom -> base"),
                f"No base frame (base_footprint or base_link) in tf{tree.whose}: the robot's own frame is "
                "missing.",
                (Step(Look.TRANSFORM_WAIT, ("odom", "base_link", *tree.ns)),),
            )
        )
    if base is not None:
        chain.append(base)
    for upper, lower in itertools.pairwise(chain):
        subject = tree.subject(f"{upper} -> {lower}")
        if (
            upper in _ancestors(lower, tree.edges)
            or subject in said
            or any(f.subject == subject for f in out)
        ):
            continue  # joined, or already said: stale
        summary = _no_path(tree, upper, lower, window)
        out.append(
            Finding("problem", "tf", subject, summary, (Step(Look.TRANSFORM_WAIT, (upper, lower, *tree.ns)),))
        )
    return out


def _no_path(tree: _Tree, upper: str, lower: str, window: float) -> str:
    """Why there is no path *upper* → *lower*: no *upper* frame at all, or *lower* under another root."""
    if upper not in tree.frames:
        who = (
            "is localization, e.g. amcl, running?"
            if upper == "map"
            else "is odometry, e.g. the EKF or the base driver, running?"
        )
        return (
            f"No {upper} frame in tf{tree.whose}: nothing published {upper} → {lower} in {window:g} s "
            f"({who})."
        )
    parent = tree.edges[lower].parent if lower in tree.edges else None
    root = _ancestors(lower, tree.edges)[-1]
    return (
        f"No transform path {upper} → {lower} in {window:g} s: {lower} "
        + (f"hangs under {parent} (tree root {root})" if parent else "has no parent")
        + f", cut off from {upper}{tree.whose}. Whatever publishes {upper} → {lower} stopped."
    )
