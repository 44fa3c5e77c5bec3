"""Where recordings live: every path held inside the recording directory (``Config.record_dir``, chosen by
:mod:`rosbridge_mcp_server.config.robot`).

A name given by a model is a path relative to the directory (``run1.mcap``, ``today/run1.mcap``) or an
absolute path that lands inside it. Whatever it is, the path is resolved with every symlink followed and must
still be inside the directory's own resolved path: ``../x``, ``/etc/passwd`` and a symlink pointing out are
all refused. A new recording is created with ``O_EXCL | O_NOFOLLOW``: it never overwrites a file and never
writes through a symlink planted in the directory.
"""

from __future__ import annotations

import os
import re
import time
from dataclasses import dataclass
from pathlib import Path

from rosbridge_mcp_server.errors import Advice, Advised

__all__ = [
    "MCAP_MAGIC",
    "PathRefused",
    "RecordingEntry",
    "create_recording",
    "list_recordings",
    "resolve_recording",
]

#: The first 8 bytes of every MCAP file.
MCAP_MAGIC = b"\x89MCAP0\r\n"
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,99}$")


class PathRefused(Advised, ValueError):
    """A path outside the recording directory, or a name that cannot be a recording; ``str()`` says why."""


def _inside(directory: Path, given: str) -> Path:
    if "\x00" in given:
        raise PathRefused("a file name cannot contain a NUL character")
    candidate = Path(given)
    try:
        root = directory.resolve()
        target = (candidate if candidate.is_absolute() else root / candidate).resolve()
    except (RuntimeError, OSError):  # a link leading to itself (RuntimeError before Python 3.13)
        raise PathRefused(
            f"{candidate.name[:100]!r} is a link that leads to itself (or the folder holding it is); name "
            "another file"
        ).advise(Advice.RECORDINGS) from None
    if target != root and root not in target.parents:
        raise PathRefused(
            f"{given!r} is outside the recording directory {str(root)!r}; name a file inside it"
        ).advise(Advice.RECORDINGS)
    return target


def resolve_recording(directory: Path, given: str) -> Path:
    """An existing file inside ``directory``; :class:`PathRefused` otherwise. A name without its ``.mcap``
    (``drive1``, as ``record`` was given it) finds ``drive1.mcap``."""
    target = _inside(directory, given.strip())
    if not target.is_file() and target.suffix != ".mcap":
        named = _inside(directory, given.strip() + ".mcap")
        target = named if named.is_file() else target
    if not target.is_file():
        raise PathRefused(f"There is no recording {given!r} in {str(directory.resolve())!r}").advise(
            Advice.NO_RECORDING
        )
    return target


def create_recording(directory: Path, name: str | None) -> tuple[Path, int]:
    """A new, empty ``.mcap`` file inside ``directory`` (made if missing) and its open descriptor.

    ``name`` is a bare file name (letters, digits, ``._-``); ``None`` names it after the time.
    """
    directory.mkdir(parents=True, exist_ok=True)
    if name is None:
        name = time.strftime("rec-%Y%m%d-%H%M%S", time.localtime())
    name = name.strip()
    if name.endswith(".mcap"):
        name = name[:-5]
    if not _NAME.match(name):
        raise PathRefused(
            f"Recording name {name!r} must be a bare file name of letters, digits, '.', '_' and '-' (at most "
            '100), e.g. "drive-test"; the file goes in the recording directory.'
        )
    target = _inside(directory, f"{name}.mcap")
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(target, flags, 0o644)
    except FileExistsError:
        raise PathRefused(
            f"A recording named {target.name!r} already exists; choose another name (recordings are never "
            "overwritten)."
        ) from None
    return target, fd


@dataclass(frozen=True)
class RecordingEntry:
    """One file in the recording directory."""

    name: str
    size: int
    modified: float
    is_mcap: bool


def list_recordings(directory: Path, limit: int = 1000) -> list[RecordingEntry]:
    """The ``.mcap`` files in ``directory`` and one level of folders, newest first."""
    try:
        root = directory.resolve()
    except (RuntimeError, OSError):  # the folder is a link leading to itself: it holds nothing to list
        return []
    if not root.is_dir():
        return []
    found: list[RecordingEntry] = []
    for path in [*root.glob("*.mcap"), *root.glob("*/*.mcap")]:
        try:
            resolved = path.resolve()
            if root not in resolved.parents or not resolved.is_file():
                continue
            stat = resolved.stat()
            with resolved.open("rb") as handle:
                magic = handle.read(len(MCAP_MAGIC))
        except (OSError, RuntimeError):  # unreadable, or a link leading to itself
            continue
        found.append(
            RecordingEntry(str(path.relative_to(root)), stat.st_size, stat.st_mtime, magic == MCAP_MAGIC)
        )
        if len(found) >= limit:
            break
    found.sort(key=lambda entry: entry.modified, reverse=True)
    return found
