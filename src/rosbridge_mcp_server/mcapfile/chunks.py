"""A chunk's records decompressed as a stream, a block at a time, never more than the chunk declares."""

from __future__ import annotations

import io
from collections.abc import Iterator

from rosbridge_mcp_server.mcapfile.model import RecordingProblem

__all__ = ["BLOCK", "decompressed"]

#: Bytes read or decompressed at a time.
BLOCK = 1024 * 1024
#: The largest zstd window a chunk may ask for (a recorder's chunks need a few MiB).
MAX_WINDOW = 32 * 1024 * 1024


def decompressed(data: bytes, compression: str, size: int, what: str) -> Iterator[bytes]:
    """The chunk's records, a block at a time, never more than ``size`` (what the chunk declares)."""
    produced = 0
    if compression == "":
        blocks: Iterator[bytes] = iter([data[i : i + BLOCK] for i in range(0, len(data), BLOCK)])
    elif compression == "zstd":
        blocks = _zstd_blocks(data, what)
    elif compression == "lz4":
        blocks = _lz4_blocks(data, what)
    else:
        raise RecordingProblem(
            f"{what} is compressed with {compression[:20]!r}, which this reader cannot read"
        )
    for block in blocks:
        produced += len(block)
        if produced > size:
            raise RecordingProblem(f"{what} decompresses to more than the {size} bytes it declares")
        yield block


def _zstd_blocks(data: bytes, what: str) -> Iterator[bytes]:
    import zstandard  # noqa: PLC0415

    # The frame's window is memory the decompressor takes at once: a frame may declare up to 2 GiB of it.
    decompressor = zstandard.ZstdDecompressor(max_window_size=MAX_WINDOW)
    reader = decompressor.stream_reader(io.BytesIO(data), read_across_frames=True)
    while True:
        try:
            block = reader.read(BLOCK)
        except zstandard.ZstdError as exc:
            raise RecordingProblem(f"{what} is not valid zstd data ({exc})") from None
        if not block:
            return
        yield block


def _lz4_blocks(data: bytes, what: str) -> Iterator[bytes]:
    import lz4.frame  # type: ignore[import-untyped]  # noqa: PLC0415

    decompressor = lz4.frame.LZ4FrameDecompressor()
    pending = data
    while True:
        try:
            block = decompressor.decompress(pending, max_length=BLOCK)
        except RuntimeError as exc:
            raise RecordingProblem(f"{what} is not valid lz4 data ({exc})") from None
        pending = b""
        if block:
            yield block
        if decompressor.eof or (not block and decompressor.needs_input):
            return
