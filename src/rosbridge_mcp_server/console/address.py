"""Where the console's one-time URL is kept besides stderr: a file only this user can read.

Under an MCP host (Claude Desktop and others) the server's stderr is a log file the person may not find, so
each running console also writes its URL to ``console-<pid>.url`` in a directory of this user's (mode 0700,
the file 0600), with a second line saying which robot it serves, and ``rosbridge-mcp-server console-url``
prints the URLs of the consoles running now (each with its robot when there are several). The
directory is chosen by the configuration (:func:`rosbridge_mcp_server.config.console.console_runtime_dir`:
``ROSBRIDGE_MCP_RUNTIME_DIR``, else the platform's runtime or cache folder) and given here. The file goes away
when the server stops.
"""

from __future__ import annotations

import contextlib
import os
import stat
from collections.abc import Iterator
from pathlib import Path

__all__ = ["ConsoleAddressFile", "console_urls"]


class ConsoleAddressFile:
    """``console-<pid>.url`` in ``directory``, readable by this user only; :meth:`remove` when done."""

    def __init__(self, directory: Path, pid: int | None = None) -> None:
        self.path = directory / f"console-{os.getpid() if pid is None else pid}.url"

    def write(self, url: str, serves: str = "") -> None:
        """Write ``url`` and what it *serves* (``the robot at ws://...``; OSError when the directory cannot be
        made or is not this user's alone)."""
        directory = self.path.parent
        directory.mkdir(mode=0o700, parents=True, exist_ok=True)
        if os.name == "posix":
            info = directory.stat()
            if info.st_uid != os.getuid():
                raise PermissionError(f"{directory} belongs to another user")
            if info.st_mode & (stat.S_IRWXG | stat.S_IRWXO):
                directory.chmod(0o700)
        with contextlib.suppress(FileNotFoundError):
            self.path.unlink()
        # Created 0600 from the start: the URL carries the console's secret.
        fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(fd, "w", encoding="utf-8") as out:
            out.write(url + "\n" + (serves + "\n" if serves else ""))

    def remove(self) -> None:
        with contextlib.suppress(OSError):
            self.path.unlink()


def console_urls(directory: Path) -> Iterator[tuple[int, str, str]]:
    """(pid, URL, the robots it serves or "") of each console running now; files a stopped server left behind
    are removed."""
    if not directory.is_dir():
        return
    for path in sorted(directory.glob("console-*.url")):
        try:
            pid = int(path.stem.removeprefix("console-"))
        except ValueError:
            continue
        if not _alive(pid):
            with contextlib.suppress(OSError):
                path.unlink()
            continue
        with contextlib.suppress(OSError, UnicodeDecodeError):
            url, _, serves = path.read_text(encoding="utf-8").strip().partition("\n")
            if url:
                yield pid, url, serves.strip()


def _alive(pid: int) -> bool:
    if os.name != "posix":
        return True  # Windows: no cheap check; a stopped server removes its file itself
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True
