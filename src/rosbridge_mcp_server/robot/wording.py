"""Counts and sizes as answers say them: ``1 topic``, ``2 topics``, ``58 KB``. One way everywhere, so no
answer says "1 topics" or shows a 58 KB file as "0.0 MB"."""

from __future__ import annotations

__all__ = ["counted", "full_stop", "size_text"]


def counted(number: int, noun: str, plural: str | None = None) -> str:
    """``1 topic``, ``2 topics``; *plural* for a noun that does not take an s (``status``, ``statuses``)."""
    if number == 1:
        return f"{number} {noun}"
    return f"{number} {plural or noun + 's'}"


def full_stop(text: str) -> str:
    """*text* as a sentence ending in one stop, to join another after it: a text of its own that already
    ends in ``.``, ``?``, ``!`` or ``…`` keeps it (no "transforms.. Nothing was sent.")."""
    text = text.rstrip()
    return text if text.endswith((".", "?", "!", "…")) else text + "."


def size_text(size: int | float) -> str:
    """A size in bytes as ``512 B``, ``58 KB``, ``1.2 MB``, ``3.4 GB`` (decimal units: 1 KB is 1,000 B)."""
    if size < 1_000:
        return f"{size:.0f} B"
    shown = ""
    for unit, scale in (("KB", 1e3), ("MB", 1e6), ("GB", 1e9)):
        value = size / scale
        shown = f"{value:.0f} {unit}" if unit == "KB" or value >= 99.95 else f"{value:.1f} {unit}"
        if float(shown.split()[0]) < 1000:
            break
    return shown
