"""Message summaries: long arrays summarised, byte arrays omitted, dotted field selection."""

from __future__ import annotations

import base64
import json

import pytest

from rosbridge_mcp_server.pictures.summary import ARRAY_LIMIT, HEAD, FieldPathError, select_fields, summarize


def laser_scan(count: int) -> dict[str, object]:
    ranges: list[float | None] = [1.0 + i / 100 for i in range(count)]
    ranges[3] = None  # rosbridge writes an infinite range as null
    return {"header": {"frame_id": "laser"}, "angle_min": -1.5, "ranges": ranges, "intensities": []}


def test_a_long_number_array_becomes_length_head_and_statistics() -> None:
    """720 ranges shrink to their length, first values, min/max/mean and the count of missing ones."""
    summary = summarize(laser_scan(720))
    ranges = summary.message["ranges"]
    assert ranges["length"] == 720
    assert ranges["first"] == [1.0, 1.01, 1.02, None, 1.04]
    assert ranges["min"] == 1.0
    assert ranges["max"] == pytest.approx(1.0 + 719 / 100)
    assert ranges["not_finite"] == 1
    assert [cut.describe() for cut in summary.cuts] == ["ranges: 720 numbers summarised"]
    assert len(json.dumps(summary.message)) < 400


def test_short_arrays_and_plain_fields_are_kept_whole() -> None:
    """A message without long arrays comes back unchanged, with no cuts."""
    msg = {"linear": {"x": 0.5, "y": 0, "z": 0}, "covariance": list(range(ARRAY_LIMIT))}
    summary = summarize(msg)
    assert summary.message == msg
    assert summary.cuts == ()


def test_a_byte_array_is_never_dumped() -> None:
    """A PointCloud2's base64 data becomes its byte count, whether the type says so or it looks like it."""
    payload = bytes(range(256)) * 40
    cloud = {"height": 1, "width": 640, "data": base64.b64encode(payload).decode(), "fields": []}
    for summary in (summarize(cloud), summarize(cloud, byte_fields=["data"])):
        assert summary.message["data"] == {"bytes": len(payload)}
        assert summary.cuts[0].kind == "bytes"


def test_a_known_byte_field_is_omitted_even_when_short() -> None:
    """A field the type calls uint8[] is omitted however short its text."""
    summary = summarize({"data": "AAEC"}, byte_fields=["data"])
    assert summary.message == {"data": {"bytes": 3}}


def test_a_long_list_of_objects_keeps_its_first_items() -> None:
    """An array of many objects keeps the first few, each itself summarised."""
    msg = {"points": [{"x": i, "data": [0] * 100} for i in range(50)]}
    summary = summarize(msg)
    assert [p["x"] for p in summary.message["points"]] == list(range(HEAD))
    assert summary.message["points"][0]["data"]["length"] == 100
    assert summary.cuts[0].describe() == f"points: 50 items, first {HEAD} shown"


def test_long_text_is_cut_and_noted() -> None:
    """A robot description of many kilobytes is cut to its beginning."""
    summary = summarize({"data": "<robot name='r'> " * 1000})
    assert summary.message["data"].endswith("...")
    assert summary.cuts[0].kind == "text"


def test_select_fields_keeps_only_the_dotted_paths() -> None:
    """pose.position and header.stamp are kept, nested as in the message; an index picks an array item."""
    msg = {
        "header": {"stamp": {"sec": 1, "nanosec": 2}, "frame_id": "map"},
        "pose": {"position": {"x": 1.0}, "orientation": {"w": 1.0}},
        "ranges": [4.0, 5.0],
    }
    assert select_fields(msg, ["pose.position", "header.stamp", "ranges.1"]) == {
        "pose": {"position": {"x": 1.0}},
        "header": {"stamp": {"sec": 1, "nanosec": 2}},
        "ranges": {"1": 5.0},
    }


def test_an_unknown_field_path_names_the_fields_that_are_there() -> None:
    """A misspelt path is an error listing the fields at the level where it went wrong."""
    with pytest.raises(
        FieldPathError, match=r"no 'positon' in pose; the fields there are: position, orientation"
    ):
        select_fields({"pose": {"position": {}, "orientation": {}}}, ["pose.positon"])
