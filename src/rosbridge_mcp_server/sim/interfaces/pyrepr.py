"""How rclpy prints a default-constructed message's fields (``str()``/``repr()``), numpy arrays included.

ROS 2 rosapi builds its TypeDef ``examples`` and pseudo-constants from these strings.
"""

from __future__ import annotations

import math
import zlib
from typing import Any

from .specs import Cat, FieldSpec, MessageSpec

__all__ = ["py_default_str", "py_str", "slot_types_repr"]


def _scalar_default(f: FieldSpec) -> Any:
    if f.default is not None and not f.is_array:
        return f.default
    return {Cat.BOOL: False, Cat.INT: 0, Cat.FLOAT: 0.0, Cat.STRING: "", Cat.OCTET: b"\x00"}.get(f.cat)


def _array_values(f: FieldSpec) -> list[Any]:
    if f.default is not None:
        return list(f.default)
    if f.fixed_len is None:
        return []
    value = _scalar_default(f)
    return [value] * f.fixed_len


def py_str(f: FieldSpec) -> str:
    """``str(getattr(msg, field))`` for a default-constructed rclpy message."""
    if f.is_array:
        values = _array_values(f)
        if f.numpy:
            return _numpy_format(values, f.cat == Cat.FLOAT, as_repr=False)
        if f.typecode is not None:
            return f"array('{f.typecode}', {values!r})" if values else f"array('{f.typecode}')"
        if f.cat == Cat.MSG and f.msg is not None:
            return "[" + ", ".join(_py_repr_msg(f.msg) for _ in values) + "]"
        return repr(values)
    if f.cat in (Cat.MSG, Cat.TIME, Cat.DURATION):
        assert f.msg is not None
        return _py_repr_msg(f.msg)
    return str(_scalar_default(f))


def py_default_str(f: FieldSpec) -> str:
    if f.is_array:
        return repr(list(f.default))
    return str(f.default)


def _py_repr(f: FieldSpec) -> str:
    """How a field shows inside the message's ``__repr__``."""
    if f.is_array:
        values = _array_values(f)
        if f.numpy:
            return _numpy_format(values, f.cat == Cat.FLOAT, as_repr=True, uint8=f.prim == "uint8")
        if f.cat == Cat.MSG and f.msg is not None:
            return "[" + ", ".join(_py_repr_msg(f.msg) for _ in values) + "]"
        return repr(values)
    if f.cat in (Cat.MSG, Cat.TIME, Cat.DURATION):
        assert f.msg is not None
        return _py_repr_msg(f.msg)
    return repr(_scalar_default(f))


def _py_repr_msg(spec: MessageSpec) -> str:
    module = spec.key.split("/")[1]
    args = ", ".join(f"{f.name}={_py_repr(f)}" for f in spec.fields)
    return f"{spec.pkg}.{module}.{spec.name}({args})"


def _slot_type_class(f: FieldSpec) -> str:
    if f.is_array:
        if f.fixed_len is not None:
            return "Array"
        return "BoundedSequence" if f.bound is not None else "UnboundedSequence"
    if f.cat == Cat.STRING:
        if f.prim == "wstring":
            return "UnboundedWString"
        return "BoundedString" if f.string_bound is not None else "UnboundedString"
    if f.cat in (Cat.MSG, Cat.TIME, Cat.DURATION):
        return "NamespacedType"
    return "BasicType"


def slot_types_repr(spec: MessageSpec) -> str:
    # Object reprs carry memory addresses; ours are made up but stable per type and field.
    items = []
    for index, f in enumerate(spec.fields):
        address = 0x7F0000000000 + (zlib.crc32(f"{spec.key}:{index}".encode()) << 4)
        items.append(f"<rosidl_parser.definition.{_slot_type_class(f)} object at 0x{address:x}>")
    if len(items) == 1:
        return f"({items[0]},)"
    return "(" + ", ".join(items) + ")"


def _numpy_format(values: list[Any], is_float: bool, *, as_repr: bool, uint8: bool = False) -> str:
    """numpy's str()/repr() of a 1-D array (line width 75), enough for the values defaults hold."""
    if is_float:
        if all(math.isfinite(v) and float(v).is_integer() for v in values):
            words = [f"{int(v)}." for v in values]
        else:
            words = [repr(float(v)) for v in values]
    else:
        words = [str(int(v)) for v in values]
    if not as_repr:
        return _numpy_wrap(words, " ", " ", 75)
    suffix = "," if uint8 else ")"
    body = "array(" + _numpy_wrap(words, ", ", " " * 7, 75 - len(suffix)) + suffix
    if not uint8:
        return body
    last_line = len(body) - (body.rfind("\n") + 1)
    spacer = " " if last_line + len("dtype=uint8)") + 1 <= 75 else "\n" + " " * len("array(")
    return body + spacer + "dtype=uint8)"


def _numpy_wrap(words: list[str], separator: str, indent: str, width: int) -> str:
    element_width = width - max(len(separator.rstrip()), len("]"))
    text = ""
    line = indent
    for index, word in enumerate(words):
        if len(line) + len(word) > element_width and len(line) > len(indent):
            text += line.rstrip() + "\n"
            line = indent
        line += word
        if index < len(words) - 1:
            line += separator
    text += line
    return "[" + text[len(indent) :] + "]"
