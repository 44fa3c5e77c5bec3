"""Camera frames as pictures: ``sensor_msgs/Image`` and ``CompressedImage`` messages to JPEG or PNG bytes.

rosbridge sends the pixel bytes (``uint8[] data``) as one base64 string in JSON (a list of ints from some
bridges; both are accepted). A raw image carries ``width``, ``height``, ``encoding``, ``is_bigendian`` and
``step`` (bytes per row, which may include padding). Depth images (``16UC1`` in millimetres, ``32FC1`` in
metres) are normalised to grey over the range of valid (non-zero, finite) pixels, nearer is darker, and the
range is reported.

Before anything is decoded, the size the message declares (a raw image's width × height, a compressed
image's PNG or JPEG header) is held to the decode budget of ``budget.py``: a frame that would take more memory
than that is refused, naming its size, and never decoded. Only JPEG and PNG are opened (what
``image_transport`` sends); Pillow's other formats are more surface than a camera needs. Pure: no I/O.
"""

from __future__ import annotations

import array
import base64
import binascii
import io
import math
import struct
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

from rosbridge_mcp_server.robot.budget import budget_problem
from rosbridge_mcp_server.robot.wording import full_stop

if TYPE_CHECKING:
    from PIL import Image

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
#: Bytes a raw encoding's decode holds per pixel at once: Pillow keeps colour in 4 bytes a pixel; mono16 is
#: read 16-bit, widened to 32 and cut to 8; a depth image is also a list of its valid values (a Python number
#: each) to find its range.
_RAW_COST: dict[str, int] = {"mono16": 11, "16UC1": 51, "32FC1": 49} | {
    encoding: 1 if mode == "L" else 4 for encoding, (mode, _, _) in _COLOUR.items()
}
#: The same for a compressed frame: an 8-bit grey or palette picture 1 byte a pixel, colour 4, a 16-bit grey
#: (depth) PNG read as depth like 16UC1.
_GREY, _COLOUR_COST, _DEPTH_COST = 1, 4, 55
#: The compressed formats opened, as Pillow names them.
_COMPRESSED_FORMATS = ("PNG", "JPEG")
#: Pillow's own limit on the pixels of one picture (``Image.MAX_IMAGE_PIXELS``), when it has been unset.
_PILLOW_PIXELS = 89_478_485


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
    from PIL import Image  # noqa: PLC0415 - Pillow on first use

    encoding = str(msg.get("encoding", "")).strip()
    width = _dimension(msg, "width")
    height = _dimension(msg, "height")
    if width == 0 or height == 0:
        raise ImageError(f"The image is empty ({width}x{height}).")
    if encoding in _RAW_COST:
        _within_budget(f"{width}x{height} pixels of {encoding}", width * height * _RAW_COST[encoding])
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
    from PIL import Image, UnidentifiedImageError  # noqa: PLC0415 - Pillow on first use

    fmt = str(msg.get("format", "")).strip()
    data = message_bytes(msg.get("data"))
    # image_transport's compressedDepth puts a small configuration header before the PNG.
    png_start = data.find(b"\x89PNG")
    if "compresseddepth" in fmt.lower() and png_start > 0:
        data = data[png_start:]
    header = _declared(data)
    if header is None:
        raise ImageError(
            f"The compressed image (format {fmt or 'not given'!r}) could not be decoded: its bytes are not a "
            "picture this server decodes (JPEG or PNG)."
        )
    width, height, kind, cost = header
    declared = f"{width}x{height} pixels ({kind})"
    _within_budget(declared, width * height * cost, what="The compressed image")
    # Pillow warns above this many pixels (and refuses above twice as many); a server must do neither.
    most = Image.MAX_IMAGE_PIXELS or _PILLOW_PIXELS
    if width * height > most:
        raise ImageError(
            f"The compressed image declares {declared}: more than the {most:,} pixels "
            "Pillow decodes safely, so it was not decoded. A real camera sends far less; check what "
            "publishes it."
        )
    try:
        image = Image.open(io.BytesIO(data), formats=_COMPRESSED_FORMATS)
        if image.size != (width, height):
            raise ImageError(
                f"The compressed image's header says {width}x{height} but Pillow reads {image.width}x"
                f"{image.height}; it was not decoded."
            )
        image.load()
    except UnidentifiedImageError:
        raise ImageError(
            f"The compressed image (format {fmt or 'not given'!r}) could not be decoded: its bytes are not a "
            "picture this server decodes (JPEG or PNG)."
        ) from None
    except OSError as exc:
        raise ImageError(
            f"The compressed image (format {fmt or 'not given'!r}) could not be decoded: "
            + full_stop(str(exc))
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
    from PIL import Image  # noqa: PLC0415 - Pillow on first use

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


def _within_budget(declared: str, needed: int, *, what: str = "The image") -> None:
    problem = budget_problem(what, declared, needed)
    if problem is not None:
        raise ImageError(problem)


_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
#: PNG colour types: (what it is, decode cost per pixel at 8 bits).
_PNG_COLOUR_TYPES = {
    0: ("grey", _GREY),
    2: ("RGB", _COLOUR_COST),
    3: ("palette", _GREY),
    4: ("grey+alpha", _COLOUR_COST),
}
#: JPEG start-of-frame markers (SOF0-SOF15 but DHT, JPG and DAC), which carry the frame's size.
_JPEG_FRAMES = frozenset(range(0xC0, 0xD0)) - {0xC4, 0xC8, 0xCC}


def _declared(data: bytes) -> tuple[int, int, str, int] | None:
    """What a PNG's or JPEG's header declares: width, height, what its pixels are, decode bytes per pixel;
    ``None`` when the bytes are neither (or the header is cut short). Read before Pillow sees the bytes."""
    if data.startswith(_PNG_SIGNATURE) and data[12:16] == b"IHDR" and len(data) >= 26:
        width, height, bits, colour = struct.unpack(">IIBB", data[16:26])
        kind, cost = _PNG_COLOUR_TYPES.get(colour, ("RGBA", _COLOUR_COST))
        if colour == 0 and bits == 16:
            return width, height, "16-bit grey PNG", _DEPTH_COST
        return width, height, f"{bits}-bit {kind} PNG", cost
    if not data.startswith(b"\xff\xd8"):
        return None
    at = 2
    while at + 4 <= len(data):
        if data[at] != 0xFF:
            return None
        marker = data[at + 1]
        if marker == 0xFF:  # fill byte
            at += 1
            continue
        if marker == 0x01 or 0xD0 <= marker <= 0xD9:  # markers without a length
            at += 2
            continue
        (length,) = struct.unpack(">H", data[at + 2 : at + 4])
        if marker in _JPEG_FRAMES:
            if at + 10 > len(data):
                return None
            height, width, components = struct.unpack(">HHB", data[at + 5 : at + 10])
            kind = "grey JPEG" if components == 1 else f"{components}-channel JPEG"
            return width, height, kind, _GREY if components == 1 else _COLOUR_COST
        at += 2 + length
    return None


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
    from PIL import Image  # noqa: PLC0415 - Pillow on first use

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
