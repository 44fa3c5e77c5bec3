"""How much memory one picture may take while it is decoded: camera frames, maps, scans and clouds.

Anyone on the robot's ROS graph can publish what the watch tools read, and a message's declared size need not
match its bytes: a 320 kB PNG that declares 13000 × 13000 pixels at 16 bits decodes to gigabytes. So every
decoder (``occupancy.py``; ``pictures/``'s ``images.py`` and ``scans.py``) first works out, from the sizes the
message *declares* (a compressed image's header, a raw image's width × height, a map's width × height, a
scan's beams, a cloud's width × height × point_step), what decoding it would hold in memory at once, and
refuses before decoding or allocating anything when that is over :data:`DECODE_BUDGET`. The refusal names the
declared size, the memory it would take and the budget. Pure: no I/O.

The budget fits every real sensor with room to spare: an 8K colour frame (33 M pixels, ~133 MB as Pillow holds
it), a 1280 × 720 depth image (~48 MB), a 7,000² map (~245 MB), a 100,000-beam scan (~22 MB).
"""

from __future__ import annotations

__all__ = ["DECODE_BUDGET", "budget_problem", "byte_size"]

#: Bytes one decode may hold at once (per call; the pixels, cells or points and the copies made on the way).
DECODE_BUDGET = 256 * 1024 * 1024


def budget_problem(what: str, declared: str, needed: int) -> str | None:
    """The sentence refusing to decode *what* (e.g. "The image") that declares *declared* (e.g.
    "13000x13000 pixels, 16-bit grey") and would take *needed* bytes, or ``None`` within the budget."""
    if needed <= DECODE_BUDGET:
        return None
    return (
        f"{what} declares {declared}: decoding it would take about {byte_size(needed)}, over this server's "
        f"budget of {byte_size(DECODE_BUDGET)} for one picture, so it was not decoded. A real sensor sends "
        "far less; check what publishes it."
    )


def byte_size(count: int) -> str:
    """``256 MiB``, ``8.7 GiB``: a byte count for a person."""
    size = float(count)
    for unit in ("bytes", "KiB", "MiB", "GiB", "TiB"):
        if size < 1024 or unit == "TiB":
            if unit == "bytes":
                return f"{count} bytes"
            return f"{size:.3g} {unit}"
        size /= 1024
    raise AssertionError("unreachable")
