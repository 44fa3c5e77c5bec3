"""Logging for every command: to stderr (stdout is JSON-RPC's in ``serve``), secrets replaced by ``***``, each
message on one line and escaped as robot text is."""

from __future__ import annotations

import logging
import sys
from collections.abc import Sequence
from typing import TextIO

from rosbridge_mcp_server.cli.arguments import PROG
from rosbridge_mcp_server.robot.text import shown

__all__ = ["LOG_LINE_CHARS", "configure_logging"]


def configure_logging(level: str, stream: TextIO | None = None, secrets: Sequence[str] = ()) -> None:
    """Log to stderr: our own loggers at ``level``, everyone else's at WARNING (or DEBUG when asked).

    ``secrets`` (e.g. the values of ``--header``) are replaced by ``***`` in every line: at DEBUG, websockets
    logs each handshake header it sends.
    """
    handler = logging.StreamHandler(stream if stream is not None else sys.stderr)
    handler.set_name(PROG)
    handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s"))
    if secrets:
        handler.addFilter(_Redact(secrets))
    handler.addFilter(_OneLine())
    root = logging.getLogger()
    # Replace only our own handler (run() may be called more than once in one process, e.g. in tests). Having
    # a handler on the root also keeps MCPServer's logging.basicConfig from adding its own.
    for old in [h for h in root.handlers if h.get_name() == PROG]:
        root.removeHandler(old)
    root.addHandler(handler)
    root.setLevel(logging.DEBUG if level == "DEBUG" else logging.WARNING)
    logging.getLogger("rosbridge_mcp_server").setLevel(level)


class _Redact(logging.Filter):
    """Replaces each secret by ``***`` in a record's message (and drops its arguments, already merged)."""

    def __init__(self, secrets: Sequence[str]) -> None:
        super().__init__()
        self._secrets = [secret for secret in secrets if secret]

    def filter(self, record: logging.LogRecord) -> bool:
        message = record.getMessage()
        if any(secret in message for secret in self._secrets):
            for secret in self._secrets:
                message = message.replace(secret, "***")
            record.msg, record.args = message, None
        return True


#: The longest message one log line carries (a traceback, written after it, is not cut).
LOG_LINE_CHARS = 10_000


class _OneLine(logging.Filter):
    """Each record's message on one line, escaped as robot text is (``robot/text.py``): a message quotes
    what the robot, a bridge or a caller wrote (a refusal's text, a JWT's subject), and a newline or an ANSI
    sequence in it must not write a line of its own on the operator's terminal."""

    def filter(self, record: logging.LogRecord) -> bool:
        message = record.getMessage()
        safe = shown(message, LOG_LINE_CHARS)
        if safe is not message:
            record.msg, record.args = safe, None
        return True
