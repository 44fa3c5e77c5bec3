"""Shorten a received ROS message for a model: long arrays summarised, byte arrays never dumped.

One ``LaserScan`` holds hundreds of ranges and one ``PointCloud2`` megabytes of base64: as JSON they would
fill a model's context with numbers it cannot use. :func:`summarize` keeps the message's shape, replaces

* a number array longer than :data:`ARRAY_LIMIT` by ``{"length", "first", "min", "max", "mean"}`` (NaN and
  infinities are left out of the statistics and counted);
* an array of objects longer than :data:`ARRAY_LIMIT` by its first few items;
* a byte array (rosbridge sends ``uint8[]``/``char[]`` as one base64 string) by ``{"bytes": N}``;
* a text longer than :data:`TEXT_LIMIT` by its beginning,

and records each cut as a :class:`Cut`. :func:`select_fields` keeps only dotted paths (``pose.position``,
``ranges.0``) first. Pure: no I/O.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

__all__ = [
    "ARRAY_LIMIT",
    "HEAD",
    "TEXT_LIMIT",
    "Cut",
    "FieldPathError",
    "Summary",
    "select_fields",
    "summarize",
]

#: Arrays up to this length are kept whole.
ARRAY_LIMIT = 16
#: How many values of a long array are shown.
HEAD = 5
#: Strings up to this length are kept whole.
TEXT_LIMIT = 500
# A base64 byte array as rosbridge writes it; short strings stay text (a frame_id is not a byte array).
_BASE64 = re.compile(r"^[A-Za-z0-9+/]*={0,2}$")
_BASE64_MIN = 64


@dataclass(frozen=True)
class Cut:
    """One shortened value: where (dotted path), what it was, and what is shown instead."""

    path: str
    kind: str  # "numbers", "items", "bytes" or "text"
    length: int

    def describe(self) -> str:
        """``ranges: 720 numbers summarised``."""
        what = {
            "numbers": "numbers summarised",
            "items": f"items, first {HEAD} shown",
            "bytes": "bytes omitted",
            "text": f"characters, first {TEXT_LIMIT} shown",
        }[self.kind]
        return f"{self.path}: {self.length} {what}"


@dataclass(frozen=True)
class Summary:
    """A shortened message and the cuts made to it."""

    message: Any
    cuts: tuple[Cut, ...]


class FieldPathError(ValueError):
    """A dotted path that is not in the message; ``str()`` names it and the fields that are there."""


def summarize(message: Any, *, byte_fields: Iterable[str] = ()) -> Summary:
    """``message`` with long arrays summarised and byte arrays replaced by their length.

    ``byte_fields`` are dotted paths known (from the type) to be byte arrays; without them a long
    base64-looking string is taken for one.
    """
    cuts: list[Cut] = []
    known = frozenset(byte_fields)
    shortened = _shorten(message, "", cuts, known)
    return Summary(shortened, tuple(cuts))


def _shorten(value: Any, path: str, cuts: list[Cut], byte_fields: frozenset[str]) -> Any:
    if isinstance(value, Mapping):
        return {
            key: _shorten(item, f"{path}.{key}" if path else str(key), cuts, byte_fields)
            for key, item in value.items()
        }
    if isinstance(value, str):
        return _shorten_text(value, path, cuts, byte_fields)
    if isinstance(value, list):
        return _shorten_list(value, path, cuts, byte_fields)
    return value


def _shorten_text(value: str, path: str, cuts: list[Cut], byte_fields: frozenset[str]) -> Any:
    if _bare(path) in byte_fields or (
        len(value) >= _BASE64_MIN and len(value) % 4 == 0 and _BASE64.match(value)
    ):
        size = len(value) * 3 // 4 - (len(value) - len(value.rstrip("=")))
        cuts.append(Cut(path, "bytes", size))
        return {"bytes": size}
    if len(value) > TEXT_LIMIT:
        cuts.append(Cut(path, "text", len(value)))
        return value[:TEXT_LIMIT] + "..."
    return value


def _shorten_list(value: list[Any], path: str, cuts: list[Cut], byte_fields: frozenset[str]) -> Any:
    if len(value) <= ARRAY_LIMIT:
        return [_shorten(item, f"{path}.{index}", cuts, byte_fields) for index, item in enumerate(value)]
    if all(_is_number(item) for item in value):
        cuts.append(Cut(path, "numbers", len(value)))
        return _number_summary(value)
    cuts.append(Cut(path, "items", len(value)))
    return [_shorten(item, f"{path}.{index}", cuts, byte_fields) for index, item in enumerate(value[:HEAD])]


def _number_summary(values: Sequence[Any]) -> dict[str, Any]:
    # rosbridge sends NaN/inf as null in JSON (both lines); a LaserScan is full of them (no return).
    finite = [float(v) for v in values if v is not None and math.isfinite(v)]
    summary: dict[str, Any] = {"length": len(values), "first": [_plain(v) for v in values[:HEAD]]}
    if finite:
        summary["min"] = _plain(min(finite))
        summary["max"] = _plain(max(finite))
        summary["mean"] = round(math.fsum(finite) / len(finite), 6)
    missing = len(values) - len(finite)
    if missing:
        summary["not_finite"] = missing
    return summary


def _is_number(value: Any) -> bool:
    return value is None or (isinstance(value, int | float) and not isinstance(value, bool))


def _plain(value: Any) -> Any:
    if isinstance(value, float):
        if not math.isfinite(value):
            return None
        return int(value) if value.is_integer() and abs(value) < 2**53 else value
    return value


def _bare(path: str) -> str:
    """``points.3.data`` → ``points.data``: array indices dropped, to match a type's field paths."""
    return ".".join(part for part in path.split(".") if not part.isdigit())


def select_fields(message: Any, paths: Sequence[str]) -> dict[str, Any]:
    """Only the dotted ``paths`` of ``message``, nested as in the message (``["pose.position"]``).

    A number in a path indexes an array (``ranges.0``). A path that is not there raises
    :class:`FieldPathError` naming the fields that are.
    """
    result: dict[str, Any] = {}
    for raw in paths:
        path = raw.strip().strip(".")
        if not path:
            continue
        parts = path.split(".")
        value = message
        for depth, part in enumerate(parts):
            value = _step(value, part, ".".join(parts[:depth]), path)
        target = result
        for part in parts[:-1]:
            nested = target.setdefault(part, {})
            if not isinstance(nested, dict):
                break
            target = nested
        else:
            target[parts[-1]] = value
    return result


def _step(value: Any, part: str, where: str, path: str) -> Any:
    if isinstance(value, Mapping):
        if part in value:
            return value[part]
        inside = f" in {where}" if where else ""
        fields = ", ".join(str(key) for key in value) or "none"
        raise FieldPathError(f"Field {path!r}: there is no {part!r}{inside}; the fields there are: {fields}.")
    if isinstance(value, list) and part.isdigit():
        index = int(part)
        if index < len(value):
            return value[index]
        raise FieldPathError(f"Field {path!r}: {where} has only {len(value)} items.")
    raise FieldPathError(f"Field {path!r}: {where or 'the message'} is a value, not an object with fields.")
