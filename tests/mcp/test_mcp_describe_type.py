"""describe_type through an MCP session: messages, services and actions, in both dialects."""

from __future__ import annotations

from mcp_harness import Session, text_of, types_for

from rosbridge_mcp_server.sim import SimulatedRobot


async def test_a_message_type_is_outlined_with_an_example(session: Session, sim: SimulatedRobot) -> None:
    """Twist: linear and angular with x/y/z, and an example publish_topic accepts."""
    result = await session.ok("describe_type", {"type_name": types_for(sim)["twist"]})
    data = result.structured_content
    assert data is not None
    assert data["kind"] == "message"
    assert data["parts"][0]["outline"][:2] == ["linear: geometry_msgs/Vector3", "  x: float64"]
    assert data["example"] == {
        "linear": {"x": 0.0, "y": 0.0, "z": 0.0},
        "angular": {"x": 0.0, "y": 0.0, "z": 0.0},
    }
    assert "Example for publish_topic" in text_of(result)


async def test_the_example_is_accepted_by_publish_topic(session: Session, sim: SimulatedRobot) -> None:
    """The example of Twist goes through publish_topic unchanged."""
    twist = types_for(sim)["twist"]
    described = await session.ok("describe_type", {"type_name": twist})
    example = (described.structured_content or {})["example"]
    await session.ok(
        "publish_topic", {"topic": "/turtle1/cmd_vel", "message_type": twist, "message": example}
    )
    await sim.world.wait_for(lambda w: bool(w.published.get("/turtle1/cmd_vel")))
    assert sim.world.published["/turtle1/cmd_vel"][-1].msg == example


async def test_a_service_type_shows_request_and_response(session: Session, sim: SimulatedRobot) -> None:
    """AddTwoInts: request a, b and response sum; the example is the request."""
    result = await session.ok("describe_type", {"type_name": types_for(sim)["add_two_ints"]})
    data = result.structured_content
    assert data is not None
    assert data["kind"] == "service"
    assert [p["part"] for p in data["parts"]] == ["request", "response"]
    assert data["parts"][1]["outline"] == ["sum: int64"]
    assert data["example"] == {"a": 0, "b": 0}


async def test_an_action_type_shows_goal_result_and_feedback(session: Session, sim: SimulatedRobot) -> None:
    """Fibonacci: goal order, result and feedback sequences, in either dialect's spelling."""
    result = await session.ok("describe_type", {"type_name": types_for(sim)["fibonacci"]})
    data = result.structured_content
    assert data is not None
    assert data["kind"] == "action"
    assert [p["part"] for p in data["parts"]] == ["goal", "result", "feedback"]
    assert data["parts"][0]["outline"] == ["order: int32"]
    assert data["parts"][1]["outline"] == ["sequence: int32[]"]
    assert data["example"] == {"order": 0}


async def test_a_short_name_finds_the_kind_itself(session: Session) -> None:
    """std_srvs/SetBool without a category is found as a service in both dialects."""
    result = await session.ok("describe_type", {"type_name": "std_srvs/SetBool"})
    assert (result.structured_content or {})["kind"] == "service"


async def test_an_unknown_type_is_an_error_with_the_naming_rule(session: Session) -> None:
    """A type that does not exist is an error naming it and how names look."""
    text = await session.error("describe_type", {"type_name": "geometry_msgs/msg/Twistt"})
    assert "'geometry_msgs/msg/Twistt'" in text
    assert "type names look like" in text


async def test_a_malformed_type_name_is_an_error(session: Session) -> None:
    """A name without a package is refused with the expected form."""
    text = await session.error("describe_type", {"type_name": "Twist"})
    assert "pkg/Type" in text
