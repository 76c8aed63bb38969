#!/usr/bin/env python3
"""Hostile inputs for scripts/hostile.sh, made with the standard library alone.

Each subcommand writes one file (or folder); see `usage` below. PNGs are streamed through zlib,
so a 32768x32768 image of zeros costs a megabyte of output and little memory. The JPEG writer is
the smallest baseline encoder that decoders accept: greyscale, every 8x8 block one flat value
(DC coefficients only, an all-ones quantisation table, the standard DC Huffman table and an
AC table holding only end-of-block).
"""

import base64
import json
import math
import random
import struct
import sys
import zlib


def chunk(kind, data):
    body = kind + data
    return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


def png(path, width, height, colour_type, bit_depth, row):
    """Writes a PNG whose every row (filter byte 0 prepended) is `row(y)`."""
    deflate = zlib.compressobj(9)
    parts = []
    for y in range(height):
        parts.append(deflate.compress(b"\0" + row(y)))
    parts.append(deflate.flush())
    header = struct.pack(">IIBBBBB", width, height, bit_depth, colour_type, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header))
        f.write(chunk(b"IDAT", b"".join(parts)))
        f.write(chunk(b"IEND", b""))


def gray(path, width, height, value, bits):
    size = 1 if bits == 8 else 2
    line = (bytes([value]) if bits == 8 else struct.pack(">H", value)) * width
    assert len(line) == width * size
    png(path, width, height, 0, bits, lambda y: line)


def rgb16_random(path, width, height, seed):
    rng = random.Random(seed)
    png(path, width, height, 2, 16, lambda y: bytes(rng.getrandbits(8) for _ in range(6 * width)))


def rgb16_const(path, width, height, r, g, b):
    line = struct.pack(">HHH", r, g, b) * width
    png(path, width, height, 2, 16, lambda y: line)


# Standard luminance DC table (JPEG Annex K): code lengths, then the categories 0..11.
DC_BITS = [0, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0]
DC_VALUES = list(range(12))


def huffman_codes(bits, values):
    codes, code, k = {}, 0, 0
    for length in range(1, 17):
        for _ in range(bits[length - 1]):
            codes[values[k]] = (code, length)
            code += 1
            k += 1
        code <<= 1
    return codes


class BitWriter:
    def __init__(self):
        self.out, self.acc, self.n = bytearray(), 0, 0

    def put(self, value, length):
        for i in range(length - 1, -1, -1):
            self.acc = (self.acc << 1) | ((value >> i) & 1)
            self.n += 1
            if self.n == 8:
                self.out.append(self.acc)
                if self.acc == 0xFF:
                    self.out.append(0)
                self.acc, self.n = 0, 0

    def flush(self):
        while self.n:
            self.put(1, 1)
        return bytes(self.out)


def jpeg(path, width, height, seed):
    """A greyscale baseline JPEG of flat 8x8 blocks (width and height rounded up to 8)."""
    rng = random.Random(seed)
    dc_codes = huffman_codes(DC_BITS, DC_VALUES)
    bits, previous = BitWriter(), 0
    for _ in range(((height + 7) // 8) * ((width + 7) // 8)):
        level = rng.randint(60, 200)
        dc = 8 * (level - 128)  # the DC coefficient of a flat block with an all-ones table
        diff, previous = dc - previous, dc
        category = abs(diff).bit_length()
        code, length = dc_codes[category]
        bits.put(code, length)
        if category:
            bits.put(diff if diff > 0 else diff + (1 << category) - 1, category)
        bits.put(0, 1)  # end of block: the only AC symbol, code `0`
    def segment(marker, data):
        return b"\xff" + bytes([marker]) + struct.pack(">H", len(data) + 2) + data
    out = b"\xff\xd8"
    out += segment(0xE0, b"JFIF\0\x01\x01\0\0\x01\0\x01\0\0")
    out += segment(0xDB, b"\0" + b"\x01" * 64)
    out += segment(0xC0, struct.pack(">BHHB", 8, height, width, 1) + b"\x01\x11\x00")
    out += segment(0xC4, b"\x00" + bytes(DC_BITS) + bytes(DC_VALUES))
    out += segment(0xC4, b"\x10" + bytes([1] + [0] * 15) + b"\x00")
    out += segment(0xDA, b"\x01\x01\x00\x00\x3f\x00")
    out += bits.flush() + b"\xff\xd9"
    with open(path, "wb") as f:
        f.write(out)


def gltf(path, variant):
    """A one-triangle glTF with an embedded buffer; `overrun`: the POSITION accessor claims a
    million vertices; `offset`: the indices' bufferView starts past the buffer's end."""
    data = b"".join(struct.pack("<3f", *p) for p in [(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    data += b"".join(struct.pack("<2f", *t) for t in [(0, 1), (1, 1), (0, 0)])
    data += struct.pack("<3H", 0, 1, 2) + b"\0\0"
    count = 1000000 if variant == "overrun" else 3
    index_offset = 4096 if variant == "offset" else 60
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2}]}],
        "buffers": [{"uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode(),
                     "byteLength": len(data)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 24},
            {"buffer": 0, "byteOffset": index_offset, "byteLength": 6},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": count, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"},
        ],
    }
    with open(path, "w") as f:
        json.dump(doc, f)


def random_bytes(path, n, seed):
    rng = random.Random(seed)
    with open(path, "wb") as f:
        f.write(bytes(rng.getrandbits(8) for _ in range(n)))


def lights_toml(directions, extra=""):
    text = extra
    for d in directions:
        text += "[[light]]\ndirection = [%r, %r, %r]\n" % tuple(d)
    return text


def rig(path, kind):
    """`near-coplanar`: 8 lights on an arc in the x-z plane, y alternating +-0.012 (condition
    number near 60); `rank2`: 8 lights, two directions repeated; `coplanar`: all in y = 0;
    `lights200`: 200 lights on rings; `ambient`: a good rig naming a missing ambient frame;
    `positions`: every light at (0, 0, 0) with a pixel size."""
    ring = [(math.cos(a) * math.sqrt(0.5), math.sin(a) * math.sqrt(0.5), math.sqrt(0.5))
            for a in (2 * math.pi * i / 8 for i in range(8))]
    if kind == "near-coplanar":
        arc = [math.radians(30 + 120 * i / 7) for i in range(8)]
        dirs = [(math.cos(a), 0.012 if i % 2 == 0 else -0.012, math.sin(a)) for i, a in enumerate(arc)]
        text = lights_toml(dirs)
    elif kind == "rank2":
        text = lights_toml([ring[0], ring[2]] * 4)
    elif kind == "coplanar":
        text = lights_toml([(math.cos(a), 0.0, math.sin(a)) for a in (math.radians(30 + 15 * i) for i in range(8))])
    elif kind == "lights200":
        dirs = []
        for i in range(200):
            elevation = math.radians(25 + 50 * (i % 5) / 4)
            azimuth = 2 * math.pi * i / 200
            dirs.append((math.cos(elevation) * math.cos(azimuth), math.cos(elevation) * math.sin(azimuth),
                         math.sin(elevation)))
        text = lights_toml(dirs)
    elif kind == "ambient":
        text = lights_toml(ring, 'ambient = "nope.png"\n')
    elif kind == "positions":
        text = "mm_per_pixel = 0.05\n"
        for d in ring:
            text += "[[light]]\ndirection = [%r, %r, %r]\nposition = [0.0, 0.0, 0.0]\n" % d
    else:
        raise SystemExit("unknown rig kind " + kind)
    with open(path, "w") as f:
        f.write(text)


def main(argv):
    usage = __doc__ + "\nusage: hostile_inputs.py gray8|gray16 PATH W H VALUE | rgb16-random PATH W H SEED | " \
        "rgb16-const PATH W H R G B | jpeg PATH W H SEED | gltf PATH overrun|offset | bytes PATH N SEED | " \
        "rig PATH KIND"
    if len(argv) < 3:
        raise SystemExit(usage)
    kind, path, rest = argv[1], argv[2], argv[3:]
    n = [int(v) for v in rest if v.lstrip("-").isdigit()]
    if kind in ("gray8", "gray16"):
        gray(path, n[0], n[1], n[2], 8 if kind == "gray8" else 16)
    elif kind == "rgb16-random":
        rgb16_random(path, n[0], n[1], n[2])
    elif kind == "rgb16-const":
        rgb16_const(path, *n[:5])
    elif kind == "jpeg":
        jpeg(path, n[0], n[1], n[2])
    elif kind == "gltf":
        gltf(path, rest[0])
    elif kind == "bytes":
        random_bytes(path, n[0], n[1])
    elif kind == "rig":
        rig(path, rest[0])
    else:
        raise SystemExit(usage)


if __name__ == "__main__":
    main(sys.argv)
