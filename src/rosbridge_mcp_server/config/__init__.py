"""Configuration: every setting of the server, read once at start from flags, the environment and files.

* :mod:`.robot`: the robot's connection, safety and tools (:class:`Config`);
* :mod:`.http`: the MCP transport (stdio, or Streamable HTTP with its address, tokens and TLS);
* :mod:`.fleet`: several robots (``--robot``, ``--robots``);
* :mod:`.console`: the operator console's address and TLS.
"""

from __future__ import annotations

from rosbridge_mcp_server.config.robot import (
    DEFAULT_HOST,
    DEFAULT_PORT,
    DEFAULT_REQUEST_TIMEOUT,
    LOG_LEVELS,
    MAX_TIMEOUT,
    Config,
    ConfigError,
    LogLevel,
    load_config,
    parse_host,
    parse_port,
    parse_timeout,
    parse_url,
    plain_text_warning,
)

__all__ = [
    "DEFAULT_HOST",
    "DEFAULT_PORT",
    "DEFAULT_REQUEST_TIMEOUT",
    "LOG_LEVELS",
    "MAX_TIMEOUT",
    "Config",
    "ConfigError",
    "LogLevel",
    "load_config",
    "parse_host",
    "parse_port",
    "parse_timeout",
    "parse_url",
    "plain_text_warning",
]
