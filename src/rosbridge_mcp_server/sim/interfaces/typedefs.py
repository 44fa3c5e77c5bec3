"""rosapi's TypeDefs (``message_details``, ``service_*_details``, ``action_*_details``) and full definition
texts (``topics_and_raw_types``), as each rosapi builds them from message instances."""

from __future__ import annotations

from typing import Any, Protocol

from .base import Dialect, InterfaceError, Kind
from .pyrepr import py_default_str, py_str, slot_types_repr
from .specs import Cat, FieldSpec, MessageSpec

__all__ = ["SpecSource", "TypeDefs"]

_SEPARATOR = "=" * 80
_ROS1_ATOMICS = frozenset(
    {"bool", "byte", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64"}
    | {"float32", "float64", "string"}
)
_ROS2_ATOMICS = _ROS1_ATOMICS | {"boolean", "float", "double", "octet"}


class SpecSource(Protocol):
    """What the TypeDefs need from the registry: its dialect, type names, and the parsed definitions."""

    @property
    def dialect(self) -> Dialect: ...

    def resolve(self, name: str, kind: Kind) -> str: ...

    def spec(self, name: str) -> MessageSpec: ...

    def service_parts(self, srv_type: str) -> tuple[str, str]: ...

    def action_parts(self, action_type: str) -> tuple[str, str, str]: ...


class TypeDefs:
    """The TypeDef lists and definition texts of one registry."""

    def __init__(self, source: SpecSource) -> None:
        self.source = source
        self.dialect = source.dialect

    def _spec(self, name: str) -> MessageSpec:
        return self.source.spec(name)

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
                self.source.service_parts(type_name) if kind == "srv" else self.source.action_parts(type_name)
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
            canonical = self.source.resolve(type_name, "msg")
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
                examples.append(py_str(f))
            members[f.name] = py_str(f)
            if f.default is not None:
                members[f"{f.name.upper()}__DEFAULT"] = py_default_str(f)
        for const in spec.constants:
            members[const.name] = str(const.value)
        members["SLOT_TYPES"] = slot_types_repr(spec)
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
