"""Configuration from flags and environment: precedence, validation, one-line errors."""

from __future__ import annotations

import pytest

from rosbridge_mcp_server.config import Config, ConfigError, load_config


def test_defaults_point_at_localhost_9090() -> None:
    """With nothing set, the server connects to ws://localhost:9090 with a 10 s request timeout."""
    config = load_config({})
    assert config == Config(url="ws://localhost:9090", request_timeout=10.0, log_level="INFO")


def test_host_and_port_come_from_the_environment() -> None:
    """ROSBRIDGE_HOST and ROSBRIDGE_PORT build the URL, as in the Claude Desktop example."""
    config = load_config({"ROSBRIDGE_HOST": "192.168.1.100", "ROSBRIDGE_PORT": "9091"})
    assert config.url == "ws://192.168.1.100:9091"


def test_environment_url_wins_over_environment_host_and_port() -> None:
    """ROSBRIDGE_URL, path included, wins over ROSBRIDGE_HOST/PORT."""
    env = {"ROSBRIDGE_URL": "wss://robot.example.com:9090/rosbridge", "ROSBRIDGE_HOST": "other"}
    assert load_config(env).url == "wss://robot.example.com:9090/rosbridge"


def test_flags_win_over_the_environment() -> None:
    """--host/--port beat every environment variable, a missing half coming from the environment."""
    env = {"ROSBRIDGE_URL": "ws://envhost:1", "ROSBRIDGE_PORT": "9999"}
    assert load_config(env, host="flaghost").url == "ws://flaghost:9999"
    assert load_config(env, url="ws://flagurl:7").url == "ws://flagurl:7"


def test_ipv6_hosts_are_bracketed_in_the_url() -> None:
    """An IPv6 address becomes a valid WebSocket URL."""
    assert load_config({}, host="::1", port=9090).url == "ws://[::1]:9090"


@pytest.mark.parametrize(
    ("kwargs", "env", "fragment"),
    [
        ({"port": "abc"}, {}, "--port must be a port number between 1 and 65535, not 'abc'"),
        ({"port": "0"}, {}, "--port must be a port number between 1 and 65535, not 0"),
        ({"port": "70000"}, {}, "not 70000"),
        ({}, {"ROSBRIDGE_PORT": "x"}, "ROSBRIDGE_PORT must be a port number"),
        ({"url": "http://x"}, {}, "--url must start with ws:// or wss://"),
        ({}, {"ROSBRIDGE_URL": "ftp://robot"}, "ROSBRIDGE_URL must start with ws:// or wss://"),
        ({"url": "ws://robot:70000"}, {}, "--url is not a valid URL"),
        ({"url": "ws://"}, {}, "--url has no host"),
        ({"host": "ws://robot"}, {}, "use --url / ROSBRIDGE_URL"),
        ({"host": "robot:9090"}, {}, "must not contain a port"),
        ({"timeout": "0"}, {}, "--timeout must be more than 0"),
        ({"timeout": "soon"}, {}, "--timeout must be a number of seconds"),
        ({}, {"ROSBRIDGE_TIMEOUT": "-1"}, "ROSBRIDGE_TIMEOUT must be more than 0"),
        ({"log_level": "LOUD"}, {}, "--log-level must be one of DEBUG, INFO, WARNING, ERROR, CRITICAL"),
        ({}, {"ROSBRIDGE_MCP_LOG_LEVEL": "chatty"}, "ROSBRIDGE_MCP_LOG_LEVEL must be one of"),
    ],
)
def test_bad_values_are_one_line_errors_naming_their_source(
    kwargs: dict[str, str], env: dict[str, str], fragment: str
) -> None:
    """Each bad value raises ConfigError with one line that names the flag or variable."""
    with pytest.raises(ConfigError) as caught:
        load_config(env, **kwargs)
    message = str(caught.value)
    assert fragment in message
    assert "\n" not in message


def test_timeout_and_log_level_are_read_from_flags_then_environment() -> None:
    """--timeout beats ROSBRIDGE_TIMEOUT; log levels are case-insensitive."""
    env = {"ROSBRIDGE_TIMEOUT": "20", "ROSBRIDGE_MCP_LOG_LEVEL": "debug"}
    assert load_config(env).request_timeout == 20.0
    assert load_config(env).log_level == "DEBUG"
    assert load_config(env, timeout="2.5", log_level="warning").request_timeout == 2.5
    assert load_config(env, timeout="2.5", log_level="warning").log_level == "WARNING"


def test_config_is_frozen() -> None:
    """Nothing can change the configuration after main() read it."""
    config = load_config({})
    with pytest.raises(AttributeError):
        config.url = "ws://elsewhere:1"  # type: ignore[misc]
