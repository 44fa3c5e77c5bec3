"""The checks every tool's arguments get first, on schemas alone (no server)."""

from __future__ import annotations

from rosbridge_mcp_server.tools.arguments import MAX_TEXT_ARGUMENT, argument_problem

SCHEMA = {
    "properties": {
        "topic": {"type": "string"},
        "message": {"anyOf": [{"type": "object"}, {"type": "string"}]},
        "timeout": {"type": "number"},
        "latch": {"type": "boolean"},
        "value": {},
    },
    "required": ["topic"],
}


def test_fitting_arguments_pass() -> None:
    """Right keys and kinds: no refusal."""
    assert (
        argument_problem("t", {"topic": "/a", "message": {"x": 1}, "timeout": 2, "latch": True}, SCHEMA)
        is None
    )


def test_an_untyped_argument_takes_long_text() -> None:
    """A value of any type (a parameter's value) is held to the payload limits, not the 1,000 characters."""
    assert argument_problem("t", {"topic": "/a", "value": "x" * 50_000}, SCHEMA) is None


def test_a_long_name_is_refused_naming_the_limit() -> None:
    """A plain string argument over the limit names the argument and the limit."""
    problem = argument_problem("t", {"topic": "/" + "a" * MAX_TEXT_ARGUMENT}, SCHEMA)
    assert problem is not None
    assert f"topic: {MAX_TEXT_ARGUMENT + 1} characters, more than the {MAX_TEXT_ARGUMENT}" in problem


def test_a_boolean_is_fine_where_the_schema_takes_one_and_refused_for_a_number() -> None:
    """``latch: true`` passes; ``timeout: false`` does not."""
    assert argument_problem("t", {"topic": "/a", "latch": True}, SCHEMA) is None
    problem = argument_problem("t", {"topic": "/a", "timeout": False}, SCHEMA)
    assert problem is not None
    assert "timeout: expected a number, got false" in problem


def test_several_unknown_keys_are_all_named() -> None:
    """Every unknown key is listed, with the likely meant one where there is one."""
    problem = argument_problem("t", {"topic": "/a", "mesage": {}, "zzz": 1}, SCHEMA)
    assert problem is not None
    assert "unknown arguments 'mesage' (did you mean message?), 'zzz'" in problem
