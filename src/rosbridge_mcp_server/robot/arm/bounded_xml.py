"""XML from the robot, read boundedly: expat with every DTD refused (so no entity expands, internal or
external: no "billion laughs", no file read), at most :data:`MAX_URDF_BYTES`, :data:`MAX_ELEMENTS` elements
nested at most :data:`MAX_DEPTH` deep, and only the elements a caller keeps. The URDF and the SRDF are read
through it (``urdf.py``, ``controllers.py``); what is wrong is one sentence (:class:`UrdfError`).
"""

from __future__ import annotations

import unicodedata
from dataclasses import dataclass, field
from xml.parsers import expat

__all__ = ["MAX_DEPTH", "MAX_ELEMENTS", "MAX_URDF_BYTES", "UrdfError", "XmlElement", "plain", "read_xml"]

#: The largest description read (a real arm's URDF with a gripper is 20–200 kB; meshes are files, not text).
MAX_URDF_BYTES = 2_000_000
#: The deepest element nesting read (a URDF nests ~5 deep).
MAX_DEPTH = 24
#: The most elements read, of any kind.
MAX_ELEMENTS = 50_000


#: Unicode categories a name from the robot may not hold: controls, format characters (bidi overrides,
#: zero-width), surrogates, private use, unassigned, line and paragraph separators.
_HIDDEN = frozenset({"Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp"})


def plain(name: str) -> bool:
    """Whether *name* (a link, joint or controller name from the robot) shows as what it is: nothing hidden,
    nothing that turns the text around."""
    return all(unicodedata.category(ch) not in _HIDDEN for ch in name)


class UrdfError(ValueError):
    """A robot description that cannot be read; ``str()`` says what is wrong and where."""


@dataclass
class XmlElement:
    """An element kept by :func:`read_xml`: its tag, attributes and kept children."""

    tag: str
    attrs: dict[str, str]
    children: list[XmlElement] = field(default_factory=list)

    def first(self, tag: str) -> XmlElement | None:
        return next((child for child in self.children if child.tag == tag), None)


def read_xml(data: bytes, what: str, keep: frozenset[str], levels: int = 2) -> XmlElement:
    """The ``<robot>`` element of *data* (a URDF or SRDF, named *what* in errors) with its descendants whose
    tags are in *keep*, *levels* below it (2: children and grandchildren); bounded, DTDs refused
    (:class:`UrdfError`)."""
    if len(data) > MAX_URDF_BYTES:
        raise UrdfError(f"the {what} is {len(data):,} bytes; at most {MAX_URDF_BYTES:,} are read")
    return _Reader(what, keep, levels).read(data)


class _Reader:
    """expat with DTDs refused and the tree bounded; keeps the elements under ``<robot>`` that we read."""

    def __init__(self, what: str, keep: frozenset[str], levels: int) -> None:
        self.what = what
        self.keep = keep
        self.levels = levels
        self.stack: list[XmlElement] = []
        self.root: XmlElement | None = None
        self.count = 0
        self.skipping = 0  # depth inside an element we do not keep

    def read(self, data: bytes) -> XmlElement:
        parser = expat.ParserCreate()
        parser.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
        parser.StartDoctypeDeclHandler = self._doctype
        parser.EntityDeclHandler = self._entity
        parser.ExternalEntityRefHandler = self._external
        parser.StartElementHandler = self._start
        parser.EndElementHandler = self._end
        try:
            parser.Parse(data, True)
        except expat.ExpatError as exc:
            raise UrdfError(
                f"the {self.what} is not well-formed XML ({expat.ErrorString(exc.code)}, line {exc.lineno})"
            ) from None
        if self.root is None or self.root.tag != "robot":
            raise UrdfError(f"the {self.what} has no <robot> element at its root")
        return self.root

    def _doctype(self, *_: object) -> None:
        raise UrdfError(f"the {self.what} has a DTD (<!DOCTYPE>); a URDF needs none, and it is not read")

    def _entity(self, *_: object) -> None:
        raise UrdfError(f"the {self.what} declares an entity; it is not read")

    def _external(self, *_: object) -> int:
        raise UrdfError(f"the {self.what} refers to an external entity; it is not read")

    def _start(self, tag: str, attrs: dict[str, str]) -> None:
        self.count += 1
        if self.count > MAX_ELEMENTS:
            raise UrdfError(f"the {self.what} has more than {MAX_ELEMENTS} elements")
        depth = len(self.stack) + self.skipping
        if depth >= MAX_DEPTH:
            raise UrdfError(f"the {self.what} nests elements deeper than {MAX_DEPTH}")
        if self.skipping or (self.stack and tag not in self.keep) or len(self.stack) > self.levels:
            self.skipping += 1
            return
        element = XmlElement(tag, attrs)
        if self.stack:
            self.stack[-1].children.append(element)
        else:
            self.root = element
        self.stack.append(element)

    def _end(self, _tag: str) -> None:
        if self.skipping:
            self.skipping -= 1
        else:
            self.stack.pop()
