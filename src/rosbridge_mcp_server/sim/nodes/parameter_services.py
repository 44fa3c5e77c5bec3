"""ROS 2: the parameter services every node offers (``<node>/list_parameters``, ``get_parameters``, ...),
answered from the same store rosapi's ``get_param``/``set_param`` use, as rclpy's ``ParameterService``
answers them (texts and quirks as rclpy 7.x/9.x on the Jazzy and Kilted labs)."""

from __future__ import annotations

from typing import Any

from rosbridge_mcp_server.sim.world import World

__all__ = ["PARAMETER_SERVICES", "ParameterServices", "parameter_type", "parameter_value_msg"]

#: (service leaf, type) of the six parameter services of every rclpy/rclcpp node.
PARAMETER_SERVICES = (
    ("describe_parameters", "rcl_interfaces/srv/DescribeParameters"),
    ("get_parameter_types", "rcl_interfaces/srv/GetParameterTypes"),
    ("get_parameters", "rcl_interfaces/srv/GetParameters"),
    ("list_parameters", "rcl_interfaces/srv/ListParameters"),
    ("set_parameters", "rcl_interfaces/srv/SetParameters"),
    ("set_parameters_atomically", "rcl_interfaces/srv/SetParametersAtomically"),
)

_ARRAY_TYPES = ((bool, 6), (int, 7), (float, 8))

#: rcl_interfaces/msg/ParameterType: the field of ParameterValue that holds each type's value.
_VALUE_FIELDS = {
    1: "bool_value",
    2: "integer_value",
    3: "double_value",
    4: "string_value",
    5: "byte_array_value",
    6: "bool_array_value",
    7: "integer_array_value",
    8: "double_array_value",
    9: "string_array_value",
}


def parameter_type(value: Any) -> int:
    """``rcl_interfaces/msg/ParameterType`` of a stored value."""
    if isinstance(value, bool):
        return 1
    if isinstance(value, int):
        return 2
    if isinstance(value, float):
        return 3
    if isinstance(value, str):
        return 4
    if isinstance(value, list):
        for kind, code in _ARRAY_TYPES:
            if value and all(
                isinstance(v, kind) and (kind is bool or not isinstance(v, bool)) for v in value
            ):
                return code
        if all(isinstance(v, str) for v in value):
            return 9
    return 0


def parameter_value_msg(value: Any) -> dict[str, Any]:
    """A stored value as a ``rcl_interfaces/msg/ParameterValue`` (other fields take their defaults)."""
    code = parameter_type(value)
    field = _VALUE_FIELDS.get(code)
    return {"type": code} if field is None else {"type": code, field: value}


def _from_msg(value: dict[str, Any]) -> tuple[int, Any]:
    code = int(value.get("type", 0))
    field = _VALUE_FIELDS.get(code)
    return code, (value.get(field) if field is not None else None)


class ParameterServices:
    """The six services of one node over the shared ``/node:name`` store (``World.params``)."""

    def __init__(self, world: World, node: str) -> None:
        self.world = world
        self.node = node

    def _names(self) -> list[str]:
        prefix = f"{self.node}:"
        return [key[len(prefix) :] for key in self.world.params if key.startswith(prefix)]

    def _key(self, name: str) -> str:
        return f"{self.node}:{name}"

    async def list_parameters(self, request: dict[str, Any]) -> dict[str, Any]:
        """Every name in declaration order; a prefix matches whole dotted components (``a`` finds ``a.b``,
        not ``ab``); depth 0 is recursive, else names with fewer dots than ``depth``."""
        prefixes: list[str] = list(request.get("prefixes", []))
        depth = int(request.get("depth", 0))
        names: list[str] = []
        found_prefixes: list[str] = []
        for name in self._names():
            if prefixes and not any(name.startswith(p + ".") for p in prefixes):
                continue
            if depth and name.count(".") >= depth:
                continue
            names.append(name)
            if "." in name:
                group = name.rsplit(".", 1)[0]
                if group not in found_prefixes:
                    found_prefixes.append(group)
        return {"result": {"names": names, "prefixes": found_prefixes}}

    async def get_parameters(self, request: dict[str, Any]) -> dict[str, Any]:
        """rclpy answers nothing at all (an empty list) as soon as one name is not declared."""
        values = []
        for name in request.get("names", []):
            key = self._key(name)
            if key not in self.world.params:
                return {"values": []}
            values.append(parameter_value_msg(self.world.params[key]))
        return {"values": values}

    async def get_parameter_types(self, request: dict[str, Any]) -> dict[str, Any]:
        types = []
        for name in request.get("names", []):
            key = self._key(name)
            if key not in self.world.params:
                return {"types": []}
            types.append(parameter_type(self.world.params[key]))
        return {"types": types}

    async def describe_parameters(self, request: dict[str, Any]) -> dict[str, Any]:
        descriptors = []
        for name in request.get("names", []):
            key = self._key(name)
            if key not in self.world.params:
                return {"descriptors": []}
            descriptors.append({"name": name, "type": parameter_type(self.world.params[key])})
        return {"descriptors": descriptors}

    def _set_one(self, parameter: dict[str, Any], *, apply: bool) -> dict[str, Any]:
        name = str(parameter.get("name", ""))
        key = self._key(name)
        if key not in self.world.params:
            # rclpy's text, with its empty list.
            return {"successful": False, "reason": "Invalid access to undeclared parameter(s): []"}
        code, value = _from_msg(parameter.get("value", {}))
        current = parameter_type(self.world.params[key])
        if code != current:
            return {"successful": False, "reason": f"Wrong parameter type, expected '{current}' got '{code}'"}
        if apply:
            self.world.params[key] = list(value) if isinstance(value, list) else value
        return {"successful": True, "reason": ""}

    async def set_parameters(self, request: dict[str, Any]) -> dict[str, Any]:
        results = [self._set_one(p, apply=True) for p in request.get("parameters", [])]
        self.world.notify()
        return {"results": results}

    async def set_parameters_atomically(self, request: dict[str, Any]) -> dict[str, Any]:
        parameters = list(request.get("parameters", []))
        for parameter in parameters:
            checked = self._set_one(parameter, apply=False)
            if not checked["successful"]:
                return {"result": checked}
        for parameter in parameters:
            self._set_one(parameter, apply=True)
        self.world.notify()
        return {"result": {"successful": True, "reason": ""}}
