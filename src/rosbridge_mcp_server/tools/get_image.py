"""``get_image``: one camera frame as a picture the model can see."""

from __future__ import annotations

import asyncio
from typing import Annotated, Any

from pydantic import BaseModel, Field

from rosbridge_mcp_server.client import Dialect
from rosbridge_mcp_server.pictures.images import (
    Encoded,
    ImageError,
    ImageFormat,
    Picture,
    decode_compressed,
    decode_raw,
    encode_picture,
)
from rosbridge_mcp_server.robot.listening import listen
from rosbridge_mcp_server.robot.messages import short_type_name
from rosbridge_mcp_server.tools.base import (
    READS_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolFailure,
    ToolImage,
    ToolSpec,
    absolute_name,
)

__all__ = ["SPEC", "ImageAnswer", "run"]

_RAW = "sensor_msgs/Image"
_COMPRESSED = "sensor_msgs/CompressedImage"


class ImageAnswer(BaseModel):
    """The frame that was returned as an image."""

    topic: str
    message_type: str
    encoding: str = Field(description="The frame's encoding (rgb8, 16UC1, jpeg, ...)")
    width: int = Field(description="Pixels, as received")
    height: int = Field(description="Pixels, as received")
    sent_width: int = Field(description="Pixels, as returned")
    sent_height: int = Field(description="Pixels, as returned")
    format: ImageFormat
    frame_id: str
    stamp: float | None = Field(description="header.stamp in seconds (None when zero)")
    depth_range: list[float] | None = Field(
        description="Depth images: [nearest, farthest] shown, in depth_unit"
    )
    depth_unit: str | None = None


SPEC = ToolSpec(
    name="get_image",
    title="Camera frame",
    description=(
        "One camera frame (Image or CompressedImage) as a picture. Read-only. Example: "
        '{"topic": "/camera/image_raw"}. Depth comes as grey (nearer darker).'
    ),
    hints=READS_ROBOT,
    output=ImageAnswer,
)


async def run(
    ctx: ToolContext,
    *,
    topic: Annotated[str, Field(description="Image topic, e.g. /camera/image_raw")],
    max_size: Annotated[int, Field(ge=16, le=4096, description="Longest side in pixels, e.g. 800")] = 800,
    format: Annotated[ImageFormat, Field(description="Picture format, e.g. jpeg (or png)")] = "jpeg",
    timeout: Annotated[float, Field(gt=0, le=60, description="Seconds to wait for a frame, e.g. 5")] = 5.0,
) -> ToolAnswer:
    """Subscribe for one frame, convert it off the event loop, return it as an image."""
    name = absolute_name(topic, "topic")
    msg_type = await ctx.graph.topic_type(name)
    if not msg_type:
        missing, known = await ctx.graph.unknown_topic(name, among=_is_image)
        listing = f" Image topics: {', '.join(known)}." if known else " The graph has no image topics."
        raise ToolFailure(f"{missing}{listing}")
    if not _is_image(msg_type):
        raise ToolFailure(
            f"Topic {name} carries {msg_type}, not a sensor_msgs Image or CompressedImage; subscribe_topic "
            "reads other topics."
        )
    heard = await listen(ctx.client, name, msg_type, count=1, duration=None, first_timeout=timeout)
    if not heard.messages:
        raise ToolFailure(
            f"No frame arrived on {name} within {timeout:g} s. Is the camera running? get_topic_info shows "
            "the topic's publishers."
        )
    message = heard.messages[0].message
    compressed = short_type_name(msg_type) == _COMPRESSED
    try:
        picture, encoded = await asyncio.to_thread(_convert, message, compressed, max_size, format)
    except ImageError as exc:
        raise ToolFailure(f"{exc} (topic {name}).") from None
    answer = _answer(name, msg_type, message, picture=picture, encoded=encoded, fmt=format)
    return ToolAnswer(text=_text(answer), data=answer, images=(ToolImage(encoded.data, f"image/{format}"),))


def _is_image(msg_type: str) -> bool:
    return short_type_name(msg_type) in (_RAW, _COMPRESSED)


def _convert(
    message: dict[str, Any], compressed: bool, max_size: int, fmt: ImageFormat
) -> tuple[Picture, Encoded]:
    picture = decode_compressed(message) if compressed else decode_raw(message)
    return picture, encode_picture(picture, max_size, fmt)


def _answer(
    topic: str,
    msg_type: str,
    message: dict[str, Any],
    *,
    picture: Picture,
    encoded: Encoded,
    fmt: ImageFormat,
) -> ImageAnswer:
    header = message.get("header")
    header = header if isinstance(header, dict) else {}
    return ImageAnswer(
        topic=topic,
        message_type=msg_type,
        encoding=picture.encoding,
        width=picture.width,
        height=picture.height,
        sent_width=encoded.width,
        sent_height=encoded.height,
        format=fmt,
        frame_id=str(header.get("frame_id", "")),
        stamp=None if (at := Dialect.seconds(header.get("stamp"))) is None else round(at, 3),
        depth_range=[picture.depth.near, picture.depth.far] if picture.depth else None,
        depth_unit=picture.depth.unit if picture.depth else None,
    )


def _text(answer: ImageAnswer) -> str:
    size = f"{answer.width}x{answer.height}"
    if (answer.sent_width, answer.sent_height) != (answer.width, answer.height):
        size += f" (sent {answer.sent_width}x{answer.sent_height})"
    parts = [f"{answer.topic}: {size} {answer.encoding} as {answer.format}"]
    parts.append(f"frame {answer.frame_id or '(none)'}")
    if answer.stamp is not None:
        parts.append(f"stamp {answer.stamp:.3f}")
    if answer.depth_range is not None:
        near, far = answer.depth_range
        if near == far == 0:
            parts.append("no valid depth in the frame (all black)")
        else:
            parts.append(f"depth {near:g}-{far:g} {answer.depth_unit}, nearer is darker, black is no reading")
    return ", ".join(parts) + "."
