"""``publish_service``: call a ROS service and return its response."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, Field

from rosbridge_mcp_server.robot.messages import compact_json
from rosbridge_mcp_server.tools.arguments import NO_FIELDS, JsonObject
from rosbridge_mcp_server.tools.base import (
    ACTS_ON_ROBOT,
    ToolAnswer,
    ToolContext,
    ToolSpec,
)

__all__ = ["MAX_SERVICE_TIMEOUT", "SPEC", "ServiceAnswer", "run"]

MAX_SERVICE_TIMEOUT = 300.0
_EXAMPLE = '{"a": 2, "b": 3}'


class ServiceAnswer(BaseModel):
    """A service's response."""

    service: str
    service_type: str = Field(description="The service's type as the graph reports it")
    response: dict[str, Any] = Field(description="The response fields")


SPEC = ToolSpec(
    name="publish_service",
    title="Call a service",
    description=(
        "Call a service and return its response; can change the robot. Example: service "
        f"/add_two_ints, service_type example_interfaces/srv/AddTwoInts, request {_EXAMPLE}."
    ),
    hints=ACTS_ON_ROBOT,
    acts_on="service",
    output=ServiceAnswer,
)


async def run(
    ctx: ToolContext,
    service: Annotated[str, Field(description="e.g. /add_two_ints")],
    service_type: Annotated[
        str,
        Field(description="e.g. example_interfaces/srv/AddTwoInts"),
    ],
    request: Annotated[
        JsonObject,
        Field(description=f"Request fields as a JSON object, e.g. {_EXAMPLE}; {{}} for std_srvs/srv/Trigger"),
    ] = NO_FIELDS,
    timeout: Annotated[
        float,
        Field(
            gt=0,
            le=MAX_SERVICE_TIMEOUT,
            description=("Seconds to wait for the response, e.g. 10"),
        ),
    ] = 10.0,
) -> ToolAnswer:
    """Check the request when the type is known, call the service, return its response."""
    from rosbridge_mcp_server.robot.acting import call_service  # noqa: PLC0415 - on the first act

    body = request
    reply = await call_service(
        ctx, tool=SPEC.name, service=service, service_type=service_type, request=body, timeout=timeout
    )
    text = f"Service {reply.service} ({reply.type}) answered: {compact_json(reply.response)}"
    # rosbridge answers a successful call with the response message as an object; anything else is kept whole.
    fields = reply.response if isinstance(reply.response, dict) else {"value": reply.response}
    return ToolAnswer(
        text=text, data=ServiceAnswer(service=reply.service, service_type=reply.type, response=fields)
    )
