"""A minimal PNG encoder (8-bit RGB, no filtering) for the simulated camera's compressed topic, and the
decompression bomb the tests and the benchmark publish at the server: a small file, a huge picture."""

from __future__ import annotations

import struct
import zlib

__all__ = ["encode_png", "png_bomb"]

_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _chunk(kind: bytes, data: bytes) -> bytes:
    return (
        struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    )


def encode_png(width: int, height: int, rgb: bytes) -> bytes:
    """Encode ``width`` × ``height`` RGB pixels (row-major, 3 bytes each) as a PNG file."""
    stride = width * 3
    if len(rgb) != stride * height:
        raise ValueError(f"expected {stride * height} bytes of RGB data, got {len(rgb)}")
    # Filter type 0 (None) in front of every row.
    raw = b"".join(b"\x00" + rgb[row * stride : (row + 1) * stride] for row in range(height))
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (
        _SIGNATURE + _chunk(b"IHDR", header) + _chunk(b"IDAT", zlib.compress(raw, 6)) + _chunk(b"IEND", b"")
    )


def png_bomb(width: int = 13000, height: int = 13000) -> bytes:
    """A 16-bit grey PNG of ``width`` × ``height`` black pixels: 13000² is ~330 kB that decodes to 338 MB
    (and ~2 GB more in a naive depth conversion). Compressed one row at a time, so making it stays small."""
    row = bytes(1 + width * 2)  # filter byte 0 and black pixels
    packer = zlib.compressobj(9)
    parts = [packer.compress(row) for _ in range(height)]
    parts.append(packer.flush())
    header = struct.pack(">IIBBBBB", width, height, 16, 0, 0, 0, 0)
    return _SIGNATURE + _chunk(b"IHDR", header) + _chunk(b"IDAT", b"".join(parts)) + _chunk(b"IEND", b"")
