"""Where a setting's value comes from, and the one rule that chooses it.

A setting can be given on the command line (a flag), in the environment (for hosts such as Claude Desktop
that start the server with an ``env`` block), in a file (the policy file, a robot's table of the fleet
file), or not at all. The rule, for every setting:

    **command-line flag > environment variable > file > default**

* a flag is given unless absent (``None``), off (``False``) or an empty repetition (``[]``): an empty string
  on the command line is given, and refused by name where it is not a value;
* an environment variable is given unless unset or blank (only spaces): ``ROSBRIDGE_PORT=`` in a host's
  configuration is the same as no ``ROSBRIDGE_PORT``;
* a file key is given unless the file leaves it out.

Every value keeps its source (``--port``, ``ROSBRIDGE_PORT``, ``--robots fleet.toml [robots.base] url``), so a
bad one is refused naming the setting and where it came from. Two kinds of setting follow the same rule with
one twist, said where they are read:

* an on-only switch (``--read-only``, ``--behind-tls-proxy``): no flag can turn it off, so an environment
  value meaning off (``0``, ``false``) is the same as no value, and the file below still counts. A safety
  switch therefore only ever tightens: ``ROSBRIDGE_MCP_READ_ONLY=0`` cannot make a read-only policy file
  writable;
* a fleet robot's own table: a flag or environment variable names every robot's value (``--ca-file``), the
  robot's table in the fleet file names that robot's; so for one robot of a fleet, its table in ``--robots``
  (its file) > the value every robot shares (its default, itself chosen by this rule). No flag names one
  robot's setting but ``--robot NAME=URL``, and naming one robot both ways is refused.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

__all__ = ["ENV", "FILE", "FLAG", "ConfigError", "Given", "Setting", "Sources", "parse_switch"]

#: The rank of each source: a lower rank wins.
FLAG, ENV, FILE = 0, 1, 2
_ON = ("1", "true", "yes", "on")
_OFF = ("0", "false", "no", "off")


class ConfigError(ValueError):
    """A configuration value is invalid; ``str()`` is one line saying which, where from, and how to fix it."""


@dataclass(frozen=True)
class Setting:
    """One setting's names: its flag, its environment variable, its key in a file (``None``: it has none)."""

    flag: str
    env: str | None = None
    key: str | None = None


@dataclass(frozen=True)
class Given:
    """A value and where it came from (``source`` is the flag, the variable, or the file and its key)."""

    value: Any
    source: str
    rank: int


class Sources:
    """The flags given, the environment, and optionally one file's keys: :meth:`pick` applies the rule."""

    def __init__(
        self,
        flags: Mapping[str, Any] | None = None,
        environ: Mapping[str, str] | None = None,
        file: Mapping[str, Any] | None = None,
        *,
        file_source: str = "",
    ) -> None:
        self._flags = dict(flags or {})
        self._environ = environ if environ is not None else {}
        self._file = dict(file or {})
        self._file_source = file_source

    def with_file(self, file: Mapping[str, Any], file_source: str) -> Sources:
        """The same flags and environment over *file* (``file_source`` names it in errors)."""
        return Sources(self._flags, self._environ, file, file_source=file_source)

    def pick(self, setting: Setting) -> Given | None:
        """The value of the highest source that gives *setting*; ``None`` when none does (the default)."""
        flag = self._flags.get(setting.flag)
        if flag is not None and flag is not False and flag != []:
            return Given(flag, setting.flag, FLAG)
        if setting.env is not None:
            text = self._environ.get(setting.env, "")
            if text.strip():
                return Given(text.strip(), setting.env, ENV)
        if setting.key is not None and self._file.get(setting.key) is not None:
            where = f"{self._file_source} {setting.key}".strip()
            return Given(self._file[setting.key], where, FILE)
        return None

    def text(self, setting: Setting) -> tuple[str | None, str]:
        """The value as text (``None``: not given) and its source (the variable's name when not given)."""
        given = self.pick(setting)
        if given is None:
            return None, setting.env or setting.flag
        return str(given.value), given.source

    def switch(self, setting: Setting) -> Given | None:
        """An on-only switch: the source that turns it on, or ``None``. An environment value meaning off
        counts as not given, so a file below it still counts; anything else there is refused by name."""
        flag = self._flags.get(setting.flag)
        if flag:
            return Given(True, setting.flag, FLAG)
        if setting.env is not None and parse_switch(self._environ.get(setting.env, ""), source=setting.env):
            return Given(True, setting.env, ENV)
        if setting.key is not None and self._file.get(setting.key) is True:
            return Given(True, f"{self._file_source} {setting.key}".strip(), FILE)
        return None


def parse_switch(value: str, *, source: str) -> bool:
    """A yes-or-no environment value: ``1, true, yes, on`` / ``0, false, no, off`` / blank (no)."""
    text = value.strip().lower()
    if text in _ON:
        return True
    if text in _OFF or not text:
        return False
    raise ConfigError(f"{source} must be 1 or 0 (true or false), not {text!r}")
