"""diagnose's next calls: robot/diagnosis/ gives typed steps, tools/diagnose.py words them as the calls the
model makes, word for word what robot/ used to write."""

from __future__ import annotations

import pytest

from rosbridge_mcp_server.robot.diagnosis import Diagnosis, Look, Step
from rosbridge_mcp_server.tools.diagnose import checked_texts, next_text

CASES: list[tuple[tuple[Step, ...], str]] = [
    (
        (Step(Look.NODE_LOG, ("/amcl",), "for its last words"), Step(Look.NODES)),
        'read_logs {"node": "/amcl", "level": "info"} for its last words; list_nodes',
    ),
    ((Step(Look.TOPIC, ("/cmd_vel",)),), 'get_topic_info {"topic": "/cmd_vel"}'),
    ((Step(Look.TOPIC, ("/odom",)), Step(Look.NODES)), 'get_topic_info {"topic": "/odom"}; list_nodes'),
    (
        (Step(Look.TOPIC, ("/tf",), "to see who publishes"),),
        'get_topic_info {"topic": "/tf"} to see who publishes',
    ),
    (
        (Step(Look.NODE_LOG, ("/amcl",), "for why"), Step(Look.ACTIVATE)),
        'read_logs {"node": "/amcl", "level": "info"} for why; activating it acts on the robot (its '
        "lifecycle manager's manage_nodes, or its change_state service, transition 3): ask the user first",
    ),
    ((Step(Look.LOG, (), "for its last words"),), 'read_logs {"level": "info"} for its last words'),
    ((Step(Look.ONE_MESSAGE, ("/diagnostics",)),), 'subscribe_topic {"topic": "/diagnostics", "count": 1}'),
    (
        (Step(Look.STATUSES, ("/diagnostics", "4")),),
        'subscribe_topic {"topic": "/diagnostics", "count": 8, "duration": 3, "fields": ["status"]} (its '
        "publishers take turns: one message is likely another's)",
    ),
    (
        (Step(Look.STATUSES, ("/diagnostics", "300")),),
        'subscribe_topic {"topic": "/diagnostics", "count": 100, "duration": 3, "fields": ["status"]} (its '
        "publishers take turns: one message is likely another's)",
    ),
    (
        (Step(Look.WAIT_MESSAGE, ("/scan",)), Step(Look.NODE, ("/lidar",))),
        'subscribe_topic {"topic": "/scan", "timeout": 5}; get_node_info {"node": "/lidar"}',
    ),
    (
        (Step(Look.STAMPS, ("/scan",)),),
        'plot_topic {"series": ["/scan header.stamp.sec"], "duration": 5}',
    ),
    (
        (Step(Look.TRANSFORM, ("odom", "base_link")),),
        'get_transform {"target_frame": "odom", "source_frame": "base_link"}',
    ),
    (
        (Step(Look.TRANSFORM_WAIT, ("map", "odom")),),
        'get_transform {"target_frame": "map", "source_frame": "odom", "timeout": 5}',
    ),
    ((Step(Look.NODE_LOG, ("/planner",)),), 'read_logs {"node": "/planner", "level": "info"}'),
    (
        (Step(Look.ACTIVATE_CONTROLLER, ("/controller_manager", "arm_controller")), Step(Look.ARM)),
        "activating arm_controller acts on the robot (/controller_manager/switch_controller, "
        "activate_controllers (ROS 1: start_controllers), if the hardware allows): ask the user first; "
        "view_arm",
    ),
]


def test_every_look_is_worded() -> None:
    """A new Look without a call would fail at the edge; the cases below cover every one."""
    assert {step.look for steps, _ in CASES for step in steps} == set(Look)


@pytest.mark.parametrize(("steps", "text"), CASES)
def test_the_steps_read_as_the_calls_to_make(steps: tuple[Step, ...], text: str) -> None:
    assert next_text(steps) == text


def test_what_an_area_left_out_is_pointed_at_in_its_checked_text() -> None:
    """robot/ counts the statuses and log groups left out; the tool says where to read them."""
    found = Diagnosis(
        findings=[],
        checked={
            "graph": "36 nodes, 78 topics",
            "diagnostics": "25 statuses, 0 OK",
            "logs": "7 errors, 1 warnings since 03:00:00 (12 lines kept)",
        },
        unavailable={},
        seconds=1.0,
        left_out={"diagnostics": 5, "logs": 2},
    )
    assert checked_texts(found) == {
        "graph": "36 nodes, 78 topics",
        "diagnostics": (
            '25 statuses, 0 OK (5 more not OK: subscribe_topic {"topic": "/diagnostics", "count": 100, '
            '"duration": 3, "fields": ["status"]})'
        ),
        "logs": "7 errors, 1 warnings since 03:00:00 (12 lines kept, 2 more groups in read_logs)",
    }
    found.left_out.clear()
    assert checked_texts(found) == found.checked
