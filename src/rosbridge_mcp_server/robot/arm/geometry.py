"""A link's size as the arm's judge uses it: the radius of a capsule around the link's centre line.

Read from the URDF's ``<collision>`` geometry, else its ``<visual>`` (the larger of all its shapes): a
``<cylinder>`` or ``<sphere>`` its ``radius``; a ``<box>`` half the diagonal of its two smaller sides (its
longest side taken to lie along the link). A ``<mesh>``, a shape that cannot be read, or no geometry at all
gives ``None``, and the judge uses a stated default (``[arm] link_radius``). The shape's own ``<origin>`` is
not read: the capsule is centred on the line between the link's joint origins. Pure; no MCP.
"""

from __future__ import annotations

import math

from rosbridge_mcp_server.robot.arm.bounded_xml import XmlElement

__all__ = ["GEOMETRY_TAGS", "MAX_RADIUS", "link_radius"]

#: The URDF elements this module reads (kept by the bounded reader, four levels under ``<robot>``).
GEOMETRY_TAGS = frozenset({"collision", "visual", "geometry", "cylinder", "sphere", "box", "mesh"})
#: A radius above this (m) is not believed: the shape is treated as unknown.
MAX_RADIUS = 5.0


def _number(text: str | None) -> float | None:
    try:
        value = float(text) if text is not None else math.nan
    except ValueError:
        return None
    return value if math.isfinite(value) and 0.0 <= value <= 2 * MAX_RADIUS else None


def _shape_radius(shape: XmlElement) -> float | None:
    if shape.tag in ("cylinder", "sphere"):
        return _number(shape.attrs.get("radius"))
    if shape.tag == "box":
        sides = [_number(part) for part in shape.attrs.get("size", "").split()]
        if len(sides) != 3 or any(side is None for side in sides):
            return None
        small = sorted(side for side in sides if side is not None)[:2]
        return math.hypot(*small) / 2
    return None  # a mesh: its size is not known without the file


def link_radius(link: XmlElement) -> float | None:
    """The capsule radius (m) of *link* (a ``<link>`` element), or ``None`` when its geometry does not say."""
    for kind in ("collision", "visual"):
        radii: list[float | None] = [
            _shape_radius(shape)
            for element in link.children
            if element.tag == kind
            for geometry in element.children
            if geometry.tag == "geometry"
            for shape in geometry.children
        ]
        if radii:
            if any(radius is None for radius in radii):
                return None
            largest = max(radius for radius in radii if radius is not None)
            return largest if largest <= MAX_RADIUS else None
    return None
