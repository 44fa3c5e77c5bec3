"""The CBOR form of a message, as rosbridge's ``extract_cbor_values`` builds it for ``compression: "cbor"``.

Mirrored from ``rosbridge_library/internal/cbor_conversion.py`` (ROS 1 0.11.17 and the ros2 branch alike):
variable-length numeric arrays become RFC 8746 typed arrays (a tag and little-endian bytes), ``uint8[]``
and ``char[]`` plain bytes, everything else the same values as JSON. A fixed-size primitive array
(``float64[36]``) is not in the converter's tables: it recurses into the array's values and fails, so the
message is never sent on that subscription (seen on the Jazzy lab with ``/odom``, 2026-11-25).
"""

from __future__ import annotations

import base64
import math
import sys
from array import array
from typing import Any, Final

import cbor2

from .base import ConversionError
from .specs import Cat, FieldSpec, MessageSpec

__all__ = ["cbor_form"]

#: rosbridge's TAGGED_ARRAY_FORMATS by slot type (ROS 1) and IDL type (ROS 2): tag and array typecode.
_TAGGED: Final = {
    "uint16": (69, "H"),
    "uint32": (70, "I"),
    "uint64": (71, "Q"),
    "byte": (72, "b"),
    "int8": (72, "b"),
    "int16": (77, "h"),
    "int32": (78, "i"),
    "int64": (79, "q"),
    "float32": (85, "f"),
    "float": (85, "f"),
    "float64": (86, "d"),
    "double": (86, "d"),
}
_SWAP: Final = sys.byteorder == "big"


def cbor_form(spec: MessageSpec, json_form: dict[str, Any], *, fixed_lists: bool = False) -> dict[str, Any]:
    """The message's CBOR values from its JSON form; :class:`ConversionError` where rosbridge's fails.

    ``fixed_lists``: fixed-size primitive arrays as lists (rosbridge-server-rs 0.1.6, seen on ``/odom``).
    """
    return {f.name: _field(f, json_form[f.name], fixed_lists) for f in spec.fields if f.name in json_form}


def _variable(f: FieldSpec) -> bool:
    return f.wire_type.endswith("[]") or (f.wire_type.startswith("sequence<") and "," not in f.wire_type)


def _field(f: FieldSpec, value: Any, fixed_lists: bool) -> Any:
    if not f.is_array:
        if f.cat == Cat.MSG and f.msg is not None:
            return cbor_form(f.msg, value, fixed_lists=fixed_lists)
        return value
    if f.cat == Cat.MSG and f.msg is not None:
        msg = f.msg
        return [cbor_form(msg, item, fixed_lists=fixed_lists) for item in value]
    if not _variable(f):
        if fixed_lists:
            return value
        raise ConversionError(
            f"rosbridge's CBOR converter cannot encode the array field {f.name} ({f.wire_type})"
        )
    if f.binary:
        return base64.b64decode(value) if isinstance(value, str) else bytes(value)
    tagged = _TAGGED.get(f.prim)
    if tagged is None:
        return value  # bool[] and string[] stay lists
    tag, code = tagged
    values = array(code, (math.nan if v is None else v for v in value) if code in "fd" else value)
    if _SWAP and values.itemsize > 1:
        values.byteswap()
    return cbor2.CBORTag(tag, values.tobytes())
