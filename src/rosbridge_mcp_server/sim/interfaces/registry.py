"""The interface registry of the simulated robot: type resolution, rosapi TypeDefs and rosbridge's conversion.

Behaviour mirrored from rosbridge_suite (read in its source, not run):

* ROS 1 = 0.11.17 (``ros1`` branch): ``ros_loader.py``, ``message_conversion.py``, ``rosapi/objectutils.py``.
* ROS 2 = 2.0.8 / 2.7.1 / 3.3.1 / 4.2.1 (identical there): the same files plus rclpy's generated setters.

The registry resolves names and owns the parsed definitions; the work is done by its parts: the inbound
conversion of each dialect (:mod:`.ros1`, :mod:`.ros2`), rosapi's TypeDefs and texts (:mod:`.typedefs`, with
rclpy's value formatting in :mod:`.pyrepr`), and the outbound JSON form (here).
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable
from typing import Any

from .base import (
    ConversionError,
    Dialect,
    InterfaceError,
    JsonDict,
    Kind,
    Now,
    b64,
    default_field,
    default_msg,
    no_field,
    split_seconds,
)
from .cbor_form import cbor_form
from .definitions import COMMON, ROS1_ONLY, ROS2_ONLY, ROSAPI_2_1, to_ros1_text
from .definitions_arm import ARM, ARM_ROS1
from .definitions_nav2 import KILTED, NAV2
from .ros1 import Ros1Conversion
from .ros2 import Ros2Conversion
from .specs import Cat, FieldSpec, MessageSpec, ParsedTable, parse_table
from .typedefs import TypeDefs

__all__ = ["ConversionError", "Dialect", "InterfaceError", "InterfaceRegistry", "Kind"]

# rospkg's ResourceNotFound lists the package path after the name; a stock Noetic install has one entry.
_ROS1_PACKAGE_PATH = "/opt/ros/noetic/share"


@functools.cache
def _table_for(dialect: Dialect, rosapi: str, distro: str = "") -> ParsedTable:
    # Parsed once per process: the specs are never mutated after linking, so robots share them. (Two threads
    # missing at once may both parse; either table is right.)
    if dialect == "ros2":
        texts = {**COMMON, **NAV2, **ARM, **ROS2_ONLY}
        if distro in KILTED_ON:
            texts.update(KILTED)
        if rosapi == "2.1.0":
            for key, text in ROSAPI_2_1.items():
                if text is None:
                    texts.pop(key, None)
                else:
                    texts[key] = text
    else:
        texts = {key: to_ros1_text(text) for key, text in {**COMMON, **NAV2, **ARM_ROS1}.items()}
        texts.update(ROS1_ONLY)
    return parse_table(dialect, texts)


#: The distros whose nav2_msgs take ``nav_msgs/Goals`` (:data:`~.definitions_nav2.KILTED`).
KILTED_ON = ("kilted", "rolling")


def _finite_or_none(value: float) -> float | None:
    return value if math.isfinite(value) else None


class InterfaceRegistry:
    """Every interface type the simulated robot knows, in one dialect.

    ``clock`` gives "now" in seconds for header stamps and ``"now"`` times (default: wall clock); ``rosapi``
    ``"2.1.0"`` (ROS 2) has rosapi_msgs as rosbridge_suite 2.1.0 ships them; ``distro`` (ROS 2) picks the
    interfaces that changed between distros (Kilted's nav2_msgs). The parsed definitions are
    shared by every registry of a dialect, the per-registry caches are small dicts.
    """

    def __init__(
        self,
        dialect: Dialect,
        *,
        clock: Callable[[], float] | None = None,
        rosapi: str = "newest",
        distro: str = "",
    ) -> None:
        if dialect not in ("ros1", "ros2"):
            raise ValueError(f"unknown dialect {dialect!r}")
        self.dialect: Dialect = dialect
        self._clock = clock or time.time
        self._table = _table_for(dialect, rosapi, distro)
        self._packages: set[str] = set()
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
        self._ros1 = Ros1Conversion()
        self._ros2 = Ros2Conversion()
        self._typedefs = TypeDefs(self)

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

    def spec(self, name: str) -> MessageSpec:
        """The parsed definition behind a message name, a service part or an action part."""
        return self._spec(name)

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

    def field_names(self, msg_type: str) -> list[str]:
        """The fields of a message (or service/action part) in definition order."""
        return [f.name for f in self._spec(msg_type).fields]

    def constants(self, msg_type: str) -> dict[str, Any]:
        return {const.name: const.value for const in self._spec(msg_type).constants}

    # ------------------------------------------------------------------ defaults

    def default(self, msg_type: str) -> dict[str, Any]:
        """The JSON form of a message with every field at its default."""
        return default_msg(self._spec(msg_type), self.dialect)

    # ------------------------------------------------------------------ inbound (JSON -> message)

    def from_json(self, msg_type: str, value: Any, *, now: float | None = None) -> dict[str, Any]:
        """rosbridge's inbound conversion (``populate_instance``) with its strictness and texts.

        Returns the message in the JSON form ``to_json`` produces, except that non-finite floats stay
        floats (they are the message's value; ``to_json`` decides how they travel). ``now`` (seconds)
        overrides the registry clock for header stamps and ``"now"`` times.
        """
        spec = self._spec(msg_type)
        clock = Now(self._clock, now)
        if self.dialect == "ros1":
            return self._ros1.from_json(spec, value, clock)
        return self._ros2.from_json(spec, value, clock)

    def ros1_wire(self, msg_type: str, value: dict[str, Any]) -> dict[str, Any]:
        """A converted ROS 1 message as a subscriber receives it after genpy packed and unpacked it.

        float32 values come back rounded to float32; times are packed as two uint32 and durations as two
        int32, and unpacked canonical (``nsecs`` in [0, 1e9), the rest carried into ``secs``). A value
        that does not pack raises :class:`ConversionError` with struct's text, as rospy's publish does
        (the message is lost). Messages without such fields are returned as they are.
        """
        return self._ros1.wire(self._spec(msg_type), value)

    def has_header(self, msg_type: str) -> bool:
        """genpy's ``_has_header``: the first field is ``std_msgs/Header header`` (rospy sets its seq)."""
        return Ros1Conversion.has_header(self._spec(msg_type))

    # ------------------------------------------------------------------ outbound (message -> JSON)

    def to_json(self, msg_type: str, value: dict[str, Any]) -> dict[str, Any]:
        """The JSON form rosbridge sends for a message given as a plain dict (missing fields = defaults).

        Byte arrays become base64, times take the dialect's spelling (either spelling or float seconds
        accepted), non-finite floats become ``None`` except inside ROS 2 fixed-size float arrays, which
        rosbridge passes through as numpy values (the JSON writer emits bare ``NaN``).
        """
        return self._out_msg(self._spec(msg_type), value)

    def to_cbor(
        self, msg_type: str, json_form: dict[str, Any], *, fixed_lists: bool = False
    ) -> dict[str, Any]:
        """The values rosbridge encodes as CBOR for a message in its JSON form (typed arrays, bytes);
        ``fixed_lists`` as rosbridge-server-rs does (fixed-size arrays as lists, not a failure)."""
        return cbor_form(self._spec(msg_type), json_form, fixed_lists=fixed_lists)

    def _out_msg(self, spec: MessageSpec, value: Any) -> JsonDict:
        if not isinstance(value, dict):
            raise ConversionError(f"{spec.short} needs a dict, got {type(value).__name__}")
        for key in value:
            if key not in spec.field_map:
                raise no_field(spec.short, [key])
        return {
            f.name: self._out_field(f, value[f.name]) if f.name in value else default_field(f, self.dialect)
            for f in spec.fields
        }

    def _out_field(self, f: FieldSpec, value: Any) -> Any:
        if f.binary:
            if isinstance(value, str):
                return value
            return b64(bytes(value))
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
            secs, nsecs = split_seconds(float(value))
        if self.dialect == "ros1":
            return {"secs": secs, "nsecs": nsecs}
        return {"sec": secs, "nanosec": nsecs}

    # ------------------------------------------------------------------ rosapi

    # ------------------------------------------------------------------ rosapi

    def message_typedefs(self, msg_type: str) -> list[dict[str, Any]]:
        """rosapi ``message_details``: the root TypeDef, then every nested type once, depth first.

        ROS 2 returns ``[]`` for an unknown type (rosapi logs the loader error, 2.0.2+); ROS 1 raises
        :class:`InterfaceError`, which fails the rosapi call as the loader's exception does in 0.11.
        """
        return self._typedefs.message_typedefs(msg_type)

    def service_request_typedefs(self, srv_type: str) -> list[dict[str, Any]]:
        return self._typedefs.service_request_typedefs(srv_type)

    def service_response_typedefs(self, srv_type: str) -> list[dict[str, Any]]:
        return self._typedefs.service_response_typedefs(srv_type)

    def action_goal_typedefs(self, action_type: str) -> list[dict[str, Any]]:
        return self._typedefs.action_goal_typedefs(action_type)

    def action_result_typedefs(self, action_type: str) -> list[dict[str, Any]]:
        return self._typedefs.action_result_typedefs(action_type)

    def action_feedback_typedefs(self, action_type: str) -> list[dict[str, Any]]:
        return self._typedefs.action_feedback_typedefs(action_type)

    def full_text(self, msg_type: str) -> str:
        """The definition with every nested definition after a separator (rosapi ``topics_and_raw_types``)."""
        return self._typedefs.full_text(msg_type)
