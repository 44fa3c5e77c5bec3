"""Camera frames to pictures: every supported encoding, padding, endianness, compressed frames, resizing."""

from __future__ import annotations

import array
import base64
import io
import struct
import sys
from typing import Any

import pytest
from PIL import Image

from rosbridge_mcp_server.pictures.images import ImageError, decode_compressed, decode_raw, encode_picture


def raw_image(
    encoding: str, width: int, height: int, pixel: bytes, *, pad: int = 0, big: bool = False
) -> dict[str, Any]:
    row = pixel * width + b"\x00" * pad
    return {
        "header": {"frame_id": "camera"},
        "height": height,
        "width": width,
        "encoding": encoding,
        "is_bigendian": 1 if big else 0,
        "step": len(row),
        "data": base64.b64encode(row * height).decode(),
    }


@pytest.mark.parametrize(
    ("encoding", "pixel", "expected"),
    [
        ("rgb8", bytes([200, 10, 20]), (200, 10, 20)),
        ("bgr8", bytes([20, 10, 200]), (200, 10, 20)),
        ("rgba8", bytes([200, 10, 20, 255]), (200, 10, 20, 255)),
        ("bgra8", bytes([20, 10, 200, 255]), (200, 10, 20, 255)),
        ("mono8", bytes([77]), 77),
        ("mono16", struct.pack("<H", 0x4D00), 0x4D),
    ],
)
def test_colour_and_grey_encodings_keep_their_pixel_values(
    encoding: str, pixel: bytes, expected: Any
) -> None:
    """Each colour or grey encoding decodes to the same pixel value, whatever its channel order."""
    picture = decode_raw(raw_image(encoding, 4, 3, pixel))
    assert (picture.width, picture.height) == (4, 3)
    assert picture.image.getpixel((3, 2)) == expected


def test_row_padding_is_skipped() -> None:
    """A step longer than width × pixel size (padded rows) still gives the right pixels."""
    picture = decode_raw(raw_image("rgb8", 3, 2, bytes([1, 2, 3]), pad=7))
    assert picture.image.getpixel((2, 1)) == (1, 2, 3)


def test_a_big_endian_depth_image_is_read_as_big_endian() -> None:
    """16UC1 with is_bigendian set reads its millimetres in network order."""
    values = [0, 1000, 2000, 3000]
    data = b"".join(struct.pack(">H", v) for v in values)
    msg = {"height": 1, "width": 4, "encoding": "16UC1", "is_bigendian": 1, "step": 8, "data": list(data)}
    picture = decode_raw(msg)
    assert picture.depth is not None
    assert (picture.depth.near, picture.depth.far, picture.depth.unit) == (1000, 3000, "mm")
    assert [picture.image.getpixel((x, 0)) for x in range(4)] == [0, 1, 128, 255]


def test_a_float_depth_image_is_normalised_over_valid_pixels() -> None:
    """32FC1 metres: NaN and 0 stay black, the nearest valid depth is darkest, the farthest white."""
    values = array.array("f", [float("nan"), 0.0, 0.5, 4.5])
    if sys.byteorder == "big":
        values.byteswap()
    msg = {
        "height": 1,
        "width": 4,
        "encoding": "32FC1",
        "is_bigendian": 0,
        "step": 16,
        "data": base64.b64encode(values.tobytes()).decode(),
    }
    picture = decode_raw(msg)
    assert picture.depth is not None
    assert (picture.depth.near, picture.depth.far, picture.depth.valid_pixels) == (0.5, 4.5, 2)
    assert [picture.image.getpixel((x, 0)) for x in range(4)] == [0, 0, 1, 255]


def test_an_unsupported_encoding_is_named() -> None:
    """yuv422 is refused with its name and the encodings that work."""
    with pytest.raises(ImageError, match=r"'yuv422' is not supported; supported: rgb8, bgr8"):
        decode_raw(raw_image("yuv422", 2, 2, b"\x00\x00"))


def test_too_little_data_is_an_error() -> None:
    """A frame whose data is shorter than its size says how many bytes it needed."""
    msg = raw_image("rgb8", 4, 4, bytes([1, 2, 3]))
    msg["height"] = 8
    with pytest.raises(ImageError, match="48 bytes of data; 4x8 at 12 bytes per row needs 96"):
        decode_raw(msg)


def test_a_large_frame_is_resized_to_max_size_and_encoded() -> None:
    """A 1920×1080 frame comes out 800 px wide as JPEG, or as PNG when asked."""
    picture = decode_raw(raw_image("rgb8", 1920, 1080, bytes([10, 120, 230])))
    jpeg = Image.open(io.BytesIO(encode_picture(picture, 800, "jpeg").data))
    assert (jpeg.format, jpeg.size) == ("JPEG", (800, 450))
    png = Image.open(io.BytesIO(encode_picture(picture, 64, "png").data))
    assert (png.format, png.size) == ("PNG", (64, 36))
    assert png.getpixel((10, 10)) == (10, 120, 230)


def test_a_compressed_image_is_decoded() -> None:
    """A CompressedImage with JPEG bytes becomes a picture of its size."""
    out = io.BytesIO()
    Image.new("RGB", (32, 24), (0, 255, 0)).save(out, "JPEG")
    picture = decode_compressed({"format": "jpeg", "data": base64.b64encode(out.getvalue()).decode()})
    assert (picture.width, picture.height, picture.encoding) == (32, 24, "jpeg")


def test_compressed_bytes_that_are_no_image_are_an_error() -> None:
    """Garbage in a CompressedImage is an error naming its format."""
    with pytest.raises(ImageError, match=r"format 'png'\) could not be decoded: its bytes are not a picture"):
        decode_compressed({"format": "png", "data": base64.b64encode(b"not a picture").decode()})
