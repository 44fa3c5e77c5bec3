"""The one validation every tool's arguments get: a strict model made the way every tool's is, refused in our
words (no server)."""

from __future__ import annotations

import inspect
import json
import typing
from typing import Annotated, Any

import pytest
from pydantic import Field, ValidationError

from rosbridge_mcp_server.server.adapter import arguments_model, module_tool
from rosbridge_mcp_server.server.failures import arguments_text
from rosbridge_mcp_server.tools import TOOL_MODULES
from rosbridge_mcp_server.tools.arguments import (
    FROM_JSON_TEXT,
    MAX_TEXT_ARGUMENT,
    NO_FIELDS,
    JsonObject,
    JsonValue,
)


async def _run(
    ctx: object,
    *,
    topic: Annotated[str, Field(description="e.g. /a")],
    message: Annotated[JsonObject, Field(description="e.g. {}")] = NO_FIELDS,
    timeout: Annotated[float, Field(gt=0, description="e.g. 2")] = 1.0,
    latch: Annotated[bool, Field(description="e.g. true")] = False,
    value: Annotated[JsonValue, Field(description="e.g. 1")] = None,
    names: Annotated[list[str] | None, Field(description='e.g. ["/a"]'), FROM_JSON_TEXT] = None,
) -> None:
    """A tool's run: its parameters are the model's fields."""


def _model() -> Any:
    hints = typing.get_type_hints(_run, include_extras=True)
    parameters = list(inspect.signature(_run).parameters.values())[1:]
    return arguments_model("t", [p.replace(annotation=hints[p.name]) for p in parameters])


MODEL = _model()
SCHEMA = {
    "properties": dict.fromkeys(["topic", "message", "timeout", "latch", "value", "names"]),
    "required": ["topic"],
}


def _refusal(arguments: dict[str, Any]) -> str:
    with pytest.raises(ValidationError) as caught:
        MODEL.model_validate(arguments, strict=True)
    return arguments_text("t", caught.value, SCHEMA)


def test_fitting_arguments_pass_in_one_validation() -> None:
    """Right keys and kinds: one model holds them, JSON text for the object read into the object."""
    read = MODEL.model_validate(
        {"topic": "/a", "message": '{"x": 1}', "timeout": 2, "latch": True, "names": '["/b"]'}, strict=True
    )
    assert (read.message, read.timeout, read.latch, read.names) == ({"x": 1}, 2, True, ["/b"])
    assert MODEL.model_validate({"topic": "/a", "message": "  "}, strict=True).message == {}


def test_the_default_object_is_a_fresh_copy_every_call() -> None:
    """A tool that changed its message could not change the next call's default."""
    first = MODEL.model_validate({"topic": "/a"}, strict=True).message
    first["x"] = 1
    assert MODEL.model_validate({"topic": "/a"}, strict=True).message == {}
    assert NO_FIELDS == {}


def test_an_untyped_argument_takes_long_text() -> None:
    """A value of any type (a parameter's value) is held to the payload limits, not the 1,000 characters."""
    assert MODEL.model_validate({"topic": "/a", "value": "x" * 50_000}, strict=True).value == "x" * 50_000


def test_a_long_name_is_refused_naming_the_limit() -> None:
    """A plain string argument over the limit names the argument and the limit."""
    problem = _refusal({"topic": "/" + "a" * MAX_TEXT_ARGUMENT})
    assert f"topic: {MAX_TEXT_ARGUMENT + 1} characters, more than the {MAX_TEXT_ARGUMENT}" in problem


def test_a_boolean_is_fine_where_the_schema_takes_one_and_refused_for_a_number() -> None:
    """``latch: true`` passes; ``timeout: false`` does not, nor is ``"2"`` a number."""
    assert MODEL.model_validate({"topic": "/a", "latch": True}, strict=True).latch is True
    assert "timeout: expected a number, got false (a boolean is not a number)" in _refusal(
        {"topic": "/a", "timeout": False}
    )
    assert "timeout: expected a number (got '2')" in _refusal({"topic": "/a", "timeout": "2"})


def test_several_unknown_keys_are_all_named_first() -> None:
    """Every unknown key is listed, with the likely meant one where there is one, before other problems."""
    problem = _refusal({"topic": "/a", "mesage": {}, "zzz": 1, "timeout": -1})
    assert problem.startswith(
        "Invalid arguments for t: unknown arguments 'mesage' (did you mean message?), 'zzz';"
    )
    assert "timeout: input should be greater than 0 (got -1)" in problem


@pytest.mark.parametrize(
    ("given", "said"),
    [
        ("null", "message: expected a JSON object; the text 'null' holds null"),
        ("[1, 2]", "message: expected a JSON object; the text '[1, 2]' holds a list"),
        ('{"x": ', "message: is not valid JSON (Expecting value at character 6)"),
        ("[" * 5000 + "]" * 5000, "message: nests deeper than 64 levels"),
        ([1, 2], "message: expected a JSON object (got [1, 2])"),
        (json.dumps({"data": "\ud800"}), "message: holds an unpaired UTF-16 surrogate (\\ud800)"),
    ],
)
def test_an_object_argument_of_the_wrong_kind_is_one_line_saying_what_it_holds(given: Any, said: str) -> None:
    """JSON text that is not an object, is not JSON or nests too deep, and a list: each once, in our words."""
    problem = _refusal({"topic": "/a", "message": given})
    assert said in problem
    assert problem.count("message:") == 1


def test_a_deep_value_given_for_a_name_is_shown_short() -> None:
    """The refusal quotes a few levels of what was given, whatever its depth."""
    deep: dict[str, Any] = {}
    for _ in range(500):
        deep = {"a": deep}
    problem = _refusal({"topic": deep})
    assert "topic: expected a string (got {'a': {'a': {...}}})" in problem


def test_every_tool_model_is_strict_and_closed() -> None:
    """Every tool's model takes no key it does not list and no string for a number (one validation)."""
    for module in TOOL_MODULES:
        tool = module_tool(module)
        assert tool.arguments.model_config.get("strict") is True, tool.name
        assert tool.arguments.model_config.get("extra") == "forbid", tool.name
