#!/usr/bin/env python3
"""Writes the three PNGs textured-box.xml reads (standard library only, so
the bytes are the same on every machine): pattern.png, the back wall's
colours; checker.png, the floor's tiles; mask.png, the card's opacity (raw,
0 or 255: holes and a ragged edge, like a leaf card)."""

import math
import os
import struct
import zlib


def write_png(path, width, height, channels, pixel):
    rows = b"".join(
        b"\0" + bytes(c for x in range(width) for c in pixel(x, y)) for y in range(height)
    )
    colour_type = {1: 0, 3: 2}[channels]

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, colour_type, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(rows, 9)))
        f.write(chunk(b"IEND", b""))


def pattern(x, y):
    # Diagonal bands of three colours over a soft vertical gradient.
    band = ((x + y) // 8) % 3
    base = [(200, 60, 40), (40, 150, 200), (230, 200, 70)][band]
    shade = 0.55 + 0.45 * y / 63
    return tuple(min(255, int(c * shade)) for c in base)


def checker(x, y):
    return (210, 205, 195) if (x // 4 + y // 4) % 2 == 0 else (60, 55, 50)


def mask(x, y):
    u, v = (x + 0.5) / 64 * 2 - 1, (y + 0.5) / 64 * 2 - 1
    if u * u + v * v > 0.95:  # a round card: its corners are cut away
        return (0,)
    for cu, cv, r in [(-0.35, -0.3, 0.22), (0.4, 0.1, 0.18), (-0.1, 0.5, 0.15)]:
        if (u - cu) ** 2 + (v - cv) ** 2 < r * r:
            return (0,)
    return (255,)


here = os.path.dirname(os.path.abspath(__file__))
write_png(os.path.join(here, "pattern.png"), 64, 64, 3, pattern)
write_png(os.path.join(here, "checker.png"), 8, 8, 3, checker)
write_png(os.path.join(here, "mask.png"), 64, 64, 1, mask)
