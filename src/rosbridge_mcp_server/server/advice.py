"""What to try after an error, worded for the model, naming the tools: the MCP edge's half of an error.

The domain (``robot/``, ``errors.py``) says what went wrong and carries what can be done next as a typed
fact (:class:`~rosbridge_mcp_server.errors.Hint`: an :class:`~rosbridge_mcp_server.errors.Advice` and the
names it involves); it names no MCP tool. :func:`advised` puts the two together: the error's own text, then
the advice in words, then what a tool said after the error's text (the hint's ``tail``, e.g. "Nothing was
set."). Each wording starts with what joins it to the error's text (a space, ``"; "``, ``" ("``).
"""

from __future__ import annotations

from typing import Final

from rosbridge_mcp_server.errors import Advice, Advised

__all__ = ["WORDS", "advised"]

#: Each advice as the model reads it after the error's text; ``{0}``, ``{1}``... are the hint's names.
WORDS: Final[dict[Advice, str]] = {
    Advice.TOPIC_TYPE: (
        " Publish a {0} message, or choose another topic (list_topics shows each topic's type)."
    ),
    Advice.SERVICES: " Call list_services to see the services.",
    Advice.SERVICE_NAME: "; check the name with list_services",
    Advice.ACTIONS: " Call list_actions to see the actions.",
    Advice.TOPICS_OR_TYPE: (
        " Call list_topics to see the topics, or give message_type to wait for a publisher that has not "
        "started yet."
    ),
    Advice.NAME: " Check the name with list_topics / list_services / list_actions.",
    Advice.PARAMETER_NAMES: " (list_parameters shows them).",
    Advice.ONE_PARAMETER: " Use set_parameter, or give each parameter's name as text.",
    Advice.TYPES_IN_USE: " list_topics, list_services and list_actions show the types in use.",
    Advice.ACTION_TYPES: (
        "; list_actions shows the action's type, and publish_action checks a goal against it."
    ),
    Advice.SERVICE_TYPES: "; list_services shows them.",
    Advice.RECORDINGS: " (read_recording without a file lists them).",
    Advice.NO_RECORDING: "; read_recording without a file lists them.",
    Advice.NODES: "; list_nodes lists the nodes.",
    Advice.RUNNING_NODES: " Call list_nodes to see the nodes.",
    Advice.TOPIC_TYPES: "; list_topics shows the types in use.",
}


def advised(exc: BaseException) -> str:
    """The error's text, followed by what to try when it carries a hint."""
    text = str(exc)
    hint = exc.hint if isinstance(exc, Advised) else None
    if hint is None:
        return text
    return text + WORDS[hint.advice].format(*hint.names) + hint.tail
