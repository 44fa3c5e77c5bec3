"""What the bridge behind a session can do, decided once per connection: the one place telling bridges apart.

Everything above the client asks a capability (``session.capabilities.node_details_of_unknown_safe``), never
which bridge it is. Each capability is decided here from what :func:`~.detect.detect` saw the bridge do on the
connection (its ROS version, whether it answered a refused op with an error ``status``); what was verified
on which bridge: ``docs/rosbridge-behaviour.md``.

========================================  ===========  ==========================  ========================
capability                                ROS 1 0.11   ROS 2 rosbridge_suite        rosbridge-server-rs 0.1.6
========================================  ===========  ==========================  ========================
``status_replies``                        no           no                           yes
``cancel_by_owner_only``                  (actionlib)  no (one goal table)          yes
``goals_hold_connection``                 (actionlib)  taken as yes (2.1.0, Humble)  no
``calls_may_queue``                       no           taken as yes until measured  no
``one_call_per_connection``               yes          no                           no
``service_timeout_field``                 no           yes                          yes
``parameter_services_on_node``            no           yes                          yes
``get_param_names_safe``                  yes          no (kills rosapi 2.1.0)      yes
``node_details_of_unknown_safe``          yes (empty)  no (kills rosapi 2.1.0)      yes (silence)
``drops_large_cbor``                      no           yes                          yes
========================================  ===========  ==========================  ========================
"""

from __future__ import annotations

from dataclasses import dataclass

from rosbridge_mcp_server.wire.ros_versions import RosInfo

__all__ = ["BridgeCapabilities", "capabilities_of"]


@dataclass(frozen=True, slots=True)
class BridgeCapabilities:
    """What one bridge does, named; see the module's table for which bridge does what."""

    #: ROS 2 action ops (``send_action_goal``, ``cancel_action_goal``); ROS 1 has actionlib topics instead.
    action_ops: bool
    #: A refused op (a cancel of a goal another connection started, a goal it will not run, a subscribe it
    #: cannot type) is answered with an error ``status`` naming the op's id; rosbridge_suite never sends one.
    status_replies: bool
    #: Only the connection that started a goal may cancel it (rosbridge-server-rs: "unknown active goal"
    #: elsewhere); rosbridge_suite keeps one goal table per process, so any connection may.
    cancel_by_owner_only: bool
    #: A goal may hold its connection up until it ends, so a cancel sent on that connection is read too late
    #: (rosbridge 2.1.0's and Humble's defaults run a goal in the connection's one thread).
    goals_hold_connection: bool
    #: One connection's service calls may wait behind each other (in order, until measured otherwise).
    calls_may_queue: bool
    #: Two calls in flight on one connection answer slowly (rosbridge 0.11.17 leaves Nagle's algorithm on).
    one_call_per_connection: bool
    #: ``call_service`` reads a ``timeout`` field.
    service_timeout_field: bool
    #: Parameters live in nodes and are read and set through each node's own parameter services (ROS 2).
    parameter_services_on_node: bool
    #: ``/rosapi/get_param_names`` is safe to call (it kills rosapi 2.1.0 on ROS 2: upstream #972/#1010).
    get_param_names_safe: bool
    #: ``/rosapi/node_details`` of a node that is not running is harmless: ROS 1 answers empty lists,
    #: rosbridge-server-rs stays silent; rosbridge_suite's ROS 2 rosapi fails in its handler (2.1.0's dies).
    node_details_of_unknown_safe: bool
    #: A CBOR message above the connection's fragment size never comes (ROS 2 cannot fragment a binary frame).
    drops_large_cbor: bool


def capabilities_of(info: RosInfo) -> BridgeCapabilities:
    """Name what the bridge described by *info* can do (the one decision; see the module's table)."""
    ros2 = info.version == 2
    told = ros2 and info.status_replies
    return BridgeCapabilities(
        action_ops=ros2,
        status_replies=told,
        cancel_by_owner_only=told or bool(info.cancel_owner_only),
        goals_hold_connection=info.goals_may_block,
        calls_may_queue=info.may_be_in_order,
        one_call_per_connection=info.one_call_per_connection,
        service_timeout_field=info.honours_service_timeout,
        parameter_services_on_node=ros2,
        get_param_names_safe=not ros2 or told,
        node_details_of_unknown_safe=not ros2 or told,
        drops_large_cbor=ros2,
    )
