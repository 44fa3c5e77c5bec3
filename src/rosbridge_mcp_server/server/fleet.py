"""The robots one server drives: each with its own configuration and robot session (client, graph, goals,
activity, guard).

With one robot nothing here shows: tools take no ``robot`` argument and ``tools/list`` is as before. With
several, the edge (``tool_calls.py``) takes the ``robot`` argument off every call before the tool's arguments
are validated (:meth:`Fleet.choose`) and hands the chosen robots to the tool's handler with the call; a
tool whose spec says ``every_robot`` (``stop_robot``) runs on every robot without one. ``list_robots`` says
what each robot is.

A robot whose policy is read-only (``read_only = true`` in the fleet file, or the whole server read-only) is
read-only in a fleet too: an acting tool's ``robot`` property offers only the robots that may act, and a call
naming a read-only robot is refused by the checks (:meth:`Fleet.read_only_refusal`) before the tool runs, so
nothing reaches its bridge (which may be another robot's too). The stop (a spec's ``stops``) stays allowed on
every robot. What a tool is comes from its spec (``EdgeTool.spec``), never from its name.
"""

from __future__ import annotations

import json
import re
import typing
from collections.abc import Container, Sequence
from dataclasses import dataclass
from typing import Any
from urllib.parse import urlsplit, urlunsplit

from mcp.types import CallToolResult, TextContent, ToolAnnotations
from pydantic import BaseModel, Field

from rosbridge_mcp_server.server.adapter import EdgeTool, ToolCall, arguments_model, edge_tool

if typing.TYPE_CHECKING:
    from rosbridge_mcp_server.config import Config
    from rosbridge_mcp_server.robot.session import RobotSession

__all__ = ["LIST_ROBOTS", "ROBOT_ARGUMENT", "Fleet", "Robot", "list_robots_tool"]

ROBOT_ARGUMENT = "robot"
#: The tool about the fleet itself: it runs on no robot and takes no ``robot`` argument.
LIST_ROBOTS = "list_robots"


@dataclass(frozen=True)
class Robot:
    """One robot of the server: its name, its configuration (policy, timeouts) and its session."""

    name: str
    config: Config
    session: RobotSession


class Fleet:
    """The robots of one server, in the order they were configured."""

    def __init__(self, robots: Sequence[Robot]) -> None:
        if not robots:
            raise ValueError("a server needs at least one robot")
        self.robots = tuple(robots)
        self._by_name = {robot.name: robot for robot in robots}

    @property
    def several(self) -> bool:
        return len(self.robots) > 1

    @property
    def names(self) -> list[str]:
        return [robot.name for robot in self.robots]

    @property
    def read_only_names(self) -> list[str]:
        """The robots whose policy is read-only."""
        return [robot.name for robot in self.robots if robot.config.policy.read_only]

    @property
    def acting_names(self) -> list[str]:
        """The robots an acting tool may act on."""
        return [robot.name for robot in self.robots if not robot.config.policy.read_only]

    def read_only_refusal(self, tool: str, robots: Sequence[Robot], stops: Sequence[str]) -> str | None:
        """The sentence refusing acting *tool* on *robots* when one of them is read-only, or ``None``; *stops*
        are the tools that stop the robot, allowed everywhere."""
        read_only = [robot.name for robot in robots if robot.config.policy.read_only]
        if not read_only:
            return None
        others = self.acting_names
        can = (
            f" It can act on {', '.join(others)}."
            if others
            else " No robot of this server may be acted on; only reading tools work."
        )
        return (
            f"{tool} is not available on {', '.join(read_only)}: that robot is read-only (read_only = true "
            f"in its policy or the fleet file), so nothing was sent.{can} Reading tools work on every robot"
            + (f", and {' and '.join(stops)} too." if stops else ".")
        )

    def not_listed(self, tool: str) -> str | None:
        """Why the fleet's own tool *tool* is not listed (``list_robots`` on a server of one robot), or
        ``None``."""
        if tool != LIST_ROBOTS or self.several:
            return None
        return (
            f"Unknown tool: {LIST_ROBOTS} is listed only when the server drives several robots (start it "
            "with --robot NAME=URL once per robot, or --robots FILE); this server drives one robot, and "
            "every tool works on it without a robot argument."
        )

    def choose(
        self, tool: str, name: object, *, every_robot: bool = False
    ) -> tuple[tuple[Robot, ...], str | None]:
        """The robots a call of *tool* with ``robot=name`` runs on, or a refusal naming the robots; without a
        name, every robot when the tool's spec says ``every_robot``."""
        if name is None:
            if every_robot:
                return self.robots, None
            return (), (
                f"{tool} needs the robot argument: this server drives {len(self.robots)} robots "
                f"({', '.join(self.names)}); nothing was sent. list_robots describes each."
            )
        if not isinstance(name, str) or name not in self._by_name:
            shown = repr(name) if len(repr(name)) <= 40 else repr(name)[:37] + "..."
            return (), (
                f"Invalid arguments for {tool}: robot {shown} is not one of {', '.join(self.names)}; nothing "
                "was sent."
            )
        return (self._by_name[name],), None

    def calls_on(self, result: CallToolResult, robot: str, tools: Container[str]) -> CallToolResult:
        """*result* with every call it suggests (``read_logs {"node": "/amcl"}``) made a call on *robot*: a
        fleet's tools take ``robot``, which the tools that word the suggestions do not know of."""
        if not self.several:
            return result
        content = [
            block.model_copy(update={"text": _robot_in_calls(block.text, robot, tools)})
            if isinstance(block, TextContent)
            else block
            for block in result.content
        ]
        data = result.structured_content
        if data is not None:
            data = _each_text(data, lambda text: _robot_in_calls(text, robot, tools))
        return result.model_copy(update={"content": content, "structured_content": data})

    def schema_with_robot(self, tool: EdgeTool) -> dict[str, Any]:
        """*tool*'s input schema with the ``robot`` property when there are several: required unless its spec
        says ``every_robot``; an acting tool's offers only the robots that are not read-only, unless it is
        the stop."""
        schema = tool.input_schema
        if not self.several:
            return schema
        spec = tool.spec
        every = spec is not None and spec.every_robot
        anywhere = tool.reads or (spec is not None and spec.stops)
        names = self.names if anywhere else self.acting_names
        description = "Which robot: " + ", ".join(names)
        if every:
            description += f" (omit to {'stop' if spec is not None and spec.stops else 'run on'} every robot)"
        elif names != self.names:
            description += f" ({', '.join(self.read_only_names)}: read-only)"
        properties = {
            **schema.get("properties", {}),
            ROBOT_ARGUMENT: {"type": "string", "enum": names, "description": description},
        }
        required = list(schema.get("required", []))
        if not every:
            required.append(ROBOT_ARGUMENT)
        return {**schema, "properties": properties, "required": required}


#: A suggested call in an answer: a tool's name, a space, its arguments as a JSON object.
_CALL = re.compile(r"\b([a-z][a-z_]+) (?=\{)")


def _each_text(value: Any, change: typing.Callable[[str], str]) -> Any:
    """*value* (structured content) with *change* applied to every string in it, keys left alone."""
    if isinstance(value, str):
        return change(value) if " {" in value else value
    if isinstance(value, dict):
        return {key: _each_text(item, change) for key, item in value.items()}
    if isinstance(value, list):
        return [_each_text(item, change) for item in value]
    return value


def _robot_in_calls(text: str, robot: str, tools: Container[str]) -> str:
    """*text* with ``"robot": ROBOT`` first in the arguments of each ``tool {...}`` it suggests."""
    decoder = json.JSONDecoder()
    out, at = [], 0
    for match in _CALL.finditer(text):
        if match.group(1) not in tools or match.start() < at:
            continue
        try:
            arguments, end = decoder.raw_decode(text, match.end())
        except json.JSONDecodeError:
            continue
        if not isinstance(arguments, dict) or ROBOT_ARGUMENT in arguments:
            continue
        called = json.dumps({ROBOT_ARGUMENT: robot, **arguments}, ensure_ascii=False)
        out += [text[at : match.end()], called]
        at = end
    return "".join(out) + text[at:]


class RobotRow(BaseModel):
    """One robot as list_robots shows it."""

    name: str
    url: str = Field(description="The robot's rosbridge URL (credentials left out)")
    connected: bool
    ros: str | None = Field(description="ROS version and distribution, once connected, e.g. 'ROS 2 jazzy'")
    policy: str = Field(description="The robot's safety policy in one line")


class RobotsAnswer(BaseModel):
    """Every robot this server drives."""

    robots: list[RobotRow]


def list_robots_tool(fleet: Fleet) -> EdgeTool:
    """The ``list_robots`` tool: each robot's connection, ROS version and policy summary."""

    async def handler(call: ToolCall, arguments: BaseModel) -> CallToolResult:
        rows = [_row(robot) for robot in fleet.robots]
        lines = [
            f"{row.name}: {'connected' if row.connected else 'not connected'}"
            f"{f', {row.ros}' if row.ros else ''}, {row.url}; policy: {row.policy}"
            for row in rows
        ]
        text = f"{len(rows)} robots (pass one as the robot argument):\n" + "\n".join(lines)
        return CallToolResult(
            content=[TextContent(type="text", text=text)],
            structured_content=RobotsAnswer(robots=rows).model_dump(mode="json"),
        )

    return edge_tool(
        name=LIST_ROBOTS,
        title="List the robots",
        description=(
            "The robots this server drives, with their connection, ROS version and safety policy. Every "
            "other tool takes one of these names as its robot argument."
        ),
        annotations=ToolAnnotations(read_only_hint=True, open_world_hint=False),
        arguments=arguments_model(LIST_ROBOTS, []),
        output=RobotsAnswer,
        handler=handler,
        on_robot=False,
    )


def _row(robot: Robot) -> RobotRow:
    client = robot.session.client
    facts = client.session_facts
    ros = None
    if facts is not None:
        info = facts.info
        ros = f"ROS {info.version}" + (f" {info.distro}" if info.distro else "")
    return RobotRow(
        name=robot.name,
        url=_without_credentials(client.url),
        connected=client.connected,
        ros=ros,
        policy=_policy_line(robot.config),
    )


def _policy_line(config: Config) -> str:
    """The policy in one line: ``from FILE; confirm = ...; [velocity] ...`` (describe()'s heading, "policy
    (from FILE):", said without the word the label already says)."""
    lines = [line.strip() for line in config.policy.describe()]
    if len(lines) == 1:
        return lines[0]
    heading = lines[0].rstrip(":").removeprefix("policy").strip().removeprefix("(").removesuffix(")")
    return "; ".join([heading, *lines[1:]] if heading else lines[1:])


def _without_credentials(url: str) -> str:
    parts = urlsplit(url)
    if parts.username is None and parts.password is None:
        return url
    host = parts.hostname or ""
    netloc = f"[{host}]" if ":" in host else host
    if parts.port is not None:
        netloc += f":{parts.port}"
    return urlunsplit(parts._replace(netloc=netloc))
