"""What every part of the interface registry shares: its errors, their texts, defaults and the clock."""

from __future__ import annotations

import base64
import math
from collections.abc import Callable
from typing import Any, Literal

from .specs import Cat, FieldSpec, MessageSpec

__all__ = [
    "ConversionError",
    "Dialect",
    "InterfaceError",
    "JsonDict",
    "Kind",
    "Now",
    "b64",
    "default_field",
    "default_msg",
    "mismatch",
    "no_field",
    "split_seconds",
    "zero_time",
]

Dialect = Literal["ros1", "ros2"]
Kind = Literal["msg", "srv", "action"]
JsonDict = dict[str, Any]


class InterfaceError(Exception):
    """An unknown or malformed type name; ``str()`` is the text the real server logs or returns."""


class ConversionError(Exception):
    """A JSON value that does not fit its type; ``str()`` mirrors rosbridge's text for the same input."""


def mismatch(root: str, stack: list[str], expected: str, found: Any) -> ConversionError:
    # rosbridge's FieldTypeMismatchException (same text in ROS 1 0.11 and every ROS 2 release).
    if root == expected:
        return ConversionError(f"Expected a JSON object for type {root} but received a {type(found)}")
    return ConversionError(
        f"{root} message requires a {expected} for field {'.'.join(stack)}, but got a {type(found)}"
    )


def no_field(root: str, stack: list[str]) -> ConversionError:
    return ConversionError(f"Message type {root} does not have a field {'.'.join(stack)}")


def b64(data: bytes) -> str:
    return base64.b64encode(data).decode("ascii")


def split_seconds(stamp: float) -> tuple[int, int]:
    """Seconds as (whole seconds, nanoseconds), nanoseconds never rounded up to a full second."""
    secs = math.floor(stamp)
    nsecs = min(round((stamp - secs) * 1e9), 999_999_999)
    return int(secs), nsecs


class Now:
    """The current time, read at most once per conversion."""

    __slots__ = ("_clock", "_stamp", "_value")

    def __init__(self, clock: Callable[[], float], stamp: float | None) -> None:
        self._clock = clock
        self._stamp = stamp
        self._value: tuple[int, int] | None = None

    def _get(self) -> tuple[int, int]:
        if self._value is None:
            self._value = split_seconds(self._clock() if self._stamp is None else self._stamp)
        return self._value

    def ros1(self) -> JsonDict:
        secs, nsecs = self._get()
        return {"secs": secs, "nsecs": nsecs}

    def ros2(self) -> JsonDict:
        secs, nsecs = self._get()
        return {"sec": secs, "nanosec": nsecs}


# --- defaults -----------------------------------------------------------------------------------------------


def zero_time(dialect: Dialect) -> JsonDict:
    return {"secs": 0, "nsecs": 0} if dialect == "ros1" else {"sec": 0, "nanosec": 0}


def default_msg(spec: MessageSpec, dialect: Dialect) -> JsonDict:
    """The JSON form of a message with every field at its default."""
    return {f.name: default_field(f, dialect) for f in spec.fields}


def default_field(f: FieldSpec, dialect: Dialect) -> Any:
    if f.is_array:
        if f.default is not None:
            values = list(f.default)
            return b64(bytes(values)) if f.binary else values
        count = f.fixed_len or 0
        if f.binary:
            return b64(bytes(count))
        return [_default_scalar(f, dialect) for _ in range(count)]
    return _default_scalar(f, dialect)


def _default_scalar(f: FieldSpec, dialect: Dialect) -> Any:
    if f.default is not None and not f.is_array:
        return f.default
    cat = f.cat
    if cat == Cat.FLOAT:
        return 0.0
    if cat in (Cat.INT, Cat.OCTET):
        return 0
    if cat == Cat.BOOL:
        return False
    if cat == Cat.STRING:
        return ""
    if cat in (Cat.TIME, Cat.DURATION):
        return zero_time(dialect)
    assert f.msg is not None
    return default_msg(f.msg, dialect)
