"""Types told without asking rosapi: the services every node offers, and the type a bridge names when it
refuses a probe call.

The probe is a call carrying a field no ROS message has: a ROS 2 bridge refuses it before making a ROS
client, and its refusal names the type (~2-20 ms, against rosapi's ~90 ms a quarter of the time on 2.1.0).
What was seen on which bridge: docs/rosbridge-behaviour.md.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Iterable, Mapping
from types import MappingProxyType
from typing import Final

__all__ = [
    "PROBE_CONCURRENCY",
    "PROBE_FIELD",
    "PROBE_SECONDS",
    "action_type_from_refusal",
    "infrastructure_types",
    "per_node_types",
    "ros1_load_failure",
    "rosapi_types",
    "service_type_from_refusal",
]


# How rosbridge 0.11's ros_loader says a type cannot be loaded (rosapi passes the text on).
_ROS1_LOAD_FAILURES = ("Unable to import", "Unable to load", "is not a valid type string")


def ros1_load_failure(message: str) -> bool:
    return any(text in message for text in _ROS1_LOAD_FAILURES)


# The services every node offers, by the last part of their name, with their fixed types. ROS 2 (rclcpp and
# rclpy): six parameter services, and since Iron get_type_description; ROS 1 (roscpp and rospy): two logger
# services. Seen on rosbridge 2.1.0's Jazzy and Kilted graphs and on a 0.11.17 Noetic-line graph.
_ROS2_PARAMETER_SERVICES: Final = {
    "describe_parameters": "rcl_interfaces/srv/DescribeParameters",
    "get_parameter_types": "rcl_interfaces/srv/GetParameterTypes",
    "get_parameters": "rcl_interfaces/srv/GetParameters",
    "list_parameters": "rcl_interfaces/srv/ListParameters",
    "set_parameters": "rcl_interfaces/srv/SetParameters",
    "set_parameters_atomically": "rcl_interfaces/srv/SetParametersAtomically",
}
# Offered by every node since Iron (also by rosapi's helper node, which has no parameter services); the
# name is rcl's, so it is typed wherever it appears.
_ROS2_TYPE_DESCRIPTION = ("get_type_description", "type_description_interfaces/srv/GetTypeDescription")
# A managed (lifecycle) node's five services, typed when all five are under one prefix.
_ROS2_LIFECYCLE_SERVICES: Final = {
    "change_state": "lifecycle_msgs/srv/ChangeState",
    "get_state": "lifecycle_msgs/srv/GetState",
    "get_available_states": "lifecycle_msgs/srv/GetAvailableStates",
    "get_available_transitions": "lifecycle_msgs/srv/GetAvailableTransitions",
    "get_transition_graph": "lifecycle_msgs/srv/GetAvailableTransitions",
}
_ROS1_LOGGER_SERVICES: Final = {
    "get_loggers": "roscpp/GetLoggers",
    "set_logger_level": "roscpp/SetLoggerLevel",
}
# rosapi's own services under /rosapi, whose types rosapi fixes (`rosapi_msgs/srv/X` on ROS 2, `rosapi/X` on
# ROS 1). Services a later rosapi adds are simply looked up.
_ROSAPI_SERVICES: Final = {
    "action_servers": "GetActionServers",
    "delete_param": "DeleteParam",
    "get_param": "GetParam",
    "get_param_names": "GetParamNames",
    "get_time": "GetTime",
    "has_param": "HasParam",
    "message_details": "MessageDetails",
    "node_details": "NodeDetails",
    "nodes": "Nodes",
    "publishers": "Publishers",
    "service_node": "ServiceNode",
    "service_providers": "ServiceProviders",
    "service_request_details": "ServiceRequestDetails",
    "service_response_details": "ServiceResponseDetails",
    "service_type": "ServiceType",
    "services": "Services",
    "services_for_type": "ServicesForType",
    "set_param": "SetParam",
    "subscribers": "Subscribers",
    "topic_type": "TopicType",
    "topics": "Topics",
    "topics_and_raw_types": "TopicsAndRawTypes",
    "topics_for_type": "TopicsForType",
}
_ROSAPI_SERVICES_ROS1: Final = {"search_param": "SearchParam", "service_host": "ServiceHost"}
_ROSAPI_SERVICES_ROS2: Final = {"get_ros_version": "GetROSVersion"}


def infrastructure_types(names: Iterable[str], version: int) -> dict[str, str]:
    """The types of the per-node and rosapi services among *names*, told from the names alone."""
    listed = list(names)
    return {**per_node_types(listed, version), **rosapi_types(listed, version)}


def per_node_types(names: Iterable[str], version: int) -> dict[str, str]:
    """The types of the services among *names* that every node offers (parameters, loggers, lifecycle).

    A node's set counts only when it is complete (all six parameter services, or all five lifecycle services,
    under one prefix on ROS 2; both logger services on ROS 1), so a single service that merely shares a leaf
    name is looked up as usual.
    """
    found: dict[str, str] = {}
    sets = (_ROS2_PARAMETER_SERVICES, _ROS2_LIFECYCLE_SERVICES) if version == 2 else (_ROS1_LOGGER_SERVICES,)
    for prefix, leaves in _by_prefix(names).items():
        for per_node in sets:
            if per_node.keys() <= leaves:
                found.update({f"{prefix}/{leaf}": kind for leaf, kind in per_node.items()})
        leaf, kind = _ROS2_TYPE_DESCRIPTION
        if version == 2 and leaf in leaves:
            found[f"{prefix}/{leaf}"] = kind
    return found


def rosapi_types(names: Iterable[str], version: int) -> dict[str, str]:
    """The types of rosapi's own services among *names* (``/rosapi/topics`` and the like)."""
    rosapi = {**_ROSAPI_SERVICES, **(_ROSAPI_SERVICES_ROS2 if version == 2 else _ROSAPI_SERVICES_ROS1)}
    package = "rosapi_msgs/srv" if version == 2 else "rosapi"
    leaves = _by_prefix(names).get("/rosapi", frozenset())
    return {f"/rosapi/{leaf}": f"{package}/{rosapi[leaf]}" for leaf in leaves if leaf in rosapi}


def _by_prefix(names: Iterable[str]) -> Mapping[str, frozenset[str]]:
    # A listing asks several of these helpers about the same few hundred names: split them once.
    return _split_by_prefix(tuple(names))


@functools.lru_cache(maxsize=4)
def _split_by_prefix(names: tuple[str, ...]) -> Mapping[str, frozenset[str]]:
    # Read-only: every caller with the same names gets this one answer.
    by_prefix: dict[str, set[str]] = {}
    for name in set(names):
        prefix, _, leaf = name.rpartition("/")
        by_prefix.setdefault(prefix, set()).add(leaf)
    return MappingProxyType({prefix: frozenset(leaves) for prefix, leaves in by_prefix.items()})


#: A field name no ROS message has (ROS field names start with a letter): a request carrying it is refused.
PROBE_FIELD = "__type_probe__"
_IMPORT_REFUSAL = re.compile(r"Unable to import \w+ class (\w+)_SendGoal from package (\w+)")
_FIELD_REFUSAL = re.compile(r"Message type (\w+)/(?:action/)?(\w+)_SendGoal_Request does not have a field")


#: Probes are refused before the bridge makes a ROS client, so more may run at once than rosapi look-ups
#: (2.1.0 lost calls only with sixteen or more in flight).
PROBE_CONCURRENCY = 8
#: How long a probe call may take before rosapi is asked instead (a refusal comes in ~2-20 ms).
PROBE_SECONDS = 1.0
_SERVICE_FIELD_REFUSAL = re.compile(r"Message type (\w+)/(?:srv/)?(\w+)_Request does not have a field")
_SERVICE_IMPORT_REFUSAL = re.compile(r"Unable to import srv class (\w+) from package (\w+)")


def service_type_from_refusal(text: str) -> str | None:
    """``pkg/srv/Name`` from a ROS 2 bridge's refusal of a probe call, or ``None``."""
    if match := _SERVICE_FIELD_REFUSAL.search(text):
        return f"{match.group(1)}/srv/{match.group(2)}"
    if match := _SERVICE_IMPORT_REFUSAL.search(text):
        return f"{match.group(2)}/srv/{match.group(1)}"
    return None


def action_type_from_refusal(text: str) -> str | None:
    """``pkg/action/Name`` from the bridge's refusal of a send_goal probe, or ``None``."""
    if match := _IMPORT_REFUSAL.search(text):
        return f"{match.group(2)}/action/{match.group(1)}"
    if match := _FIELD_REFUSAL.search(text):
        return f"{match.group(1)}/action/{match.group(2)}"
    return None
