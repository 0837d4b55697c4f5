"""8-bit RGB PNG encoding with numpy and zlib (the render preview).

Pillow takes longer to import and set up its plugins (tens of ms) than the preview takes to encode, on every
`clrender render`. The format (PNG specification, ISO/IEC 15948): signature, IHDR (size, 8 bits, colour type 2:
RGB), IDAT (the zlib stream of all rows, each led by its filter type byte), IEND; every chunk is length, type,
data, CRC-32 of type and data. Every row uses filter 3, "Average" (each byte minus the mean of its left and upper
neighbours), which suits smooth renders and needs no per-row choice.
"""
from __future__ import annotations

import struct
import zlib

import numpy as np

SIGNATURE = b"\x89PNG\r\n\x1a\n"
AVERAGE = 3


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def encode_png(rgb: np.ndarray, level: int = 6) -> bytes:
    """The PNG file of an (H, W, 3) uint8 image."""
    rgb = np.asarray(rgb)
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.dtype != np.uint8 or 0 in rgb.shape[:2]:
        raise ValueError(f"expected a non-empty (H, W, 3) uint8 image, got {rgb.dtype} {rgb.shape}")
    h, w, _ = rgb.shape
    x = rgb.reshape(h, 3 * w).astype(np.int16)
    left = np.zeros_like(x)
    left[:, 3:] = x[:, :-3]
    up = np.zeros_like(x)
    up[1:] = x[:-1]
    rows = np.empty((h, 1 + 3 * w), np.uint8)
    rows[:, 0] = AVERAGE
    rows[:, 1:] = (x - (left + up) // 2) & 0xFF
    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)  # 8 bits, RGB, deflate, adaptive filters, no interlace
    return (SIGNATURE + _chunk(b"IHDR", header) + _chunk(b"IDAT", zlib.compress(rows.tobytes(), level))
            + _chunk(b"IEND", b""))
