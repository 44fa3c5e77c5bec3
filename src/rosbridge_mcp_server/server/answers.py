"""A tool's answer on its way out: images as MCP content, the fleet robot named where settings are pointed
at, the answers of a call made on several robots merged into one, and text the SDK can write
(:func:`writable`)."""

from __future__ import annotations

import base64
import typing
from typing import Any

from mcp.types import CallToolResult, ImageContent, InputRequiredResult, TextContent

from rosbridge_mcp_server.errors import NotConnectedError
from rosbridge_mcp_server.robot.text import repaired
from rosbridge_mcp_server.tools.base import ToolImage

if typing.TYPE_CHECKING:
    from rosbridge_mcp_server.config import Config

__all__ = ["images", "merged", "where_set", "writable"]


class NamedRobot(typing.Protocol):
    """A robot as an answer names it (``server.fleet.Robot`` is one)."""

    @property
    def name(self) -> str: ...
    @property
    def config(self) -> Config: ...


def writable(result: CallToolResult | InputRequiredResult) -> CallToolResult | InputRequiredResult:
    """*result* with no unpaired UTF-16 surrogate left in its texts and structured content: the last line
    before an answer is written. The SDK's JSON writer refuses such a string, and on stdio that ends the
    server; robot text is repaired where frames are decoded (``wire/protocol.py``), this catches any other
    way one could come (a file, a path we missed). The very result when it holds none."""
    if not isinstance(result, CallToolResult):
        return result
    texts = [block.text for block in result.content if isinstance(block, TextContent)]
    structured = result.structured_content
    if repaired(texts) is texts and repaired(structured) is structured:
        return result
    content = [
        block.model_copy(update={"text": repaired(block.text)}) if isinstance(block, TextContent) else block
        for block in result.content
    ]
    return result.model_copy(update={"content": content, "structured_content": repaired(structured)})


def where_set(text: str, robot: NamedRobot) -> str:
    """*text* with a fleet robot's own entry (``[robots.base] in --robots fleet.toml``) named where a robot
    that cannot be reached points at the server's ROSBRIDGE_HOST/PORT settings, which it does not use."""
    if robot.config.url_source is None:
        return text
    return text.replace(NotConnectedError.SETTINGS, f"{robot.config.url_source} (robot {robot.name})")


def images(images: typing.Iterable[ToolImage]) -> list[ImageContent]:
    return [
        ImageContent(
            type="image", data=base64.b64encode(image.data).decode("ascii"), mime_type=image.mime_type
        )
        for image in images
    ]


def merged(names: list[str], answers: list[CallToolResult | InputRequiredResult]) -> CallToolResult:
    """One answer for a call made on several robots: each robot's text under its name, and every list of
    the structured content joined with each entry prefixed by its robot (stop_robot's answer is lists)."""
    texts: list[str] = []
    data: dict[str, Any] = {}
    failed = False
    for name, answer in zip(names, answers, strict=True):
        if not isinstance(answer, CallToolResult):
            # Only stop_robot runs on several robots, and it never asks the person.
            texts.append(f"{name}: could not run here")
            failed = True
            continue
        failed = failed or bool(answer.is_error)
        text = "\n".join(block.text for block in answer.content if isinstance(block, TextContent))
        # Every line under its robot: a robot's answer may take several.
        texts += [f"{name}: {line}" for line in text.splitlines() or [""]]
        for key, value in (answer.structured_content or {}).items():
            if isinstance(value, list):
                data.setdefault(key, []).extend(f"{name}: {item}" for item in value)
    return CallToolResult(
        content=[TextContent(type="text", text="\n".join(texts))],
        structured_content=None if failed else data,
        is_error=failed,
    )
