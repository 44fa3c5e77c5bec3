"""Property: JSON text (``"null"``, ``"[1, 2]"``, ...) for parameters that are not text — what a client that
writes every argument as a string sends, and what the SDK reads as JSON before it validates — beside any other
arguments, for any tool: an error is always our sentence (or the tool's), never the SDK's raw "N validation
errors for ...Arguments". Derandomized, as ``test_mcp_property_arguments.py``, whose session it shares."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
from argument_strategies import Vocabulary, call_deadline, tool_calls
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st
from mcp.types import CallToolResult
from mcp_harness import text_of
from test_mcp_property_arguments import SessionThread

EXAMPLES = 100
#: JSON inside a string, which the SDK reads as JSON before it validates (null, a boolean, a list, an object).
JSON_TEXTS = ["null", "true", "[1, 2]", "{}", '{"data": 1}', "[]"]


def json_text_calls(
    schemas: dict[str, dict[str, Any]], vocabulary: Vocabulary
) -> st.SearchStrategy[tuple[str, dict[str, Any]]]:
    """``(tool name, arguments)`` of ``tool_calls`` with JSON text for at least one parameter that is not
    plain text, the others as they come."""
    takers = {
        name: [key for key, prop in schema.get("properties", {}).items() if prop.get("type") != "string"]
        for name, schema in schemas.items()
    }
    some = {name: schema for name, schema in schemas.items() if takers[name]}

    def with_text(call: tuple[str, dict[str, Any]]) -> st.SearchStrategy[tuple[str, dict[str, Any]]]:
        name, arguments = call
        texts = st.dictionaries(st.sampled_from(takers[name]), st.sampled_from(JSON_TEXTS), min_size=1)
        return texts.map(lambda text: (name, arguments | text))

    return tool_calls(some, vocabulary).flatmap(with_text)


@pytest.fixture(scope="module", params=["ros2", "ros1"])
def hosted(request: pytest.FixtureRequest) -> Iterator[SessionThread]:
    """A session per dialect."""
    hosted = SessionThread(request.param)
    try:
        yield hosted
    finally:
        hosted.close()


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:Generating overly large repr")
def test_json_text_for_parameters_that_are_not_text_is_answered_in_our_words(hosted: SessionThread) -> None:
    """Every error names what is wrong in our words; the session keeps working."""
    errors = 0

    @settings(
        max_examples=EXAMPLES,
        derandomize=True,
        database=None,
        deadline=None,
        phases=[Phase.explicit, Phase.generate],
        suppress_health_check=list(HealthCheck),
    )
    @given(json_text_calls(hosted.schemas, hosted.vocabulary))
    def one_call(call: tuple[str, dict[str, Any]]) -> None:
        nonlocal errors
        name, arguments = call
        deadline = call_deadline(arguments, hosted.schemas[name])
        result: CallToolResult = hosted.run(hosted.session.call(name, arguments), deadline)
        if result.is_error:
            errors += 1
            assert "validation error" not in text_of(result), text_of(result)[:300]
            assert "Error executing tool" not in text_of(result), text_of(result)[:300]

    one_call()
    assert errors > EXAMPLES // 2, "most calls with JSON text for a number or an object are errors"
    follow_up: CallToolResult = hosted.run(hosted.session.call("list_topics", {}), 10.0)
    assert not follow_up.is_error, text_of(follow_up)[:300]
