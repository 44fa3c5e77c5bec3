"""The decode budget: a picture, map, scan or cloud that declares more than the budget is refused from its
declared size, naming it and the limit, before anything is decoded; real sensors' sizes pass."""

from __future__ import annotations

import base64
import io
import struct
import tracemalloc
from typing import Any

import pytest
from PIL import Image

from rosbridge_mcp_server.pictures.images import ImageError, decode_compressed, decode_raw
from rosbridge_mcp_server.robot.budget import DECODE_BUDGET, byte_size
from rosbridge_mcp_server.robot.occupancy import MapError, decode_grid
from rosbridge_mcp_server.robot.scans import ScanError, decode_cloud, decode_scan
from rosbridge_mcp_server.sim.png import png_bomb

LIMIT = f"budget of {byte_size(DECODE_BUDGET)}"


def _compressed(data: bytes, fmt: str = "png") -> dict[str, Any]:
    return {"format": fmt, "data": base64.b64encode(data).decode()}


def test_the_png_bomb_is_refused_from_its_header_without_decoding() -> None:
    """13000² at 16 bits in ~330 kB: refused naming the size and the limit, holding no more than its bytes."""
    message = _compressed(png_bomb())
    tracemalloc.start()
    try:
        with pytest.raises(ImageError) as refused:
            decode_compressed(message)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    text = str(refused.value)
    assert "declares 13000x13000 pixels (16-bit grey PNG)" in text
    assert LIMIT in text
    assert "not decoded" in text
    # The base64 text decoded once (~330 kB) and nothing of the 338 MB picture.
    assert peak < 4 * 1024 * 1024


def test_a_jpeg_declaring_a_huge_frame_is_refused_from_its_header() -> None:
    """A JPEG's start-of-frame segment is read for its size: 60000 × 60000 colour is refused."""
    out = io.BytesIO()
    Image.new("RGB", (16, 16), (9, 9, 9)).save(out, "JPEG")
    data = bytearray(out.getvalue())
    at = next(i for i in range(2, len(data) - 1) if data[i] == 0xFF and data[i + 1] in (0xC0, 0xC2))
    data[at + 5 : at + 9] = struct.pack(">HH", 60000, 60000)
    with pytest.raises(ImageError, match=r"declares 60000x60000 pixels \(3-channel JPEG\)"):
        decode_compressed(_compressed(bytes(data), "jpeg"))


def test_a_picture_over_pillows_pixel_limit_is_refused_even_within_the_budget() -> None:
    """A 1-bit-cheap palette PNG of 10000 × 10000 fits the byte budget but not Pillow's pixel limit."""
    header = struct.pack(">IIBBBBB", 10000, 10000, 8, 3, 0, 0, 0)
    data = png_bomb(4, 4)[:8] + struct.pack(">I", 13) + b"IHDR" + header + b"\0\0\0\0"
    limit = r"10000x10000 pixels \(8-bit palette PNG\): more than the 89,478,485"
    with pytest.raises(ImageError, match=limit):
        decode_compressed(_compressed(data))


def test_formats_other_than_jpeg_and_png_are_not_opened() -> None:
    """A TIFF (which Pillow could open) is refused as not JPEG or PNG."""
    out = io.BytesIO()
    Image.new("RGB", (8, 8)).save(out, "TIFF")
    with pytest.raises(ImageError, match=r"not a picture this server decodes \(JPEG or PNG\)"):
        decode_compressed(_compressed(out.getvalue(), "tiff"))


def test_a_raw_image_declaring_more_than_the_budget_is_refused_before_its_data_is_read() -> None:
    """A 16UC1 frame of 20000 × 20000 with a few bytes of data: the budget speaks first, naming the size."""
    message = {"width": 20000, "height": 20000, "encoding": "16UC1", "step": 40000, "data": "AAAA"}
    with pytest.raises(ImageError) as refused:
        decode_raw(message)
    assert "declares 20000x20000 pixels of 16UC1" in str(refused.value)
    assert LIMIT in str(refused.value)


def test_real_camera_sizes_fit_the_budget() -> None:
    """An 8K colour frame and a 1280 × 720 depth frame are within the budget (only the size is checked)."""
    wide = {"width": 7680, "height": 4320, "encoding": "rgb8", "step": 0, "data": ""}
    with pytest.raises(ImageError, match="bytes of data"):
        decode_raw(wide)  # past the budget check, refused only for its missing data
    depth = {"width": 1280, "height": 720, "encoding": "16UC1", "step": 0, "data": ""}
    with pytest.raises(ImageError, match="bytes of data"):
        decode_raw(depth)


def test_a_map_declaring_more_than_the_budget_is_refused_before_its_data_is_decoded() -> None:
    """A 100000 × 100000 OccupancyGrid is refused from its info, naming the cells and the limit."""
    message = {"info": {"width": 100000, "height": 100000, "resolution": 0.05}, "data": "AAAA"}
    with pytest.raises(MapError) as refused:
        decode_grid(message)
    assert "The map declares 100000x100000 cells" in str(refused.value)
    assert LIMIT in str(refused.value)


def test_a_scan_with_more_beams_than_the_budget_is_refused() -> None:
    """Two million beams would be ~460 MB of Python objects: refused naming the beams and the limit."""
    message = {"ranges": [1.0] * 2_000_000, "angle_min": 0.0, "angle_increment": 0.001}
    with pytest.raises(ScanError, match=r"The scan declares 2,000,000 beams: .*budget of 256 MiB"):
        decode_scan(message)


def test_a_cloud_declaring_more_than_the_budget_is_refused_before_its_data_is_decoded() -> None:
    """A PointCloud2 of 100000 × 1000 points of 16 bytes, with four bytes of data: refused by its header."""
    fields = [
        {"name": "x", "offset": 0, "datatype": 7, "count": 1},
        {"name": "y", "offset": 4, "datatype": 7, "count": 1},
    ]
    message = {"width": 100000, "height": 1000, "point_step": 16, "fields": fields, "data": "AAAA"}
    with pytest.raises(ScanError, match=r"The cloud declares 100000x1000 points of 16 bytes"):
        decode_cloud(message)
