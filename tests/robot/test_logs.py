"""The log ring's bounds, both dialects' log messages, folding, filters, the tally, and diagnostic levels."""

from __future__ import annotations

import base64

from rosbridge_mcp_server.robot.diagnostics import StatusBoard, status_level
from rosbridge_mcp_server.robot.logs import (
    RING_LINES,
    RING_SECONDS,
    TALLY_GROUPS,
    LogLine,
    LogRing,
    fold,
    line_of,
    node_matcher,
)

NOW = 1_800_000_000.0


def line(text: str, *, at: float = NOW, level: str = "warn", node: str = "/amcl") -> LogLine:
    return LogLine(at, at, level, node, text, "")


def test_the_ring_keeps_the_newest_lines_up_to_its_count() -> None:
    ring = LogRing()
    for i in range(RING_LINES + 2_345):
        ring.add(line(f"line {i}", at=NOW + i * 1e-3))
    kept = ring.lines(now=NOW + 10)
    assert len(kept) == RING_LINES
    assert [x.text for x in kept] == [f"line {i}" for i in range(2_345, RING_LINES + 2_345)]
    assert ring.received == RING_LINES + 2_345
    assert ring.dropped == 2_345


def test_the_ring_lets_lines_older_than_its_age_go() -> None:
    ring = LogRing()
    ring.add(line("old", at=NOW - RING_SECONDS - 1))
    ring.add(line("new", at=NOW - 5))
    assert [x.text for x in ring.lines(now=NOW)] == ["new"]
    assert ring.dropped == 1


def test_ros2_and_ros1_log_messages_read_alike() -> None:
    ros2 = line_of(
        {
            "stamp": {"sec": 10, "nanosec": 500_000_000},
            "level": 40,
            "name": "local_costmap.local_costmap",
            "msg": "Sensor origin out of bounds",
            "file": "costmap.cpp",
            "function": "update",
            "line": 12,
        },
        NOW,
    )
    ros1 = line_of(
        {
            "header": {"seq": 3, "stamp": {"secs": 10, "nsecs": 500_000_000}, "frame_id": ""},
            "level": 8,
            "name": "/local_costmap/local_costmap",
            "msg": "Sensor origin out of bounds",
            "file": "costmap.cpp",
            "function": "update",
            "line": 12,
            "topics": [],
        },
        NOW,
    )
    assert ros2 == ros1
    assert (ros2.level, ros2.node, ros2.stamp, ros2.where) == (
        "error",
        "/local_costmap/local_costmap",
        10.5,
        "costmap.cpp:12 (update)",
    )
    assert line_of({"level": 2, "name": "/a"}, NOW).level == "info"
    assert line_of({"level": 30, "name": "a"}, NOW).level == "warn"
    assert line_of({"level": "garbage", "msg": None}, NOW).level == "info"
    long = line_of({"level": 20, "name": "a", "msg": "x" * 2_000}, NOW)
    assert len(long.text) < 600
    assert long.text.endswith("(2,000 characters)")


def test_repeats_fold_when_only_their_numbers_differ() -> None:
    lines = [
        line("Goal 7 failed after 1.5 s", at=NOW),
        line("Something else", at=NOW + 1),
        line("Goal 8 failed after 2.25 s", at=NOW + 12),
        line("Goal 9 failed after 2.25 s", at=NOW + 12, node="/other"),
    ]
    folds = fold(lines)
    assert [(f.node, f.text, f.count) for f in folds] == [
        ("/amcl", "Something else", 1),
        ("/amcl", "Goal 8 failed after 2.25 s", 2),
        ("/other", "Goal 9 failed after 2.25 s", 1),
    ]
    assert (
        folds[1].describe(NOW + 12.4)
        == "[WARN] /amcl: Goal 8 failed after 2.25 s (×2 in 12 s, last 0.4 s ago)"
    )
    assert folds[0].describe(NOW + 100) == "[WARN] /amcl: Something else (99 s ago)"


def test_select_filters_by_level_node_text_and_since() -> None:
    ring = LogRing()
    ring.add(line("a debug line", at=NOW - 50, level="debug"))
    ring.add(line("an info line", at=NOW - 40, level="info", node="/local_costmap/local_costmap"))
    ring.add(line("A WARNING", at=NOW - 30))
    ring.add(line("an error", at=NOW - 5, level="error", node="/controller_server"))
    texts = lambda **kw: [x.text for x in ring.select(now=NOW, **kw)]  # noqa: E731
    assert texts() == ["A WARNING", "an error"]
    assert texts(level="debug") == ["a debug line", "an info line", "A WARNING", "an error"]
    assert texts(level="info", node="*costmap*") == ["an info line"]
    assert texts(node="controller_server") == ["an error"]
    assert texts(level="debug", text="warn") == ["A WARNING"]
    assert texts(level="debug", since=35) == ["A WARNING", "an error"]


def test_node_names_match_with_or_without_their_slash() -> None:
    assert node_matcher("amcl")("/amcl")
    assert not node_matcher("amcl")("/amcl_2")
    assert node_matcher("*costmap*")("/global_costmap/global_costmap")
    assert node_matcher(None)("/anything")


def test_the_tally_keeps_every_warning_since_connect_within_its_bound() -> None:
    ring = LogRing(max_lines=10)
    for i in range(TALLY_GROUPS + 50):
        ring.add(line(f"problem {chr(65 + i % 26)}{chr(65 + i // 26)}", at=NOW + i))
    ring.add(line("noise", level="info"))
    assert len(ring) == 10
    groups = ring.tally.folds()
    assert len(groups) == TALLY_GROUPS
    assert groups[0].last == NOW + TALLY_GROUPS + 49  # the newest kept, the oldest replaced
    assert all(g.level == "warn" for g in groups)


def test_diagnostic_levels_are_read_in_every_form_bridges_send() -> None:
    assert [status_level(v) for v in (0, 1, 2, 3)] == [0, 1, 2, 3]
    assert status_level(base64.b64encode(b"\x02").decode()) == 2
    assert status_level("\x01") == 1
    assert status_level("2") == 2
    assert status_level([3]) == 3
    assert [status_level(v) for v in (7, True, None, "nonsense!", 2.0)] == [None] * 5
    board = StatusBoard(max_statuses=2)
    board.add_message(
        {
            "status": [
                {"level": 2, "name": "lidar", "message": "stalled", "hardware_id": "a", "values": []},
                {"level": 0, "name": "camera", "message": "OK", "hardware_id": "b", "values": []},
                {"level": 1, "name": "imu", "message": "noisy", "hardware_id": "c", "values": []},
                "not a status",
            ]
        },
        "/diagnostics",
        NOW,
    )
    board.add_message(
        {"status": [{"level": 0, "name": "lidar", "message": "OK", "hardware_id": "a", "values": []}]},
        "/diagnostics",
        NOW + 1,
    )
    assert [(s.name, s.level_name) for s in board.statuses()] == [("camera", "OK"), ("lidar", "OK")]
