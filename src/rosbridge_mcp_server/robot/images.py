"""Camera frames as pictures: ``sensor_msgs/Image`` and ``CompressedImage`` messages to JPEG or PNG bytes.

rosbridge sends the pixel bytes (``uint8[] data``) as one base64 string in JSON (a list of ints from some
bridges; both are accepted). A raw image carries ``width``, ``height``, ``encoding``, ``is_bigendian`` and
``step`` (bytes per row, which may include padding). Depth images (``16UC1`` in millimetres, ``32FC1`` in
metres) are normalised to grey over the range of valid (non-zero, finite) pixels, nearer is darker, and the
range is reported. Pure: no I/O.
"""

from __future__ import annotations

import array
import base64
import binascii
import io
import math
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

from PIL import Image, UnidentifiedImageError

__all__ = [
    "ENCODINGS",
    "DepthRange",
    "Encoded",
    "ImageError",
    "ImageFormat",
    "Picture",
    "decode_compressed",
    "decode_raw",
    "encode_picture",
    "message_bytes",
]

ImageFormat = Literal["jpeg", "png"]

# encoding → (Pillow mode of the image we make, Pillow raw mode of the bytes, bytes per pixel)
_COLOUR: dict[str, tuple[str, str, int]] = {
    "rgb8": ("RGB", "RGB", 3),
    "bgr8": ("RGB", "BGR", 3),
    "rgba8": ("RGBA", "RGBA", 4),
    "bgra8": ("RGBA", "BGRA", 4),
    "mono8": ("L", "L", 1),
    "8UC1": ("L", "L", 1),
    # OpenCV's cv_bridge writes colour frames as 8UC3 in BGR order.
    "8UC3": ("RGB", "BGR", 3),
}
_SIXTEEN = frozenset({"mono16", "16UC1"})
_DEPTH = frozenset({"16UC1", "32FC1"})
#: Every raw encoding we turn into a picture.
ENCODINGS: tuple[str, ...] = (*_COLOUR, "mono16", "16UC1", "32FC1")
_JPEG_QUALITY = 85


class ImageError(ValueError):
    """A message that cannot be made into a picture; ``str()`` says why."""


@dataclass(frozen=True)
class DepthRange:
    """The depths mapped to black and white (``unit`` is ``mm`` for 16UC1, ``m`` for 32FC1)."""

    near: float
    far: float
    unit: str
    valid_pixels: int


@dataclass(frozen=True)
class Picture:
    """A decoded frame, ready to resize and encode; ``depth`` is set for depth encodings."""

    image: Image.Image
    encoding: str
    width: int
    height: int
    depth: DepthRange | None = None


def message_bytes(data: Any, what: str = "data") -> bytes:
    """A ``uint8[]`` field as rosbridge sends it: base64 text, or a list of ints."""
    if isinstance(data, str):
        try:
            return base64.b64decode(data, validate=False)
        except (binascii.Error, ValueError) as exc:
            raise ImageError(f"The image's {what} is not valid base64 ({exc}).") from None
    if isinstance(data, bytes | bytearray):
        return bytes(data)
    if isinstance(data, list):
        try:
            return bytes(data)
        except (TypeError, ValueError):
            raise ImageError(f"The image's {what} is a list but not of bytes (0-255).") from None
    raise ImageError(f"The image has no {what} bytes.")


def decode_raw(msg: Mapping[str, Any]) -> Picture:
    """A ``sensor_msgs/Image`` message as a :class:`Picture`; :class:`ImageError` when it cannot be one."""
    encoding = str(msg.get("encoding", "")).strip()
    width = _dimension(msg, "width")
    height = _dimension(msg, "height")
    if width == 0 or height == 0:
        raise ImageError(f"The image is empty ({width}x{height}).")
    big_endian = bool(msg.get("is_bigendian", 0))
    data = message_bytes(msg.get("data"))
    if encoding in _COLOUR:
        mode, raw_mode, size = _COLOUR[encoding]
        step = _step(msg, width, size, height, data)
        image = Image.frombuffer(mode, (width, height), data, "raw", raw_mode, step, 1)
        return Picture(image, encoding, width, height)
    if encoding in _SIXTEEN:
        step = _step(msg, width, 2, height, data)
        raw_mode = "I;16B" if big_endian else "I;16"
        wide = Image.frombuffer("I;16", (width, height), data, "raw", raw_mode, step, 1)
        if encoding == "16UC1":
            values = _pixels_16(data, width, height, step, big_endian)
            return _depth_picture(wide.convert("I"), values, encoding, width, height, unit="mm")
        # mono16: an ordinary grey image with 16-bit levels; the high byte is its 8-bit picture.
        return Picture(wide.convert("I").point(lambda v: v / 256).convert("L"), encoding, width, height)
    if encoding == "32FC1":
        step = _step(msg, width, 4, height, data)
        raw_mode = "F;32BF" if big_endian else "F;32F"
        image = Image.frombuffer("F", (width, height), data, "raw", raw_mode, step, 1)
        floats = _pixels_float(data, width, height, step, big_endian)
        return _depth_picture(image, floats, encoding, width, height, unit="m")
    known = ", ".join(ENCODINGS)
    raise ImageError(f"The image encoding {encoding or '(empty)'!r} is not supported; supported: {known}.")


def decode_compressed(msg: Mapping[str, Any]) -> Picture:
    """A ``sensor_msgs/CompressedImage`` (JPEG or PNG; ``compressedDepth`` PNG) as a :class:`Picture`."""
    fmt = str(msg.get("format", "")).strip()
    data = message_bytes(msg.get("data"))
    # image_transport's compressedDepth puts a small configuration header before the PNG.
    png_start = data.find(b"\x89PNG")
    if "compresseddepth" in fmt.lower() and png_start > 0:
        data = data[png_start:]
    try:
        image = Image.open(io.BytesIO(data))
        image.load()
    except UnidentifiedImageError:
        raise ImageError(
            f"The compressed image (format {fmt or 'not given'!r}) could not be decoded: its bytes are not a "
            "picture Pillow knows (JPEG, PNG, …)."
        ) from None
    except OSError as exc:
        raise ImageError(
            f"The compressed image (format {fmt or 'not given'!r}) could not be decoded: {exc}."
        ) from None
    encoding = fmt or (image.format or "compressed").lower()
    if image.mode in ("I;16", "I;16B", "I"):
        wide = image.convert("I")
        values = array.array("i", wide.tobytes())
        return _depth_picture(wide, values, encoding, image.width, image.height, unit="mm")
    return Picture(image, encoding, image.width, image.height)


@dataclass(frozen=True)
class Encoded:
    """A picture as file bytes, and the size it was encoded at."""

    data: bytes
    width: int
    height: int


def encode_picture(picture: Picture, max_size: int, fmt: ImageFormat) -> Encoded:
    """The picture no larger than ``max_size`` on its longest side, as JPEG or PNG bytes."""
    image = picture.image
    if max(image.width, image.height) > max_size:
        scale = max_size / max(image.width, image.height)
        size = (max(1, round(image.width * scale)), max(1, round(image.height * scale)))
        # reducing_gap: shrink by whole factors first (fast), then resample the rest properly.
        image = image.resize(size, Image.Resampling.BILINEAR, reducing_gap=2.0)
    out = io.BytesIO()
    if fmt == "jpeg":
        if image.mode not in ("RGB", "L"):
            image = image.convert("RGB")
        image.save(out, "JPEG", quality=_JPEG_QUALITY)
    else:
        image.save(out, "PNG", compress_level=1)
    return Encoded(out.getvalue(), image.width, image.height)


def _dimension(msg: Mapping[str, Any], name: str) -> int:
    value = msg.get(name)
    if not isinstance(value, int) or isinstance(value, bool) or value < 0:
        raise ImageError(f"The image's {name} is {value!r}, not a size in pixels.")
    return value


def _step(msg: Mapping[str, Any], width: int, pixel: int, height: int, data: bytes) -> int:
    """Bytes per row: ``step`` when given (rows may be padded), else width × pixel size."""
    step = msg.get("step")
    row = width * pixel
    if not isinstance(step, int) or isinstance(step, bool) or step == 0:
        step = row
    if step < row:
        raise ImageError(f"The image's step ({step} bytes per row) is shorter than a row of {width} pixels.")
    needed = step * (height - 1) + row
    if len(data) < needed:
        raise ImageError(
            f"The image has {len(data)} bytes of data; {width}x{height} at {step} bytes per row needs "
            f"{needed}."
        )
    return step


def _rows(data: bytes, width: int, height: int, step: int, pixel: int) -> bytes:
    row = width * pixel
    if step == row:
        return data[: row * height]
    return b"".join(data[y * step : y * step + row] for y in range(height))


def _pixels_16(data: bytes, width: int, height: int, step: int, big_endian: bool) -> array.array[int]:
    values = array.array("H", _rows(data, width, height, step, 2))
    if big_endian != (sys.byteorder == "big"):
        values.byteswap()
    return values


def _pixels_float(data: bytes, width: int, height: int, step: int, big_endian: bool) -> array.array[float]:
    values = array.array("f", _rows(data, width, height, step, 4))
    if big_endian != (sys.byteorder == "big"):
        values.byteswap()
    return values


def _depth_picture(
    image: Image.Image, values: Any, encoding: str, width: int, height: int, *, unit: str
) -> Picture:
    """Grey over the valid depths (0 and NaN mean "no reading" in both encodings): near dark, far light."""
    valid = [v for v in values if v > 0 and math.isfinite(v)]
    if not valid:
        black = Image.new("L", (width, height), 0)
        return Picture(black, encoding, width, height, DepthRange(0.0, 0.0, unit, 0))
    near, far = min(valid), max(valid)
    span = (far - near) or 1.0
    # Pillow evaluates a point() function on an I or F image once, as scale and offset; converting to L
    # clamps, so "no reading" (0, NaN) comes out black and the nearest valid depth just above it.
    grey = image.point(lambda v: (v - near) * (254.0 / span) + 1.0).convert("L")
    return Picture(grey, encoding, width, height, DepthRange(float(near), float(far), unit, len(valid)))
