"""The person at the MCP client, asked whether the robot may do something, in both protocol eras.

Up to 2025-11-25 (handshake sessions) the server sends ``elicitation/create`` in the middle of a call (or,
when the client can open a URL, a link to the call's approval on the operator console). From 2026-07-28
on, a call that must ask ends with an ``InputRequiredResult`` holding the question (:func:`question_round`),
and the client calls again with the person's answer. :class:`Asker` is a tool's
``ToolContext.ask_person``.
"""

from __future__ import annotations

import asyncio
import contextlib
import hashlib
import logging
from collections.abc import Mapping
from typing import Any

from mcp.server import ServerRequestContext
from mcp.server.elicitation import elicit_url, elicit_with_validation, render_elicitation_schema
from mcp.types import ElicitRequest, ElicitRequestFormParams, ElicitResult, InputRequiredResult
from pydantic import BaseModel, Field, ValidationError

from rosbridge_mcp_server.robot.approval import Answer, AnswerNotInForm, AskPerson

__all__ = ["AskInNextRound", "Asker", "question_round"]

_log = logging.getLogger("rosbridge_mcp_server.server")


class _Confirmation(BaseModel):
    approve: bool = Field(description="Let the robot do this")


#: From this protocol version on a server cannot send a request in the middle of a call: it answers with
#: ``InputRequiredResult`` and the client calls again with the person's answers (``input_responses``).
_INPUT_ROUNDS_FROM = "2026-07-28"


class AskInNextRound(BaseException):
    """The person must be asked before this call can go on: answer with an ``InputRequiredResult``.

    A ``BaseException`` so that no ``except Exception`` on the way (the guard treats a failed question as a
    "no") turns "not asked yet" into a refusal; nothing has been sent when it is raised, because the guard
    asks before anything is sent.
    """

    def __init__(self, key: str, question: str) -> None:
        super().__init__(key)
        self.key = key
        self.question = question


class Asker(AskPerson):
    """The person at the MCP client, asked through elicitation (``unsupported`` when the client cannot).

    Handshake sessions (up to 2025-11-25) get an ``elicitation/create`` request in the middle of the call.
    In 2026-07-28 sessions the call ends with an ``InputRequiredResult`` holding the question; the client asks
    the person and calls again, the tool runs again up to the same question, and the answer is found by a key
    made from the question's text, so a "yes" only ever approves exactly what it was shown.

    ``by_link`` is set when the client can open a URL for the person (URL-mode elicitation, handshake
    sessions): the guard then sends the person to this call's approval on the operator console, when one runs.
    """

    def __init__(
        self, request: ServerRequestContext[Any, Any], input_responses: Mapping[str, Any] | None
    ) -> None:
        self._request = request
        self._input_responses = input_responses
        capabilities = request.session.client_capabilities
        version = request.protocol_version
        can_link = (
            capabilities is not None
            and capabilities.elicitation is not None
            and capabilities.elicitation.url is not None
            and (version is None or version < _INPUT_ROUNDS_FROM)
        )
        self.by_link = self._send_to_link if can_link else None

    async def __call__(self, question: str) -> Answer:
        request = self._request
        capabilities = request.session.client_capabilities
        if capabilities is None or capabilities.elicitation is None:
            return "unsupported"
        version = request.protocol_version
        if version is not None and version >= _INPUT_ROUNDS_FROM:
            key = "confirm-" + hashlib.sha256(question.encode()).hexdigest()[:24]
            response = (self._input_responses or {}).get(key)
            if not isinstance(response, ElicitResult):
                raise AskInNextRound(key, question)
            if response.action != "accept":
                return response.action
            return "accept" if _confirmed(response.content) else "decline"
        if capabilities.elicitation.form is None and capabilities.elicitation.url is not None:
            return "unsupported"  # a URL-only client answers by link, or not at all
        try:
            result = await elicit_with_validation(
                request.session, question, _Confirmation, related_request_id=request.request_id
            )
        except ValueError as exc:
            # The SDK's words for an accepted answer without content, or (caused by a ValidationError) with
            # content off the form.
            cause = exc.__cause__
            raise AnswerNotInForm(
                _form_problems(cause) if isinstance(cause, ValidationError) else "it accepted with no answer"
            ) from None
        except Exception:
            _log.info("asking the person failed", exc_info=True)
            return "unsupported"
        if result.action == "accept":
            return "accept" if result.data.approve else "decline"
        return result.action

    async def _send_to_link(self, question: str, url: str, elicitation_id: str) -> Answer:
        request = self._request
        message = f"Approve or deny this on the robot's operator console:\n{question}"
        try:
            result = await elicit_url(
                request.session, message, url, elicitation_id, related_request_id=request.request_id
            )
        except asyncio.CancelledError:
            # Answered on the console (or the call ended) while the client still shows the link: tell it the
            # out-of-band part is over, so it can close its prompt.
            with contextlib.suppress(Exception):
                await request.session.send_elicit_complete(elicitation_id)
            raise
        except Exception:
            _log.info("sending the person to the console failed", exc_info=True)
            return "unsupported"
        return result.action


def _confirmed(content: Mapping[str, Any] | None) -> bool:
    """Whether an accepted answer of a 2026 input round ticks ``approve``; :class:`AnswerNotInForm` when it
    does not fit the form."""
    if content is None:
        raise AnswerNotInForm("it accepted with no answer")
    try:
        return _Confirmation.model_validate(content).approve
    except ValidationError as exc:
        raise AnswerNotInForm(_form_problems(exc)) from None


def _form_problems(exc: ValidationError) -> str:
    """What was wrong with an answer, by field and pydantic's words, without the client's values."""
    problems = [f"{'.'.join(map(str, e['loc'])) or 'answer'}: {e['msg']}" for e in exc.errors()[:3]]
    return "; ".join(problems)[:200]


def question_round(asking: AskInNextRound) -> InputRequiredResult:
    request = ElicitRequest(
        params=ElicitRequestFormParams(
            message=asking.question, requested_schema=render_elicitation_schema(_Confirmation)
        )
    )
    return InputRequiredResult(input_requests={asking.key: request})
