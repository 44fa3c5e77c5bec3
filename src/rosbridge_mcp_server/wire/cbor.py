"""CBOR frames: what rosbridge sends on a subscription that asked for ``"compression": "cbor"``.

The server writes the same ``publish`` op as in JSON, as one binary WebSocket frame (not fragmented).
Numeric arrays travel as RFC 8746 typed arrays: a tag and a little-endian byte string
(``rosbridge_library/internal/cbor_conversion.py``, ROS 1 0.11.17 and every ROS 2 release alike).
They are decoded into :class:`array.array` (one compact copy, never a list of Python numbers), so a
4,000 × 4,000 map's ``int8[]`` cells stay 16 MB. ``uint8[]``/``char[]`` arrive as plain bytes (JSON's
base64 string is gone). rosbridge encodes no fixed-size arrays (``float64[36]``) this way: its converter
fails on them, so such messages never arrive as CBOR.

Pure: no I/O.
"""

from __future__ import annotations

import base64
import sys
from array import array
from typing import Any, Final

import cbor2

__all__ = ["TYPED_ARRAY_CODES", "decode_cbor", "json_shaped"]

#: RFC 8746 tag → array typecode, for the little-endian tags rosbridge writes (TAGGED_ARRAY_FORMATS).
TYPED_ARRAY_CODES: Final = {
    64: "B",  # uint8 (rosbridge sends uint8[] as a byte string instead; decoded if another server tags it)
    69: "H",  # uint16
    70: "I",  # uint32
    71: "Q",  # uint64
    72: "b",  # int8 (and ROS 1 byte[])
    77: "h",  # int16
    78: "i",  # int32
    79: "q",  # int64
    85: "f",  # float32
    86: "d",  # float64
}

_SWAP: Final = sys.byteorder == "big"


def decode_cbor(data: bytes | bytearray | memoryview) -> Any:
    """One CBOR item with its typed arrays as :class:`array.array`; ``ValueError`` when it is not CBOR."""
    try:
        # cbor2 6.x hands unknown tags back as CBORTag; they are replaced after decoding (its tag_hook
        # signature changed between major versions, the CBORTag value did not).
        item = cbor2.loads(bytes(data) if not isinstance(data, bytes) else data)
    except Exception as exc:  # cbor2 raises CBORDecodeError (a ValueError) and, on odd input, others
        raise ValueError(f"not CBOR: {exc}") from None
    return _typed_arrays(item)


def _typed_arrays(item: Any) -> Any:
    if isinstance(item, dict):
        for key, value in item.items():
            if isinstance(value, dict | list | cbor2.CBORTag):
                item[key] = _typed_arrays(value)
        return item
    if isinstance(item, list):
        for index, value in enumerate(item):
            if isinstance(value, dict | list | cbor2.CBORTag):
                item[index] = _typed_arrays(value)
        return item
    if isinstance(item, cbor2.CBORTag):
        code = TYPED_ARRAY_CODES.get(item.tag)
        if code is None or not isinstance(item.value, bytes):
            raise ValueError(f"unsupported CBOR tag {item.tag}")
        values = array(code)
        if len(item.value) % values.itemsize:
            raise ValueError(f"typed array (tag {item.tag}) of {len(item.value)} bytes is not whole items")
        values.frombytes(item.value)
        if _SWAP and values.itemsize > 1:
            values.byteswap()
        return values
    return item


def json_shaped(item: Any) -> Any:
    """A decoded CBOR message as rosbridge's JSON would have carried it: typed arrays as lists, ``uint8[]``
    bytes as a base64 string. A new object (the CBOR listener's message is left alone).

    rosbridge keeps one subscription per topic per connection and sends every listener of it the strongest
    compression any of them asked for, so a listener that asked for JSON can receive a CBOR frame.
    """
    if isinstance(item, dict):
        return {key: json_shaped(value) for key, value in item.items()}
    if isinstance(item, list):
        return [json_shaped(value) for value in item]
    if isinstance(item, array):
        return item.tolist()
    if isinstance(item, bytes | bytearray):
        return base64.b64encode(item).decode("ascii")
    return item
