"""ROS 1 actionlib on the wire: the topics under an action's namespace and the cancel message.

ROS 1 rosbridge has no action ops, so a goal goes through five topics under the action's namespace: we publish
``<ns>/goal`` and ``<ns>/cancel`` and listen on ``<ns>/status``, ``<ns>/feedback`` and ``<ns>/result``,
matching our goal by ``goal_id.id``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Final

if TYPE_CHECKING:
    from rosbridge_mcp_server.client import RosbridgeClient, Session

__all__ = ["CANCEL_TYPE", "goal_id_of", "publish_cancel"]

#: The message on ``<ns>/cancel``: a goal id and a stamp (both empty/zero: every goal).
CANCEL_TYPE: Final = "actionlib_msgs/GoalID"


async def publish_cancel(
    client: RosbridgeClient, ns: str, goal_id: str, *, session: Session | None = None
) -> None:
    """Publish a cancel for *goal_id* on ``<ns>/cancel`` (an empty id cancels every goal of the action).

    With *session*, only on that session. Raises what ``publish`` raises when it cannot be sent.
    """
    msg = {"stamp": {"sec": 0, "nanosec": 0}, "id": goal_id}
    await client.publish(f"{ns}/cancel", CANCEL_TYPE, msg, session=session)


def goal_id_of(status: Any) -> str | None:
    """The ``goal_id.id`` of an ``actionlib_msgs/GoalStatus``, or None."""
    if isinstance(status, dict):
        goal_id = status.get("goal_id")
        if isinstance(goal_id, dict):
            gid = goal_id.get("id")
            return gid if isinstance(gid, str) else None
    return None
