"""The interface registry of the simulated robot: type resolution, rosapi TypeDefs and rosbridge's conversion.

Behaviour mirrored from rosbridge_suite (read in its source, not run):

* ROS 1 = 0.11.17 (``ros1`` branch): ``ros_loader.py``, ``message_conversion.py``, ``rosapi/objectutils.py``;
  serialization failures use genpy's ``check_type`` texts.
* ROS 2 = 2.0.8 / 2.7.1 / 3.3.1 / 4.2.1 (identical there): the same files plus rclpy's generated setters
  (rosidl_generator_py ``_msg.py.em``) whose assertions surface as error texts.
"""

from __future__ import annotations

import array
import base64
import binascii
import math
import struct
import threading
import time
import zlib
from collections.abc import Callable
from typing import Any, Literal

from .definitions import COMMON, ROS1_ONLY, ROS2_ONLY, to_ros1_text
from .specs import Cat, FieldSpec, MessageSpec, ParsedTable, parse_table

__all__ = ["ConversionError", "Dialect", "InterfaceError", "InterfaceRegistry", "Kind"]

Dialect = Literal["ros1", "ros2"]
Kind = Literal["msg", "srv", "action"]
JsonDict = dict[str, Any]


class InterfaceError(Exception):
    """An unknown or malformed type name; ``str()`` is the text the real server logs or returns."""


class ConversionError(Exception):
    """A JSON value that does not fit its type; ``str()`` mirrors rosbridge's text for the same input."""


# rospkg's ResourceNotFound lists the package path after the name; a stock Noetic install has one entry.
_ROS1_PACKAGE_PATH = "/opt/ros/noetic/share"
_SEPARATOR = "=" * 80
_ROS1_ATOMICS = frozenset(
    {"bool", "byte", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64"}
    | {"float32", "float64", "string"}
)
_ROS2_ATOMICS = _ROS1_ATOMICS | {"boolean", "float", "double", "octet"}
_PY_TYPE = {Cat.BOOL: "bool", Cat.INT: "int", Cat.FLOAT: "float", Cat.STRING: "str", Cat.OCTET: "bytes"}

_tables: dict[str, ParsedTable] = {}
_tables_lock = threading.Lock()


def _table_for(dialect: Dialect) -> ParsedTable:
    # Parsed once per process: the specs are never mutated after linking, so robots share them.
    with _tables_lock:
        table = _tables.get(dialect)
        if table is None:
            if dialect == "ros2":
                texts = {**COMMON, **ROS2_ONLY}
            else:
                texts = {key: to_ros1_text(text) for key, text in COMMON.items()}
                texts.update(ROS1_ONLY)
            table = parse_table(dialect, texts)
            _tables[dialect] = table
        return table


def _mismatch(root: str, stack: list[str], expected: str, found: Any) -> ConversionError:
    # rosbridge's FieldTypeMismatchException (same text in ROS 1 0.11 and every ROS 2 release).
    if root == expected:
        return ConversionError(f"Expected a JSON object for type {root} but received a {type(found)}")
    return ConversionError(
        f"{root} message requires a {expected} for field {'.'.join(stack)}, but got a {type(found)}"
    )


def _no_field(root: str, stack: list[str]) -> ConversionError:
    return ConversionError(f"Message type {root} does not have a field {'.'.join(stack)}")


def _b64(data: bytes) -> str:
    return base64.b64encode(data).decode("ascii")


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


def _finite_or_none(value: float) -> float | None:
    return value if math.isfinite(value) else None


class InterfaceRegistry:
    """Every interface type the simulated robot knows, in one dialect.

    ``clock`` gives "now" in seconds for header stamps and ``"now"`` times (default: wall clock); the parsed
    definitions are shared by every registry of a dialect, the per-registry caches are small dicts.
    """

    def __init__(self, dialect: Dialect, *, clock: Callable[[], float] | None = None) -> None:
        if dialect not in ("ros1", "ros2"):
            raise ValueError(f"unknown dialect {dialect!r}")
        self.dialect: Dialect = dialect
        self._clock = clock or time.time
        self._table = _table_for(dialect)
        self._packages: set[str] = set()
        self._wire_cache: dict[str, bool] = {}
        self._modules: dict[tuple[str, str], dict[str, Kind]] = {}
        for key in self._table.msg_names:
            self._add_module(key, "msg")
        for key in self._table.services:
            self._add_module(key, "srv")
        for key in self._table.actions:
            if dialect == "ros2":
                self._add_module(key, "action")
        self._lookup_cache: dict[str, MessageSpec] = {}
        self._resolve_cache: dict[tuple[str, str], str] = {}

    def _add_module(self, key: str, kind: Kind) -> None:
        pkg, _, name = key.split("/")
        self._packages.add(pkg)
        self._modules.setdefault((pkg, kind), {})[name] = kind

    # ------------------------------------------------------------------ names

    def resolve(self, name: str, kind: Kind) -> str:
        """The canonical name of a type, or :class:`InterfaceError` with the real server's text."""
        cached = self._resolve_cache.get((name, kind))
        if cached is not None:
            return cached
        canonical = (
            self._resolve_ros2(name, kind) if self.dialect == "ros2" else self._resolve_ros1(name, kind)
        )
        self._resolve_cache[(name, kind)] = canonical
        return canonical

    def has(self, name: str, kind: Kind) -> bool:
        try:
            self.resolve(name, kind)
        except InterfaceError:
            return False
        return True

    def _resolve_ros2(self, name: str, kind: Kind) -> str:
        # ros_loader._get_interface_class: try the middle segment as module, then fall back to the kind's
        # own module; the second attempt's error is the one raised. Names of 1 or 4+ parts fail in _splittype.
        splits = [part for part in name.split("/") if part]
        if len(splits) not in (2, 3):
            raise InterfaceError(f"{name} is not a valid type string")
        pkg, cls = splits[0], splits[-1]
        first = splits[1] if len(splits) == 3 else kind
        found, error = self._load_ros2(pkg, first, cls, kind)
        if found is None:
            found, error = self._load_ros2(pkg, kind, cls, kind)
        if found is None:
            raise InterfaceError(error)
        return found

    def _load_ros2(self, pkg: str, sub: str, cls: str, kind: Kind) -> tuple[str | None, str]:
        if pkg not in self._packages:
            return (
                None,
                f"Unable to import {pkg}.{sub} from package {pkg}. Caused by: No module named '{pkg}'",
            )
        module = self._modules.get((pkg, sub)) if sub in ("msg", "srv", "action") else None
        if module is None:
            return None, (
                f"Unable to import {pkg}.{sub} from package {pkg}. Caused by: No module named '{pkg}.{sub}'"
            )
        missing = cls
        if sub == "action" and kind == "msg" and cls.endswith("_FeedbackMessage"):
            # ros_loader special case (2.0.3 / 2.4.1 / 3.0.1+): X_FeedbackMessage comes from X.Impl.
            action_name = cls.rsplit("_", 1)[0]
            if action_name in module:
                return f"{pkg}/action/{cls}", ""
            missing = action_name
        elif module.get(cls) == kind:
            return f"{pkg}/{kind}/{cls}", ""
        return None, (
            f"Unable to import {sub} class {cls} from package {pkg}. "
            f"Caused by module '{pkg}.{sub}' has no attribute '{missing}'"
        )

    def _resolve_ros1(self, name: str, kind: Kind) -> str:
        splits = [part for part in name.split("/") if part]
        if len(splits) != 2:
            raise InterfaceError(f"{name} is not a valid type string")
        pkg, cls = splits
        if pkg not in self._packages:
            raise InterfaceError(
                f"Unable to load the manifest for package {pkg}. "
                f"Caused by: {pkg}\nROS path [0]={_ROS1_PACKAGE_PATH}"
            )
        if kind == "action":
            # ROS 1 rosbridge loads no actions; we accept the .action base name and its XAction message.
            base = cls[: -len("Action")] if cls.endswith("Action") else cls
            if f"{pkg}/action/{base}" in self._table.actions:
                return f"{pkg}/{base}"
            sub: str = "msg"
        else:
            sub = kind
        module = self._modules.get((pkg, sub))
        if module is None:
            raise InterfaceError(
                f"Unable to import {pkg}.{sub} from package {pkg}. Caused by: No module named '{pkg}.{sub}'"
            )
        if module.get(cls) != kind:
            raise InterfaceError(
                f"Unable to import {sub} class {cls} from package {pkg}. "
                f"Caused by module '{pkg}.{sub}' has no attribute '{cls}'"
            )
        return f"{pkg}/{cls}"

    def all_interfaces(self) -> list[str]:
        """Every known type by canonical name (ROS 2: what rosapi ``interfaces`` lists)."""
        if self.dialect == "ros2":
            names = [*self._table.msg_names, *self._table.services, *self._table.actions]
            return sorted(names)
        return sorted(
            f"{key.split('/')[0]}/{key.split('/')[2]}"
            for key in (*self._table.msg_names, *self._table.services)
        )

    def service_parts(self, srv_type: str) -> tuple[str, str]:
        """Request and response message names of a service, usable with every message-level method."""
        canonical = self.resolve(srv_type, "srv")
        pkg, name = canonical.split("/")[0], canonical.split("/")[-1]
        request, response = self._table.services[f"{pkg}/srv/{name}"]
        return self._public_part(request), self._public_part(response)

    def action_parts(self, action_type: str) -> tuple[str, str, str]:
        """Goal, result and feedback message names (ROS 2 ``pkg/action/X_Goal``; ROS 1 ``pkg/XGoal``)."""
        canonical = self.resolve(action_type, "action")
        pkg, name = canonical.split("/")[0], canonical.split("/")[-1]
        goal, result, feedback = self._table.actions[f"{pkg}/action/{name}"]
        return self._public_part(goal), self._public_part(result), self._public_part(feedback)

    def _public_part(self, key: str) -> str:
        if self.dialect == "ros2":
            return key
        pkg, _, name = key.split("/")
        return f"{pkg}/{name}"

    def _spec(self, name: str) -> MessageSpec:
        """The message spec behind a message name, a service part or an action part."""
        spec = self._lookup_cache.get(name)
        if spec is not None:
            return spec
        messages = self._table.messages
        spec = messages.get(name)
        if spec is None:
            splits = [part for part in name.split("/") if part]
            if len(splits) == 2:
                pkg, cls = splits
                for kind in ("msg", "srv", "action"):
                    spec = messages.get(f"{pkg}/{kind}/{cls}")
                    if spec is not None:
                        break
            elif len(splits) == 3:
                spec = messages.get("/".join(splits))
        if spec is None:
            canonical = self.resolve(name, "msg")
            pkg, cls = canonical.split("/")[0], canonical.split("/")[-1]
            spec = messages.get(f"{pkg}/msg/{cls}") or messages[f"{pkg}/action/{cls}"]
        self._lookup_cache[name] = spec
        return spec

    def constants(self, msg_type: str) -> dict[str, Any]:
        return {const.name: const.value for const in self._spec(msg_type).constants}

    # ------------------------------------------------------------------ defaults

    def default(self, msg_type: str) -> dict[str, Any]:
        """The JSON form of a message with every field at its default."""
        return self._default_msg(self._spec(msg_type))

    def _zero_time(self) -> JsonDict:
        return {"secs": 0, "nsecs": 0} if self.dialect == "ros1" else {"sec": 0, "nanosec": 0}

    def _default_msg(self, spec: MessageSpec) -> JsonDict:
        return {f.name: self._default_field(f) for f in spec.fields}

    def _default_field(self, f: FieldSpec) -> Any:
        if f.is_array:
            if f.default is not None:
                values = list(f.default)
                return _b64(bytes(values)) if f.binary else values
            count = f.fixed_len or 0
            if f.binary:
                return _b64(bytes(count))
            return [self._default_scalar(f) for _ in range(count)]
        return self._default_scalar(f)

    def _default_scalar(self, f: FieldSpec) -> Any:
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
            return self._zero_time()
        assert f.msg is not None
        return self._default_msg(f.msg)

    # ------------------------------------------------------------------ inbound (JSON -> message)

    def _now(self, now: float | None) -> tuple[int, int]:
        stamp = self._clock() if now is None else now
        secs = math.floor(stamp)
        nsecs = min(round((stamp - secs) * 1e9), 999_999_999)
        return int(secs), nsecs

    def from_json(self, msg_type: str, value: Any, *, now: float | None = None) -> dict[str, Any]:
        """rosbridge's inbound conversion (``populate_instance``) with its strictness and texts.

        Returns the message in the JSON form ``to_json`` produces, except that non-finite floats stay
        floats (they are the message's value; ``to_json`` decides how they travel). ``now`` (seconds)
        overrides the registry clock for header stamps and ``"now"`` times.
        """
        spec = self._spec(msg_type)
        clock = _Now(self, now)
        if self.dialect == "ros1":
            return self._r1_msg(spec, value, spec.short, [], expected=spec.short, clock=clock)
        return self._r2_root(spec, value, clock)

    # ROS 1 (0.11.17) ---------------------------------------------------------

    def _r1_msg(
        self, spec: MessageSpec, value: Any, root: str, stack: list[str], *, expected: str, clock: _Now
    ) -> JsonDict:
        if type(value) is not dict:
            raise _mismatch(root, stack, expected, value)
        # Every std_msgs/Header object present is stamped with the current time before its fields apply
        # (0.11.17 _to_object_inst), so a partial stamp keeps the other half of "now".
        stamp = clock.ros1() if spec.is_header else None
        converted: JsonDict = {}
        for key, item in value.items():
            f = spec.field_map.get(key)
            path = [*stack, key]
            if f is None:
                raise _no_field(root, path)
            base = stamp if (stamp is not None and key == "stamp") else None
            converted[key] = self._r1_field(f, item, root, path, clock=clock, base=base)
        out: JsonDict = {}
        for f in spec.fields:
            if f.name in converted:
                out[f.name] = converted[f.name]
            elif stamp is not None and f.name == "stamp":
                out[f.name] = dict(stamp)
            else:
                out[f.name] = self._default_field(f)
        return out

    def _r1_field(
        self, f: FieldSpec, value: Any, root: str, path: list[str], *, clock: _Now, base: JsonDict | None
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
            raise _mismatch(root, path, f.wire_type, value)
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
            raise _mismatch(root, path, f.prim, value)
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
    def _r1_time(cat: Cat, value: Any, base: JsonDict | None, clock: _Now, path: list[str]) -> JsonDict:
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
        return _b64(data)

    # ROS 2 (2.0.8 / 2.7.1 / 3.3.1 / 4.2.1) -------------------------------------

    def _r2_root(self, spec: MessageSpec, value: Any, clock: _Now) -> JsonDict:
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
                raise _mismatch(root, ["header"], "dict", given)
            stamp = given is None or "stamp" not in given
        out = self._r2_msg(spec, value, root, [], clock)
        if stamp:
            out["header"]["stamp"] = clock.ros2()
        return out

    def _r2_msg(self, spec: MessageSpec, value: Any, root: str, stack: list[str], clock: _Now) -> JsonDict:
        if not isinstance(value, dict):
            if not stack:
                raise _mismatch(root, stack, root, value)
            raise ConversionError(f"msg is not a dict, but a {type(value)}")
        converted: JsonDict = {}
        for key, item in value.items():
            f = spec.field_map.get(key)
            path = [*stack, key]
            if f is None:
                raise _no_field(root, path)
            converted[key] = self._r2_field(f, item, root, path, clock)
        return {
            f.name: converted[f.name] if f.name in converted else self._default_field(f) for f in spec.fields
        }

    def _r2_field(self, f: FieldSpec, value: Any, root: str, path: list[str], clock: _Now) -> Any:
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
            raise _mismatch(root, path, f.prim, value)
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
    def _r2_time(f: FieldSpec, value: Any, clock: _Now) -> JsonDict:
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
        return _b64(data)

    # ------------------------------------------------------------------ ROS 1 serialization (genpy)

    def ros1_wire(self, msg_type: str, value: dict[str, Any]) -> dict[str, Any]:
        """A converted ROS 1 message as a subscriber receives it after genpy packed and unpacked it.

        float32 values come back rounded to float32; times are packed as two uint32 and durations as two
        int32, and unpacked canonical (``nsecs`` in [0, 1e9), the rest carried into ``secs``). A value
        that does not pack raises :class:`ConversionError` with struct's text, as rospy's publish does
        (the message is lost). Messages without such fields are returned as they are.
        """
        spec = self._spec(msg_type)
        if not self._needs_wire(spec):
            return value
        return self._wire_msg(spec, value, [])

    def has_header(self, msg_type: str) -> bool:
        """genpy's ``_has_header``: the first field is ``std_msgs/Header header`` (rospy sets its seq)."""
        fields = self._spec(msg_type).fields
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

    # ------------------------------------------------------------------ outbound (message -> JSON)

    def to_json(self, msg_type: str, value: dict[str, Any]) -> dict[str, Any]:
        """The JSON form rosbridge sends for a message given as a plain dict (missing fields = defaults).

        Byte arrays become base64, times take the dialect's spelling (either spelling or float seconds
        accepted), non-finite floats become ``None`` except inside ROS 2 fixed-size float arrays, which
        rosbridge passes through as numpy values (the JSON writer emits bare ``NaN``).
        """
        return self._out_msg(self._spec(msg_type), value)

    def _out_msg(self, spec: MessageSpec, value: Any) -> JsonDict:
        if not isinstance(value, dict):
            raise ConversionError(f"{spec.short} needs a dict, got {type(value).__name__}")
        for key in value:
            if key not in spec.field_map:
                raise _no_field(spec.short, [key])
        return {
            f.name: self._out_field(f, value[f.name]) if f.name in value else self._default_field(f)
            for f in spec.fields
        }

    def _out_field(self, f: FieldSpec, value: Any) -> Any:
        if f.binary:
            if isinstance(value, str):
                return value
            return _b64(bytes(value))
        if not f.is_array:
            return self._out_scalar(f, value)
        if f.cat == Cat.FLOAT:
            if f.numpy:
                return [float(v) for v in value]
            return [_finite_or_none(float(v)) for v in value]
        return [self._out_scalar(f, v) for v in value]

    def _out_scalar(self, f: FieldSpec, value: Any) -> Any:
        cat = f.cat
        if cat == Cat.FLOAT:
            return _finite_or_none(float(value))
        if cat == Cat.INT:
            return int(value)
        if cat == Cat.BOOL:
            return bool(value)
        if cat == Cat.STRING:
            return str(value)
        if cat == Cat.OCTET:
            return value[0] if isinstance(value, (bytes, bytearray)) else int(value)
        if cat in (Cat.TIME, Cat.DURATION):
            return self._out_time(value)
        assert f.msg is not None
        return self._out_msg(f.msg, value)

    def _out_time(self, value: Any) -> JsonDict:
        if isinstance(value, dict):
            secs = int(value["secs"] if "secs" in value else value.get("sec", 0))
            nsecs = int(value["nsecs"] if "nsecs" in value else value.get("nanosec", 0))
        else:
            secs, nsecs = self._now(float(value))
        if self.dialect == "ros1":
            return {"secs": secs, "nsecs": nsecs}
        return {"sec": secs, "nanosec": nsecs}

    # ------------------------------------------------------------------ rosapi

    def message_typedefs(self, msg_type: str) -> list[dict[str, Any]]:
        """rosapi ``message_details``: the root TypeDef, then every nested type once, depth first.

        ROS 2 returns ``[]`` for an unknown type (rosapi logs the loader error, 2.0.2+); ROS 1 raises
        :class:`InterfaceError`, which fails the rosapi call as the loader's exception does in 0.11.
        """
        if msg_type in _ROS2_ATOMICS or msg_type in ("time", "duration"):
            return self._typedefs_recursive(msg_type, [])
        try:
            spec = self._spec(msg_type)
        except InterfaceError:
            if self.dialect == "ros2":
                return []
            raise
        return self._subtypedefs(self._typedef(spec), [msg_type])

    def service_request_typedefs(self, srv_type: str) -> list[dict[str, Any]]:
        return self._part_typedefs(srv_type, "srv", 0)

    def service_response_typedefs(self, srv_type: str) -> list[dict[str, Any]]:
        return self._part_typedefs(srv_type, "srv", 1)

    def action_goal_typedefs(self, action_type: str) -> list[dict[str, Any]]:
        return self._part_typedefs(action_type, "action", 0)

    def action_result_typedefs(self, action_type: str) -> list[dict[str, Any]]:
        return self._part_typedefs(action_type, "action", 1)

    def action_feedback_typedefs(self, action_type: str) -> list[dict[str, Any]]:
        return self._part_typedefs(action_type, "action", 2)

    def _part_typedefs(self, type_name: str, kind: Kind, index: int) -> list[dict[str, Any]]:
        try:
            parts: tuple[str, ...] = (
                self.service_parts(type_name) if kind == "srv" else self.action_parts(type_name)
            )
        except InterfaceError:
            if self.dialect == "ros2":
                return []
            raise
        typedef = self._typedef(self._spec(parts[index]))
        return self._subtypedefs(typedef, [])

    def _typedefs_recursive(self, type_name: str, seen: list[str]) -> list[dict[str, Any]]:
        if type_name in seen:
            return []
        seen.append(type_name)
        typedef = self._get_typedef(type_name)
        if typedef is None:
            return []
        return self._subtypedefs(typedef, seen)

    def _subtypedefs(self, typedef: dict[str, Any], seen: list[str]) -> list[dict[str, Any]]:
        typedefs = [typedef]
        for field_type in typedef["fieldtypes"]:
            typedefs.extend(self._typedefs_recursive(field_type, seen))
        return typedefs

    def _get_typedef(self, type_name: str) -> dict[str, Any] | None:
        if self.dialect == "ros1":
            if type_name in _ROS1_ATOMICS:
                return None
            if type_name in ("time", "duration"):
                return {
                    "type": type_name,
                    "fieldnames": ["secs", "nsecs"],
                    "fieldtypes": ["int32", "int32"],
                    "fieldarraylen": [-1, -1],
                    "examples": ["0", "0"],
                    "constnames": [],
                    "constvalues": [],
                }
            # An unknown name (also the 'builtin/int' of a char field) raises, failing the rosapi call.
            return self._typedef(self._spec(type_name))
        if type_name.startswith("sequence<") and type_name.endswith(">"):
            type_name = type_name[len("sequence<") : -1]
        if type_name in _ROS2_ATOMICS:
            return None
        try:
            canonical = self.resolve(type_name, "msg")
        except InterfaceError:
            return None  # rosapi 2.0.2+ logs "An error occurred trying to get the type definition ..."
        return self._typedef(self._spec(canonical))

    def _typedef(self, spec: MessageSpec) -> dict[str, Any]:
        return _Ros1TypeDefs.build(spec) if self.dialect == "ros1" else _Ros2TypeDefs.build(spec)

    def full_text(self, msg_type: str) -> str:
        """The definition with every nested definition after a separator (rosapi ``topics_and_raw_types``)."""
        spec = self._spec(msg_type)
        if self.dialect == "ros1":
            # genpy's _full_text: root, then dependencies depth first in field order, each once.
            deps: list[MessageSpec] = []
            self._ros1_depends(spec, deps)
            text = spec.text + "\n"
            for dep in deps:
                text += f"{_SEPARATOR}\nMSG: {dep.short}\n{dep.text}\n"
            return text[:-1]
        # rosapi stringify_field_types: a stack (last pushed first), root under the name it was asked by.
        definition = ""
        seen: set[str] = set()
        stack: list[tuple[str, MessageSpec]] = [(msg_type, spec)]
        is_root = True
        while stack:
            name, current = stack.pop()
            if not is_root:
                definition += f"\n{_SEPARATOR}\nMSG: {name}\n"
            is_root = False
            definition += current.text
            for f in current.fields:
                if f.msg is not None and f.prim not in seen:
                    stack.append((f.prim, f.msg))
                    seen.add(f.prim)
        return definition

    def _ros1_depends(self, spec: MessageSpec, out: list[MessageSpec]) -> None:
        for f in spec.fields:
            dep = f.msg
            if dep is None or f.cat in (Cat.TIME, Cat.DURATION):
                continue
            if dep not in out:
                out.append(dep)
            self._ros1_depends(dep, out)


class _Now:
    """The current time, read at most once per conversion."""

    __slots__ = ("_registry", "_stamp", "_value")

    def __init__(self, registry: InterfaceRegistry, stamp: float | None) -> None:
        self._registry = registry
        self._stamp = stamp
        self._value: tuple[int, int] | None = None

    def _get(self) -> tuple[int, int]:
        if self._value is None:
            self._value = self._registry._now(self._stamp)
        return self._value

    def ros1(self) -> JsonDict:
        secs, nsecs = self._get()
        return {"secs": secs, "nsecs": nsecs}

    def ros2(self) -> JsonDict:
        secs, nsecs = self._get()
        return {"sec": secs, "nanosec": nsecs}


class _Ros1TypeDefs:
    """rosapi 0.11.17 objectutils._get_typedef over genpy message instances."""

    @staticmethod
    def build(spec: MessageSpec) -> dict[str, Any]:
        names: list[str] = []
        types: list[str] = []
        lengths: list[int] = []
        examples: list[str] = []
        for f in spec.fields:
            names.append(f.name)
            lengths.append(-1 if not f.is_array else (f.fixed_len or 0))
            if f.cat in (Cat.TIME, Cat.DURATION):
                field_type = "time" if f.cat == Cat.TIME else "duration"
                atomic = False
            elif f.cat == Cat.MSG:
                field_type, atomic = f.prim, False
            elif f.ros1_char:
                # 'char' is missing from rosapi's atomics, so the type comes from the Python value's class:
                # 'builtin/int' (or 'builtin/bytes' for char[]), which later fails to load.
                field_type, atomic = ("builtin/bytes" if f.is_array else "builtin/int"), False
            else:
                field_type, atomic = f.prim, True
            types.append(field_type)
            if f.is_array:
                examples.append("[]")
            elif not atomic:
                examples.append("{}")
            else:
                examples.append(_ros1_str(f))
        consts = sorted(spec.constants, key=lambda c: c.name)
        return {
            "type": spec.short,
            "fieldnames": names,
            "fieldtypes": types,
            "fieldarraylen": lengths,
            "examples": examples,
            "constnames": [c.name for c in consts],
            "constvalues": [str(c.value) for c in consts],
        }


def _ros1_str(f: FieldSpec) -> str:
    if f.cat == Cat.BOOL:
        return "False"
    if f.cat == Cat.FLOAT:
        return "0.0"
    if f.cat == Cat.STRING:
        return ""
    return "0"


class _Ros2TypeDefs:
    """rosapi 2.x-4.x objectutils over rclpy message instances, including its pseudo-constants.

    ``inspect.getmembers(instance)`` also yields ``SLOT_TYPES``, every field property and every
    ``X__DEFAULT`` of a field with a default, sorted by name; rosapi keeps them all as "constants".
    """

    @staticmethod
    def build(spec: MessageSpec) -> dict[str, Any]:
        names: list[str] = []
        types: list[str] = []
        lengths: list[int] = []
        examples: list[str] = []
        members: dict[str, str] = {}
        for f in spec.fields:
            names.append(f.name)
            lengths.append(-1 if not f.is_array else (f.fixed_len if f.fixed_len is not None else 0))
            # A bounded sequence keeps its bound: objectutils' regex captures 'T, N' from 'sequence<T, N>'.
            types.append(f.prim if f.bound is None else f"{f.prim}, {f.bound}")
            if f.is_array:
                examples.append("[]")
            elif f.cat in (Cat.MSG, Cat.TIME, Cat.DURATION):
                examples.append("{}")
            else:
                examples.append(_py_str(f))
            members[f.name] = _py_str(f)
            if f.default is not None:
                members[f"{f.name.upper()}__DEFAULT"] = _py_default_str(f)
        for const in spec.constants:
            members[const.name] = str(const.value)
        members["SLOT_TYPES"] = _slot_types_repr(spec)
        ordered = sorted(members)
        return {
            "type": spec.short,
            "fieldnames": names,
            "fieldtypes": types,
            "fieldarraylen": lengths,
            "examples": examples,
            "constnames": ordered,
            "constvalues": [members[name] for name in ordered],
        }


# --- Python reprs of rclpy default values (what str()/repr() print for a fresh message) -------------------


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


def _py_str(f: FieldSpec) -> str:
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


def _py_default_str(f: FieldSpec) -> str:
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


def _slot_types_repr(spec: MessageSpec) -> str:
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
