"""The policy's allow lists as rosbridge's own launch arguments: defence in depth at the bridge.

rosbridge_suite can refuse, by itself, a publish, a call or a parameter write whose name matches none of its
globs: ``topics_glob``, ``services_glob`` and ``params_glob`` (ROS 1 0.11 and ROS 2 from 2.x on; each a string
``"['/a', '/b/*']"``, read by cutting the brackets and splitting at commas, each glob matched with
``fnmatch``, so ``*`` crosses ``/`` as in the policy). Since rosbridge_suite PR #1260 (the 4.2 line)
``topics_pub_glob`` and ``topics_sub_glob`` split ``topics_glob`` into publishing and subscribing; before,
``topics_glob`` limits both, so the watching tools then see only the topics it names. What
:func:`bridge_arguments` gives for a policy:

* ``[topics] allow``: the publishing glob (plus ``<action>/goal`` and ``<action>/cancel`` of the allowed ROS 1
  actions, which are topics there);
* ``[services] allow``: ``services_glob``, plus the services this server reads the robot through (rosapi, a
  node's parameter and lifecycle state services), the ``set_parameters`` services ``[parameters]`` allows and
  the hidden services of the allowed ROS 2 actions;
* ``[parameters] allow``: ``params_glob``, which rosapi checks (ROS 1: the full name; ROS 2: the name within
  the node, so ``/turtlesim:background_*`` becomes ``background_*``, which any node's parameter of that name
  matches).

The bridge cannot hold deny lists, the velocity caps, confirmations or ``[navigation]``: the server holds
those. A list that allows nothing is written as a glob no ROS name matches (``!none``): on 2.x an empty list
``[]`` means "no filtering".
"""

from __future__ import annotations

from dataclasses import dataclass

from rosbridge_mcp_server.safety.policy import Policy

__all__ = ["NOTHING", "READ_SERVICES", "BridgeArguments", "bridge_arguments"]

#: A glob no ROS name matches (every resolved name starts with "/").
NOTHING = "!none"
#: The services this server reads the robot through, which the bridge must still let it call.
READ_SERVICES = (
    "/rosapi/*",
    "*/get_parameters",
    "*/list_parameters",
    "*/describe_parameters",
    "*/get_parameter_types",
    "*/get_state",
)
_SET_PARAMETERS = ("set_parameters", "set_parameters_atomically")


@dataclass(frozen=True)
class BridgeArguments:
    """The launch arguments (name → globs) and what the person should know about them."""

    arguments: dict[str, tuple[str, ...]]
    notes: tuple[str, ...]

    def launch(self, ros_version: int, *, split_topics: bool = False) -> str:
        """The launch command; with ``split_topics``, ``topics_pub_glob`` in place of ``topics_glob``."""
        command = (
            "ros2 launch rosbridge_server rosbridge_websocket_launch.xml"
            if ros_version == 2
            else "roslaunch rosbridge_server rosbridge_websocket.launch"
        )
        parts = [command]
        for name, globs in self.arguments.items():
            shown = "topics_pub_glob" if split_topics and name == "topics_glob" else name
            listed = ", ".join(f"'{glob}'" for glob in globs or (NOTHING,))
            parts.append(f'{shown}:="[{listed}]"')
        return " ".join(parts)


def _unreadable(globs: tuple[str, ...]) -> list[str]:
    return [glob for glob in globs if "," in glob or "'" in glob or '"' in glob]


def bridge_arguments(policy: Policy, ros_version: int) -> BridgeArguments:
    """The rosbridge launch arguments that hold *policy*'s allow lists at the bridge (none without any)."""
    arguments: dict[str, tuple[str, ...]] = {}
    notes: list[str] = []
    actions = policy.actions.allow
    if policy.topics.allow is not None:
        topics = list(policy.topics.allow)
        if ros_version == 1:
            for action in actions if actions is not None else ("*",):
                topics += [f"{action}/goal", f"{action}/cancel"]
        arguments["topics_glob"] = tuple(topics)
    if policy.services.allow is not None:
        services = [*policy.services.allow, *READ_SERVICES]
        parameters = policy.parameters.allow
        if ros_version == 2:
            for pattern in parameters if parameters is not None else ("*:",):
                node = pattern.partition(":")[0] if ":" in pattern else "*"
                services += [f"{node.rstrip('/')}/{leaf}" for leaf in _SET_PARAMETERS]
            services += [f"{action}/_action/*" for action in (actions if actions is not None else ("*",))]
        arguments["services_glob"] = tuple(dict.fromkeys(services))
    if policy.parameters.allow is not None:
        params = policy.parameters.allow
        if ros_version == 2:
            params = tuple(pattern.partition(":")[2] if ":" in pattern else pattern for pattern in params)
            notes.append(
                "params_glob: rosapi matches a ROS 2 parameter's name within its node, so it allows that "
                "name in every node"
            )
        arguments["params_glob"] = tuple(dict.fromkeys(params))
    for name, globs in arguments.items():
        bad = _unreadable(globs)
        if bad:
            notes.append(
                f"{name}: rosbridge splits its value at commas and strips quotes, so "
                f"{', '.join(repr(g) for g in bad)} cannot be given to it; write the pattern without them"
            )
    if "topics_glob" in arguments:
        notes.append(
            "topics_glob also limits subscribing (rosbridge before 4.2), so the watching tools see only "
            "these topics; where rosbridge has topics_pub_glob (4.2 and later) give it instead"
        )
    if policy.services.allow is not None:
        notes.append(
            "services_glob also hides services from list_services; a call it refuses gets no answer at all, "
            "so a read of a refused service waits for its timeout"
        )
    return BridgeArguments(arguments, tuple(notes))
