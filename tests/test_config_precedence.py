"""The one precedence rule, flag > environment variable > file > default, for every kind of source and every
setting that has more than one; and a bad value is refused naming where it came from."""

from __future__ import annotations

import asyncio
import re
import socket
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from rosbridge_mcp_server.cli import run
from rosbridge_mcp_server.config import Config, ConfigError, load_config
from rosbridge_mcp_server.config.console import console_runtime_dir, load_console_settings
from rosbridge_mcp_server.config.fleet import load_fleet
from rosbridge_mcp_server.config.http import load_http_settings
from rosbridge_mcp_server.config.robot import default_record_dir
from rosbridge_mcp_server.config.sources import ENV, FILE, FLAG, Setting, Sources
from rosbridge_mcp_server.sim import SimulatedRobot

THING = Setting("--thing", "THING", key="thing")


@pytest.mark.parametrize(
    ("flag", "env", "file", "expected"),
    [
        ("from-flag", "from-env", "from-file", ("from-flag", "--thing", FLAG)),
        (None, "from-env", "from-file", ("from-env", "THING", ENV)),
        (None, None, "from-file", ("from-file", "robots.toml thing", FILE)),
        (None, None, None, None),
    ],
)
def test_a_flag_beats_the_environment_beats_a_file_beats_the_default(
    flag: str | None, env: str | None, file: str | None, expected: tuple[str, str, int] | None
) -> None:
    sources = Sources(
        {"--thing": flag}, {"THING": env} if env else {}, {"thing": file}, file_source="robots.toml"
    )
    given = sources.pick(THING)
    assert (None if given is None else (given.value, given.source, given.rank)) == expected


def test_a_blank_variable_is_unset_and_an_empty_flag_is_given() -> None:
    """``THING=`` (or spaces) in a host's env block is no value, so the file's counts; an empty string on the
    command line is given (and refused by name where it is no value)."""
    blank = Sources({}, {"THING": "  "}, {"thing": "from-file"}).pick(THING)
    assert blank is not None
    assert (blank.value, blank.rank) == ("from-file", FILE)
    empty = Sources({"--thing": ""}, {"THING": "from-env"}).pick(THING)
    assert empty is not None
    assert (empty.value, empty.source) == ("", "--thing")
    assert Sources({"--thing": False, "--other": "x"}, {}).pick(THING) is None
    assert Sources({"--thing": []}, {}).pick(THING) is None


@pytest.mark.parametrize(
    ("flag", "env", "file", "on"),
    [
        (True, "", False, "--thing"),
        (False, "1", False, "THING"),
        (False, "0", True, "robots.toml thing"),  # off in the environment cannot loosen the file
        (False, "no", False, None),
        (False, "", False, None),
    ],
)
def test_an_on_only_switch_follows_the_rule_and_only_tightens(
    flag: bool, env: str, file: bool, on: str | None
) -> None:
    switch = Sources({"--thing": flag}, {"THING": env}, {"thing": file}, file_source="robots.toml").switch(
        THING
    )
    assert (switch.source if switch is not None else None) == on


# (load_config keyword, environment variable, flag value, environment value, Config attribute, default)
ROBOT_SETTINGS: list[tuple[str, str, Any, str, str, Any]] = [
    ("url", "ROSBRIDGE_URL", "ws://flag:1", "ws://env:2", "url", "ws://localhost:9090"),
    ("host", "ROSBRIDGE_HOST", "flag", "env", "url", "ws://localhost:9090"),
    ("port", "ROSBRIDGE_PORT", "1111", "2222", "url", "ws://localhost:9090"),
    ("timeout", "ROSBRIDGE_TIMEOUT", "3", "4", "request_timeout", 10.0),
    ("log_level", "ROSBRIDGE_MCP_LOG_LEVEL", "DEBUG", "ERROR", "log_level", "INFO"),
    ("tools", "ROSBRIDGE_MCP_TOOLS", "watch", "view", "tools", None),
    ("audit_log", "ROSBRIDGE_MCP_AUDIT_LOG", "flag.jsonl", "env.jsonl", "audit_log", None),
    ("record_dir", "ROSBRIDGE_MCP_RECORD_DIR", "/flag", "/env", "record_dir", default_record_dir({})),
    ("headers", "ROSBRIDGE_HEADERS", ["X-From: flag"], "X-From: env", "headers", ()),
]


@pytest.mark.parametrize("row", ROBOT_SETTINGS, ids=[row[0] for row in ROBOT_SETTINGS])
def test_each_robot_setting_takes_the_flag_then_the_environment_then_the_default(
    row: tuple[str, str, Any, str, str, Any],
) -> None:
    keyword, variable, flag, env, attribute, default = row
    from_flag = getattr(load_config({variable: env}, **{keyword: flag}), attribute)
    from_env = getattr(load_config({variable: env}), attribute)
    assert getattr(load_config({}), attribute) == default
    assert len({repr(from_flag), repr(from_env), repr(default)}) == 3, "each source gives its own value"
    assert getattr(load_config({}, **{keyword: flag}), attribute) == from_flag
    assert getattr(load_config({variable: "  "}), attribute) == default


@pytest.mark.parametrize(
    ("keyword", "variable", "bad"),
    [
        ("url", "ROSBRIDGE_URL", "http://x"),
        ("host", "ROSBRIDGE_HOST", "a b"),
        ("port", "ROSBRIDGE_PORT", "abc"),
        ("timeout", "ROSBRIDGE_TIMEOUT", "-1"),
        ("log_level", "ROSBRIDGE_MCP_LOG_LEVEL", "LOUD"),
        ("tools", "ROSBRIDGE_MCP_TOOLS", "no_such_tool"),
        ("policy", "ROSBRIDGE_MCP_POLICY", "/no/such/policy.toml"),
    ],
)
def test_a_bad_value_is_refused_naming_the_source_it_came_from(keyword: str, variable: str, bad: str) -> None:
    with pytest.raises(ConfigError, match=f"^{keyword.replace('_', '-').join(['--', ''])}"):
        load_config({variable: "fine"}, **{keyword: bad})
    with pytest.raises(ConfigError, match=f"^{variable}"):
        load_config({variable: bad})
    # The flag hides a bad variable: the value a source does not win with is never read.
    good = {"url": "ws://x:1", "host": "x", "port": "1", "timeout": "1", "log_level": "INFO", "tools": "all"}
    if keyword in good:
        load_config({variable: bad}, **{keyword: good[keyword]})


def test_a_url_beats_host_and_port_of_its_own_source_or_a_lower_one() -> None:
    env = {"ROSBRIDGE_URL": "ws://env-url:1", "ROSBRIDGE_HOST": "env-host", "ROSBRIDGE_PORT": "2"}
    assert load_config(env).url == "ws://env-url:1"
    assert load_config(env, url="ws://flag-url:3", host="flag-host").url == "ws://flag-url:3"
    # A host flag beats ROSBRIDGE_URL; its port comes from the environment, then the default.
    assert load_config(env, host="flag-host").url == "ws://flag-host:2"
    assert load_config({"ROSBRIDGE_URL": "ws://env-url:1"}, host="flag-host").url == "ws://flag-host:9090"
    assert load_config({"ROSBRIDGE_HOST": "env-host"}, port="4").url == "ws://env-host:4"


def _policy(folder: Path, name: str, text: str) -> str:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return str(path)


def test_the_policy_file_is_chosen_by_flag_then_environment(tmp_path: Path) -> None:
    flag = _policy(tmp_path, "flag.toml", 'confirm = "always"\n')
    env = _policy(tmp_path, "env.toml", 'confirm = "motion"\n')
    assert load_config({"ROSBRIDGE_MCP_POLICY": env}, policy=flag).policy.confirm == "always"
    assert load_config({"ROSBRIDGE_MCP_POLICY": env}).policy.confirm == "motion"
    assert load_config({}).policy.confirm == "never"


@pytest.mark.parametrize(
    ("flag", "env", "file", "read_only"),
    [
        (True, "0", "read_only = false\n", True),
        (False, "1", "read_only = false\n", True),
        (False, "0", "read_only = true\n", True),  # the environment's "off" cannot loosen the file
        (False, "", "read_only = true\n", True),
        (False, "0", "", False),
        (False, "", None, False),
    ],
)
def test_read_only_comes_from_flag_environment_or_policy_file_and_only_tightens(
    tmp_path: Path, flag: bool, env: str, file: str | None, read_only: bool
) -> None:
    policy = _policy(tmp_path, "policy.toml", file) if file is not None else None
    config = load_config({"ROSBRIDGE_MCP_READ_ONLY": env}, read_only=flag, policy=policy)
    assert config.policy.read_only is read_only


def test_a_fleet_robots_table_beats_the_value_every_robot_shares(tmp_path: Path) -> None:
    """For one robot of a fleet its table is its file, and the value all robots share (flag > environment >
    default) is its default: the table wins where it has the key, the shared value fills in where not."""
    fleet = tmp_path / "fleet.toml"
    fleet.write_text(
        '[robots.own]\nurl = "ws://own:1"\nheaders = { X-From = "table" }\n[robots.shared]\nurl = "ws://shared:2"\n',
        encoding="utf-8",
    )
    env = {"ROSBRIDGE_HEADERS": "X-From: env"}
    for base, shared in (
        (load_config(env, headers=["X-From: flag"]), "flag"),
        (load_config(env), "env"),
        (Config(), None),
    ):
        robots = dict(load_fleet(base, robots_file=str(fleet)))
        assert robots["own"].headers == (("X-From", "table"),)
        assert robots["shared"].headers == ((("X-From", shared),) if shared else ())


def test_each_http_setting_takes_the_flag_then_the_environment_then_the_default() -> None:
    env = {
        "ROSBRIDGE_MCP_TRANSPORT": "http",
        "ROSBRIDGE_MCP_BIND": "127.0.0.1:2222",
        "ROSBRIDGE_MCP_ALLOWED_HOSTS": "env.example",
        "ROSBRIDGE_MCP_ALLOWED_ORIGINS": "https://env.example",
    }
    flags = load_http_settings(
        env,
        transport="http",
        bind="127.0.0.1:1111",
        allow_hosts=["flag.example"],
        allow_origins=["https://flag.example"],
    )
    assert (flags.port, "flag.example:*" in flags.allowed_hosts) == (1111, True)
    assert "env.example:*" not in flags.allowed_hosts
    assert "https://flag.example" in flags.allowed_origins
    assert "https://env.example" not in flags.allowed_origins
    environment = load_http_settings(env)
    assert (environment.transport, environment.port) == ("http", 2222)
    assert "env.example:*" in environment.allowed_hosts
    assert "https://env.example" in environment.allowed_origins
    assert load_http_settings(env, transport="stdio").transport == "stdio"
    assert load_http_settings({}).transport == "stdio"
    assert load_http_settings({}, transport="http").port == 8765
    with pytest.raises(ConfigError, match=r"^ROSBRIDGE_MCP_BIND: 'nowhere'"):
        load_http_settings({**env, "ROSBRIDGE_MCP_BIND": "nowhere"})
    with pytest.raises(ConfigError, match=r"^--bind: 'nowhere'"):
        load_http_settings(env, bind="nowhere")


def test_the_console_address_takes_the_flag_then_the_environment() -> None:
    env = {"ROSBRIDGE_MCP_CONSOLE": "2222"}
    flag = load_console_settings(env, address="1111")
    assert flag is not None
    assert flag.port == 1111
    from_env = load_console_settings(env)
    assert from_env is not None
    assert from_env.port == 2222
    assert load_console_settings({"ROSBRIDGE_MCP_CONSOLE": " "}) is None
    with pytest.raises(ConfigError, match=r"^ROSBRIDGE_MCP_CONSOLE"):
        load_console_settings({"ROSBRIDGE_MCP_CONSOLE": "x:y"})


def _dead_url() -> str:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return f"ws://127.0.0.1:{probe.getsockname()[1]}"


async def test_the_command_line_connects_where_the_winning_source_says(
    sim_ros2: SimulatedRobot, capsys: pytest.CaptureFixture[str]
) -> None:
    """`check` through the real command line: it reaches the robot only when the source naming it wins."""
    dead = _dead_url()
    cases = [
        (["--url", sim_ros2.url], {"ROSBRIDGE_URL": dead}, 0),
        (["--url", dead], {"ROSBRIDGE_URL": sim_ros2.url}, 1),
        ([], {"ROSBRIDGE_URL": sim_ros2.url}, 0),
        (["--port", str(sim_ros2.port)], {"ROSBRIDGE_HOST": "127.0.0.1", "ROSBRIDGE_URL": dead}, 0),
    ]
    for argv, env, code in cases:
        assert await asyncio.to_thread(run, ["check", "--timeout", "5", *argv], env) == code, (argv, env)
        out = capsys.readouterr().out
        assert ("Healthy" in out) is (code == 0)


@pytest.mark.parametrize(
    "module",
    [
        "rosbridge_mcp_server.config",
        "rosbridge_mcp_server.config.console",
        "rosbridge_mcp_server.config.fleet",
        "rosbridge_mcp_server.config.http",
        "rosbridge_mcp_server.console",
        "rosbridge_mcp_server.cli.demo",
    ],
)
def test_each_settings_module_imports_first_in_a_fresh_interpreter(module: str) -> None:
    """No import cycle between the config package, the console that reads its settings, and the CLI."""
    done = subprocess.run(
        [sys.executable, "-c", f"import {module}"], capture_output=True, text=True, timeout=60, check=False
    )
    assert done.returncode == 0, done.stderr


def test_the_robots_config_holds_no_demo_setting() -> None:
    """The demo's settings are the command line's (cli/demo.py), not a robot's."""
    assert not [name for name in Config.__dataclass_fields__ if name.startswith("demo")]


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: load_config({"ROSBRIDGE_MCP_POLICY": "p.toml"}, policy=""), "--policy is empty"),
        (lambda: load_config({}, audit_log=" "), "--audit-log is empty"),
        (
            lambda: load_http_settings({"ROSBRIDGE_MCP_BIND": "127.0.0.1:9"}, transport="http", bind=""),
            "--bind: ''",
        ),
        (lambda: load_http_settings({}, transport="http", tls_cert=""), "--tls-cert is empty"),
    ],
)
def test_an_empty_flag_is_refused_by_name_not_taken_for_absent(call: Any, message: str) -> None:
    """`--policy "$POLICY"` with the variable unset must not quietly mean "no policy" (nor the variable's)."""
    with pytest.raises(ConfigError, match=f"^{re.escape(message)}"):
        call()


def test_the_recording_folder_is_chosen_with_the_configuration(monkeypatch: pytest.MonkeyPatch) -> None:
    """``--record-dir`` > ``ROSBRIDGE_MCP_RECORD_DIR`` > ``$XDG_DATA_HOME/...`` > ``~/.local/share/...``, read
    from the environment given to ``load_config`` (not from the process's at the time of a tool call)."""
    monkeypatch.setenv("HOME", "/home/someone")
    share = Path("/home/someone/.local/share/rosbridge-mcp-server/recordings")
    data = {"XDG_DATA_HOME": "/data"}
    assert load_config({}).record_dir == share
    assert load_config(data).record_dir == Path("/data/rosbridge-mcp-server/recordings")
    assert load_config({"XDG_DATA_HOME": "relative/data"}).record_dir == share  # the spec: absolute only
    assert load_config({"XDG_DATA_HOME": "  "}).record_dir == share
    assert load_config({**data, "ROSBRIDGE_MCP_RECORD_DIR": "/env"}).record_dir == Path("/env")
    assert load_config(data, record_dir="~/rec").record_dir == Path("/home/someone/rec")
    monkeypatch.setenv("XDG_DATA_HOME", "/process")
    assert load_config({}).record_dir == share
    assert Config().record_dir == Path("/process/rosbridge-mcp-server/recordings")  # built directly


def test_the_console_runtime_folder_is_chosen_with_the_configuration(monkeypatch: pytest.MonkeyPatch) -> None:
    """``ROSBRIDGE_MCP_RUNTIME_DIR`` > ``$XDG_RUNTIME_DIR/...`` > the platform's cache folder."""
    monkeypatch.setenv("HOME", "/home/someone")
    monkeypatch.setattr(sys, "platform", "linux")
    runtime = {"XDG_RUNTIME_DIR": "/run/user/1000"}
    assert console_runtime_dir({}) == Path("/home/someone/.cache/rosbridge-mcp-server")
    assert console_runtime_dir(runtime) == Path("/run/user/1000/rosbridge-mcp-server")
    assert console_runtime_dir({**runtime, "ROSBRIDGE_MCP_RUNTIME_DIR": "/mine"}) == Path("/mine")
    assert console_runtime_dir({**runtime, "ROSBRIDGE_MCP_RUNTIME_DIR": " "}) == Path(
        "/run/user/1000/rosbridge-mcp-server"
    )
    monkeypatch.setattr(sys, "platform", "darwin")
    assert console_runtime_dir({}) == Path("/home/someone/Library/Caches/rosbridge-mcp-server")
    monkeypatch.setattr(sys, "platform", "win32")
    assert console_runtime_dir({"LOCALAPPDATA": "/appdata"}) == Path("/appdata/rosbridge-mcp-server")
