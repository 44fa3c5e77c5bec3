"""ROS 1 (rosbridge 0.11.17): the inbound conversion (``message_conversion.populate_instance``) with its
strictness and texts, and what genpy's packing and unpacking does to a message on its way to a subscriber.

Serialization failures use genpy's ``check_type`` texts.
"""

from __future__ import annotations

import base64
import binascii
import struct
from typing import Any

from .base import ConversionError, JsonDict, Now, b64, default_field, mismatch, no_field
from .specs import Cat, FieldSpec, MessageSpec

__all__ = ["Ros1Conversion"]

_FLOAT32 = struct.Struct("<f")


def _wire_time(cat: Cat, value: Any, path: list[str]) -> JsonDict:
    """genpy packs a time as '<2I' and a duration as '<2i', and canonicalizes both when unpacking."""
    secs, nsecs = int(value["secs"]), int(value["nsecs"])
    lo, hi, fmt = (0, 2**32 - 1, "I") if cat == Cat.TIME else (-(2**31), 2**31 - 1, "i")
    for number in (secs, nsecs):
        if not lo <= number <= hi:
            detail = (
                "argument out of range"
                if number < 0 and fmt == "I"
                else f"'{fmt}' format requires {lo} <= number <= {hi}"
            )
            raise ConversionError(f"<class 'struct.error'>: '{detail}' when writing '{'.'.join(path)}'")
    carry = nsecs // 1_000_000_000
    return {"secs": secs + carry, "nsecs": nsecs - carry * 1_000_000_000}


class Ros1Conversion:
    """JSON to a ROS 1 message and back through genpy, for one registry (it caches per message type)."""

    def __init__(self) -> None:
        self._wire_cache: dict[str, bool] = {}

    def from_json(self, spec: MessageSpec, value: Any, clock: Now) -> JsonDict:
        return self._r1_msg(spec, value, spec.short, [], expected=spec.short, clock=clock)

    def _r1_msg(
        self, spec: MessageSpec, value: Any, root: str, stack: list[str], *, expected: str, clock: Now
    ) -> JsonDict:
        if type(value) is not dict:
            raise mismatch(root, stack, expected, value)
        # Every std_msgs/Header object present is stamped with the current time before its fields apply
        # (0.11.17 _to_object_inst), so a partial stamp keeps the other half of "now".
        stamp = clock.ros1() if spec.is_header else None
        converted: JsonDict = {}
        for key, item in value.items():
            f = spec.field_map.get(key)
            path = [*stack, key]
            if f is None:
                raise no_field(root, path)
            base = stamp if (stamp is not None and key == "stamp") else None
            converted[key] = self._r1_field(f, item, root, path, clock=clock, base=base)
        out: JsonDict = {}
        for f in spec.fields:
            if f.name in converted:
                out[f.name] = converted[f.name]
            elif stamp is not None and f.name == "stamp":
                out[f.name] = dict(stamp)
            else:
                out[f.name] = default_field(f, "ros1")
        return out

    def _r1_field(
        self, f: FieldSpec, value: Any, root: str, path: list[str], *, clock: Now, base: JsonDict | None
    ) -> Any:
        if f.binary:
            return self._r1_binary(f, value)
        if not f.is_array:
            if f.cat in (Cat.TIME, Cat.DURATION):
                return self._r1_time(f.cat, value, base, clock, path)
            if f.cat == Cat.MSG:
                assert f.msg is not None
                return self._r1_msg(f.msg, value, root, path, expected=f.prim, clock=clock)
            return self._r1_primitive(f, value, root, path, ".".join(path))
        if type(value) not in (list, tuple):
            raise mismatch(root, path, f.wire_type, value)
        if f.cat in (Cat.TIME, Cat.DURATION):
            items = [self._r1_time(f.cat, item, None, clock, path) for item in value]
        elif f.cat == Cat.MSG:
            assert f.msg is not None
            items = [self._r1_msg(f.msg, item, root, path, expected=f.prim, clock=clock) for item in value]
        else:
            field_name = ".".join(path) + "[]"
            items = [self._r1_primitive(f, item, root, path, field_name) for item in value]
        if f.fixed_len is not None and len(items) != f.fixed_len:
            # Conversion never checks the length; genpy's struct.pack fails when the message is serialized.
            raise ConversionError(
                f"<class 'struct.error'>: 'pack expected {f.fixed_len} items for packing (got {len(items)})'"
            )
        return items

    @staticmethod
    def _r1_primitive(f: FieldSpec, value: Any, root: str, path: list[str], field_name: str) -> Any:
        kind = type(value)
        cat = f.cat
        if kind is bool:
            ok = cat == Cat.BOOL
        elif kind is int:
            ok = cat in (Cat.INT, Cat.FLOAT)  # 0.11 type_map lets ints into float32/float64
        elif kind is float:
            ok = cat == Cat.FLOAT
        elif kind is str:
            ok = cat == Cat.STRING
        else:
            ok = False
        if not ok:
            raise mismatch(root, path, f.prim, value)
        if cat == Cat.FLOAT:
            return float(value)
        if cat == Cat.INT:
            # genpy check_type texts, raised when serialization fails on an out-of-range value.
            if f.lo == 0 and value < 0:
                raise ConversionError(f"field {field_name} must be unsigned integer type")
            if value < f.lo or value > f.hi:
                raise ConversionError(f"field {field_name} exceeds specified width [{f.prim}]")
        return value

    @staticmethod
    def _r1_time(cat: Cat, value: Any, base: JsonDict | None, clock: Now, path: list[str]) -> JsonDict:
        if cat == Cat.TIME and value == "now":
            return clock.ros1()
        out = dict(base) if base is not None else {"secs": 0, "nsecs": 0}
        # 0.11.17 reads only 'secs'/'nsecs' and swallows the TypeError of a non-container: sec/nanosec and
        # plain numbers are silently ignored (the time stays 0).
        if isinstance(value, dict):
            for key in ("secs", "nsecs"):
                if key in value:
                    item = value[key]
                    if not isinstance(item, int):
                        raise ConversionError(
                            "<class 'struct.error'>: 'required argument is not an integer' "
                            f"when writing field {'.'.join(path)}.{key}"
                        )
                    out[key] = int(item)
        return out

    @staticmethod
    def _r1_binary(f: FieldSpec, value: Any) -> str:
        try:
            data = base64.b64decode(value) if isinstance(value, str) else bytes(bytearray(value))
        except (TypeError, ValueError, binascii.Error) as exc:
            raise ConversionError(str(exc)) from None
        if f.fixed_len is not None:
            # genpy packs uint8[N] with struct '<Ns', which pads or truncates silently.
            data = data[: f.fixed_len].ljust(f.fixed_len, b"\0")
        return b64(data)

    # ROS 2 (2.0.8 / 2.7.1 / 3.3.1 / 4.2.1) -------------------------------------

    # genpy serialization ---------------------------------------------------------

    def wire(self, spec: MessageSpec, value: dict[str, Any]) -> dict[str, Any]:
        """A converted ROS 1 message as a subscriber receives it after genpy packed and unpacked it.

        float32 values come back rounded to float32; times are packed as two uint32 and durations as two
        int32, and unpacked canonical (``nsecs`` in [0, 1e9), the rest carried into ``secs``). A value
        that does not pack raises :class:`ConversionError` with struct's text, as rospy's publish does
        (the message is lost). Messages without such fields are returned as they are.
        """
        if not self._needs_wire(spec):
            return value
        return self._wire_msg(spec, value, [])

    @staticmethod
    def has_header(spec: MessageSpec) -> bool:
        """genpy's ``_has_header``: the first field is ``std_msgs/Header header`` (rospy sets its seq)."""
        fields = spec.fields
        return bool(fields) and fields[0].name == "header" and fields[0].prim in ("std_msgs/Header", "Header")

    def _needs_wire(self, spec: MessageSpec) -> bool:
        cached = self._wire_cache.get(spec.key)
        if cached is None:
            self._wire_cache[spec.key] = False  # breaks recursion; no ROS message nests itself
            cached = any(
                f.prim == "float32"
                or f.cat in (Cat.TIME, Cat.DURATION)
                or (f.msg is not None and self._needs_wire(f.msg))
                for f in spec.fields
                if not f.binary
            )
            self._wire_cache[spec.key] = cached
        return cached

    def _wire_msg(self, spec: MessageSpec, value: dict[str, Any], path: list[str]) -> dict[str, Any]:
        out = dict(value)
        for f in spec.fields:
            if f.binary or f.name not in value:
                continue
            item = value[f.name]
            if f.msg is not None:
                if self._needs_wire(f.msg):
                    where = [*path, f.name]
                    out[f.name] = (
                        [self._wire_msg(f.msg, v, where) for v in item]
                        if f.is_array
                        else self._wire_msg(f.msg, item, where)
                    )
            elif f.cat in (Cat.TIME, Cat.DURATION):
                where = [*path, f.name]
                if f.is_array:
                    out[f.name] = [_wire_time(f.cat, v, where) for v in item]
                else:
                    out[f.name] = _wire_time(f.cat, item, where)
            elif f.prim == "float32":
                try:
                    if f.is_array:
                        layout = f"<{len(item)}f"
                        out[f.name] = list(struct.unpack(layout, struct.pack(layout, *item)))
                    else:
                        out[f.name] = _FLOAT32.unpack(_FLOAT32.pack(item))[0]
                except OverflowError:
                    raise ConversionError("float too large to pack with f format") from None
        return out
