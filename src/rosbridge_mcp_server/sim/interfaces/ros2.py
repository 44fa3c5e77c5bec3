"""ROS 2 (rosbridge 2.0.8 / 2.7.1 / 3.3.1 / 4.2.1, identical there): the inbound conversion with its
strictness, and rclpy's generated setters (rosidl_generator_py ``_msg.py.em``) whose assertions surface as
error texts."""

from __future__ import annotations

import array
import base64
import binascii
from typing import Any

from .base import ConversionError, JsonDict, Now, b64, default_field, mismatch, no_field
from .specs import Cat, FieldSpec, MessageSpec

__all__ = ["Ros2Conversion"]

_PY_TYPE = {Cat.BOOL: "bool", Cat.INT: "int", Cat.FLOAT: "float", Cat.STRING: "str", Cat.OCTET: "bytes"}


class Ros2Conversion:
    """JSON to a ROS 2 message (stateless)."""

    def from_json(self, spec: MessageSpec, value: Any, clock: Now) -> JsonDict:
        return self._r2_root(spec, value, clock)

    def _r2_root(self, spec: MessageSpec, value: Any, clock: Now) -> JsonDict:
        root = spec.short
        header = spec.field_map.get("header")
        stamp = False
        if header is not None and header.prim == "std_msgs/Header" and not header.is_array:
            # Only the root 'header' is stamped, and only when it or its stamp is omitted
            # (2.0.7 / 2.7.0 / 3.3.0 / 4.2.0+; older releases stamped every Header like ROS 1).
            if not isinstance(value, dict):
                raise ConversionError(f"'{type(value).__name__}' object has no attribute 'get'")
            given = value.get("header")
            if given is not None and not isinstance(given, dict):
                raise mismatch(root, ["header"], "dict", given)
            stamp = given is None or "stamp" not in given
        out = self._r2_msg(spec, value, root, [], clock)
        if stamp:
            out["header"]["stamp"] = clock.ros2()
        return out

    def _r2_msg(self, spec: MessageSpec, value: Any, root: str, stack: list[str], clock: Now) -> JsonDict:
        if not isinstance(value, dict):
            if not stack:
                raise mismatch(root, stack, root, value)
            raise ConversionError(f"msg is not a dict, but a {type(value)}")
        converted: JsonDict = {}
        for key, item in value.items():
            f = spec.field_map.get(key)
            path = [*stack, key]
            if f is None:
                raise no_field(root, path)
            converted[key] = self._r2_field(f, item, root, path, clock)
        return {
            f.name: converted[f.name] if f.name in converted else default_field(f, "ros2")
            for f in spec.fields
        }

    def _r2_field(self, f: FieldSpec, value: Any, root: str, path: list[str], clock: Now) -> Any:
        if f.binary:
            return self._r2_binary(f, value)
        if not f.is_array:
            if f.cat in (Cat.TIME, Cat.DURATION):
                return self._r2_time(f, value, clock)
            if f.cat == Cat.MSG:
                assert f.msg is not None
                return self._r2_msg(f.msg, value, root, path, clock)
            return self._r2_primitive(f, value, root, path, setter=True)
        if not isinstance(value, (list, tuple)):
            raise ConversionError(f"msg is not a list type, but a {type(value)}")
        if not value:
            items: list[Any] = []
        elif f.typecode is not None:
            return self._r2_typed_sequence(f, value)
        elif f.numpy:
            return self._r2_numpy(f, value)
        elif f.cat in (Cat.TIME, Cat.DURATION):
            items = [self._r2_time(f, item, clock) for item in value]
        elif f.cat == Cat.MSG:
            assert f.msg is not None
            items = [self._r2_msg(f.msg, item, root, path, clock) for item in value]
        else:
            items = [self._r2_primitive(f, item, root, path, setter=False) for item in value]
        self._r2_check_sequence(f, items)
        return items

    @staticmethod
    def _r2_check_sequence(f: FieldSpec, items: list[Any]) -> None:
        # The generated setter's assertion (elements already passed the converter's checks).
        length_ok = True
        suffixes = ["a set or sequence"]
        if f.fixed_len is not None:
            length_ok = len(items) == f.fixed_len
            suffixes.append(f"with length {f.fixed_len}")
        elif f.bound is not None:
            length_ok = len(items) <= f.bound
            suffixes.append(f"with length <= {f.bound}")
        if length_ok:
            return
        py_type = f.msg.name if f.cat == Cat.MSG and f.msg is not None else _PY_TYPE.get(f.cat, "int")
        suffixes.append(f"and each value of type '{py_type}'")
        if f.cat == Cat.INT:
            if f.lo == 0:
                suffixes.append(f"and each unsigned integer in [0, {f.hi}]")
            else:
                suffixes.append(f"and each integer in [{f.lo}, {f.hi}]")
        raise ConversionError(f"The '{f.name}' field must be {' '.join(suffixes)}")

    @staticmethod
    def _r2_typed_sequence(f: FieldSpec, value: list[Any] | tuple[Any, ...]) -> list[Any]:
        assert f.typecode is not None
        data = array.array(f.typecode)
        try:
            # rosbridge extends the message's array.array in place; Python's own errors are the texts.
            data.extend(value)
        except (TypeError, OverflowError, ValueError) as exc:
            raise ConversionError(str(exc)) from None
        if f.bound is not None and len(data) > f.bound:
            raise ConversionError(f"The '{f.name}' array.array() must have a size <= {f.bound}")
        return data.tolist()

    @staticmethod
    def _r2_numpy(f: FieldSpec, value: list[Any] | tuple[Any, ...]) -> list[Any]:
        assert f.fixed_len is not None
        # rosbridge assigns into the numpy array (inst[:] = msg); these are numpy's texts.
        items: list[Any] = []
        for item in value:
            if isinstance(item, (list, tuple, dict)):
                raise ConversionError("setting an array element with a sequence.")
            if item is None:
                raise ConversionError("float() argument must be a string or a real number, not 'NoneType'")
            try:
                number = float(item)
            except ValueError:
                raise ConversionError(f"could not convert string to float: {item!r}") from None
            items.append(number if f.cat == Cat.FLOAT else int(number))
        if len(items) != f.fixed_len:
            raise ConversionError(
                f"could not broadcast input array from shape ({len(items)},) into shape ({f.fixed_len},)"
            )
        return items

    @staticmethod
    def _r2_primitive(f: FieldSpec, value: Any, root: str, path: list[str], *, setter: bool) -> Any:
        if not isinstance(value, (bool, int, float, str)):
            raise ConversionError(f"msg is not a primitive type, but a {type(value)}")
        cat = f.cat
        if isinstance(value, int) and cat == Cat.FLOAT:
            # rosbridge casts any int (bools included) to float for float fields.
            try:
                return float(value)
            except OverflowError as exc:
                raise ConversionError(str(exc)) from None
        if cat == Cat.OCTET and isinstance(value, int):
            if not 0 <= value < 256:
                raise ConversionError("bytes must be in range(0, 256)")
            return int(value)
        kind = type(value)
        if kind is bool:
            ok = cat == Cat.BOOL
        elif kind is int:
            ok = cat == Cat.INT
        elif kind is float:
            ok = cat == Cat.FLOAT
        else:
            ok = cat == Cat.STRING
        if not ok:
            raise mismatch(root, path, f.prim, value)
        if setter and isinstance(value, int) and cat == Cat.INT and not f.lo <= value <= f.hi:
            if f.lo == 0:
                raise ConversionError(f"The '{f.name}' field must be an unsigned integer in [0, {f.hi}]")
            raise ConversionError(f"The '{f.name}' field must be an integer in [{f.lo}, {f.hi}]")
        if setter and isinstance(value, str) and f.string_bound is not None and len(value) > f.string_bound:
            raise ConversionError(
                f"The '{f.name}' field must be string value not longer than {f.string_bound}"
            )
        return value

    @staticmethod
    def _r2_time(f: FieldSpec, value: Any, clock: Now) -> JsonDict:
        rostype = "builtin_interfaces/Time" if f.cat == Cat.TIME else "builtin_interfaces/Duration"
        if not isinstance(value, (dict, str)):
            raise ConversionError(f"msg is not dict or str, but a {type(value)}")
        if isinstance(value, str):
            if f.cat == Cat.TIME and value == "now":
                return clock.ros2()
            raise ConversionError(f"Invalid string for {rostype}: {value}")
        out = {"sec": 0, "nanosec": 0}
        # Both spellings are read, ROS 2 first; other keys are ignored.
        for target, keys, lo, hi in (
            ("sec", ("sec", "secs"), -(2**31), 2**31 - 1),
            ("nanosec", ("nanosec", "nsecs"), 0, 2**32 - 1),
        ):
            for key in keys:
                if key in value:
                    item = value[key]
                    if not isinstance(item, int):
                        raise ConversionError(f"The '{target}' field must be of type 'int'")
                    if not lo <= item <= hi:
                        kind = "an unsigned integer" if lo == 0 else "an integer"
                        raise ConversionError(f"The '{target}' field must be {kind} in [{lo}, {hi}]")
                    out[target] = int(item)
                    break
        return out

    @staticmethod
    def _r2_binary(f: FieldSpec, value: Any) -> str:
        if not isinstance(value, (str, list, tuple)):
            raise ConversionError(f"msg is not a Sequence, but a {type(value)}")
        # Fast paths (a 640x480 image is 921 600 elements): decoded base64 is bytes, in range by
        # construction; bytes() of a list checks int-ness and range in C with the same verdict as an
        # element-by-element isinstance(v, int) and 0 <= v < 256 (bools pass, floats and None do not).
        data: bytes | None
        if isinstance(value, str):
            try:
                data = base64.b64decode(value)
            except (ValueError, binascii.Error) as exc:
                raise ConversionError(str(exc)) from None
        else:
            try:
                data = bytes(value)
            except (TypeError, ValueError, OverflowError):
                data = None
        ok = data is not None
        if f.fixed_len is not None:
            ok = ok and data is not None and len(data) == f.fixed_len
            length = f" with length {f.fixed_len}"
        else:
            length = ""
        if not ok or data is None:
            raise ConversionError(
                f"The '{f.name}' field must be a set or sequence{length} and each value of type 'int' "
                "and each unsigned integer in [0, 255]"
            )
        return b64(data)
