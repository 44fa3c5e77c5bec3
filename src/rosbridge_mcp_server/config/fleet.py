"""Several robots from one server: ``--robot NAME=URL`` (repeatable) and ``--robots FILE`` (TOML).

Without either, the server drives the one robot the connection flags name, exactly as before. With them, each
robot is a :class:`~rosbridge_mcp_server.config.Config` of its own (URL, handshake headers, TLS files, safety
policy); what a robot's entry leaves out comes from the command line (``--robot`` entries take everything but
the URL from it). The fleet file::

    [robots.base]
    url = "ws://10.0.0.5:9090"
    policy = "base-policy.toml"           # relative to this file
    headers = { Authorization = "Bearer …" }

    [robots.arm]
    url = "wss://arm.local:9090"
    ca_file = "ca.pem"
    read_only = true

    [robots.robot2]                       # one of several robots on one bridge
    url = "ws://10.0.0.7:9090"
    namespace = "/robot2"                 # its topics, actions and tf: /robot2/map, /robot2/tf, ...

Robot names are what a model passes as ``robot``: letters, digits, ``_`` and ``-``.
"""

from __future__ import annotations

import re
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from rosbridge_mcp_server.config.robot import Config, parse_url
from rosbridge_mcp_server.config.sources import ConfigError, Setting, Sources
from rosbridge_mcp_server.safety.policy import Policy, PolicyError, load_policy

__all__ = ["NAME_PATTERN", "load_fleet"]

NAME_PATTERN = re.compile(r"^[A-Za-z][A-Za-z0-9_-]{0,31}$")
_NAMESPACE = re.compile(r"^(/[A-Za-z_][A-Za-z0-9_]*)+$")
_KEYS = {"url", "headers", "ca_file", "client_cert", "client_key", "policy", "read_only", "namespace"}
# A robot's settings in its table of the fleet file (its file source).
_URL = Setting("--robot", key="url")
_HEADERS = Setting("--header", key="headers")
_CA_FILE = Setting("--ca-file", key="ca_file")
_CLIENT_CERT = Setting("--client-cert", key="client_cert")
_CLIENT_KEY = Setting("--client-key", key="client_key")
_POLICY = Setting("--policy", key="policy")
_READ_ONLY = Setting("--read-only", key="read_only")


def load_fleet(
    base: Config, *, robots: Sequence[str] | None = None, robots_file: str | None = None
) -> tuple[tuple[str, Config], ...]:
    """``(name, config)`` per robot, in the order given; empty when no robot was named (one-robot mode)."""
    fleet: dict[str, Config] = {}
    if robots_file:
        for name, config in _from_file(base, Path(robots_file)):
            fleet[name] = config
    for entry in robots or ():
        name, equals, url = entry.partition("=")
        name = name.strip()
        if not equals or not url.strip():
            raise ConfigError(f"--robot {entry!r}: give NAME=URL, e.g. base=ws://10.0.0.5:9090")
        _check_name(name, "--robot")
        if name in fleet:
            raise ConfigError(f"--robot: the robot {name!r} is named twice")
        fleet[name] = replace(
            base, url=parse_url(url.strip(), source=f"--robot {name}"), url_source=f"--robot {name}=URL"
        )
    return tuple(fleet.items())


def _check_name(name: str, source: str) -> None:
    if not NAME_PATTERN.match(name):
        raise ConfigError(
            f"{source}: robot name {name!r} must start with a letter and use letters, digits, _ and - "
            "(at most 32)"
        )


def _namespace(text: str, where: str) -> str:
    value = text.strip().rstrip("/")
    if value and not _NAMESPACE.match(value if value.startswith("/") else f"/{value}"):
        raise ConfigError(
            f'{where}: namespace {text!r} is not a ROS namespace: give e.g. "/robot2" ("" for none)'
        )
    return value if not value or value.startswith("/") else f"/{value}"


def _from_file(base: Config, path: Path) -> list[tuple[str, Config]]:
    source = f"--robots {path}"
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ConfigError(f"{source}: cannot read it: {exc.strerror or exc}") from None
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise ConfigError(f"{source}: not valid TOML: {exc}") from None
    unknown = set(data) - {"robots"}
    if unknown:
        raise ConfigError(f"{source}: unknown key {sorted(unknown)[0]!r}; robots go under [robots.NAME]")
    table = data.get("robots")
    if not isinstance(table, dict) or not table:
        raise ConfigError(f"{source}: no robots; add a [robots.NAME] table with a url")
    out = []
    for name, entry in table.items():
        _check_name(name, source)
        where = f"{source} [robots.{name}]"
        if not isinstance(entry, dict):
            raise ConfigError(f"{where}: must be a table with a url")
        robot = _robot(base, entry, where, path.parent)
        out.append((name, replace(robot, url_source=f"[robots.{name}] in {source}")))
    return out


def _robot(base: Config, entry: Mapping[str, Any], where: str, folder: Path) -> Config:
    # The one rule for a robot of the fleet: its table here is its file; no flag or variable names one robot
    # (``--robot NAME=URL`` and a table of the same name are refused as naming it twice), and what its table
    # leaves out is its default: the value every robot shares, chosen from flags and environment in *base*.
    unknown = set(entry) - _KEYS
    if unknown:
        raise ConfigError(f"{where}: unknown key {sorted(unknown)[0]!r}; known: {', '.join(sorted(_KEYS))}")
    own = Sources(file=entry, file_source=where)
    url = own.pick(_URL)
    if url is None or not isinstance(url.value, str):
        raise ConfigError(f"{where}: url (a ws:// or wss:// URL) is required")
    config = replace(base, url=parse_url(url.value, source=url.source))

    def file(setting: Setting) -> str | None:
        chosen = own.pick(setting)
        if chosen is None:
            return getattr(base, str(setting.key)) if setting.key != "policy" else None
        if not isinstance(chosen.value, str) or not chosen.value:
            raise ConfigError(f"{where}: {setting.key} must be a file path")
        resolved = folder / chosen.value
        if not resolved.is_file():
            raise ConfigError(f"{where}: {setting.key} {str(resolved)!r} does not exist")
        return str(resolved)

    policy = _robot_policy(base, entry, own, file(_POLICY), where)
    namespace = entry.get("namespace")
    if namespace is not None:
        if not isinstance(namespace, str):
            raise ConfigError(f'{where}: namespace must be a string, e.g. "/robot2"')
        namespace = _namespace(namespace, where)
    headers = _robot_headers(base, own, where)
    config = replace(
        config,
        policy=policy,
        headers=headers,
        ca_file=file(_CA_FILE),
        client_cert=file(_CLIENT_CERT),
        client_key=file(_CLIENT_KEY),
        namespace=namespace,
    )
    config.ssl_context()
    return config


def _robot_policy(
    base: Config, entry: Mapping[str, Any], own: Sources, path: str | None, where: str
) -> Policy:
    """A robot's policy: its own file's, else every robot's; read-only when anything says so."""
    if path is not None:
        try:
            policy = load_policy(path, source=f"{where} policy")
        except PolicyError as exc:
            raise ConfigError(str(exc)) from None
    else:
        policy = base.policy
    read_only = entry.get("read_only", False)
    if not isinstance(read_only, bool):
        raise ConfigError(f"{where}: read_only must be true or false")
    # An on-only switch: the robot's own read_only, its policy file's, or every robot's (flag, variable or the
    # shared policy file: base.policy) makes it read-only; none can make a read-only one writable.
    if own.switch(_READ_ONLY) or base.policy.read_only:
        policy = policy.with_read_only()
    return policy


def _robot_headers(base: Config, own: Sources, where: str) -> tuple[tuple[str, str], ...]:
    """A robot's handshake headers: its own table's, else every robot's."""
    given = own.pick(_HEADERS)
    if given is None:
        return base.headers
    raw = given.value
    if not isinstance(raw, dict) or not all(isinstance(v, str) for v in raw.values()):
        raise ConfigError(f'{where}: headers must be a table of strings, e.g. {{ Authorization = "…" }}')
    return tuple((str(k), v) for k, v in raw.items())
