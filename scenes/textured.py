#!/usr/bin/env python3
"""Writes textured.glb beside this file: a tiled floor and a wooden crate, each with a base
colour texture in the .glb's binary chunk (PNG, made here), a camera and a point light.
Python's standard library only, so that the scene can be made again anywhere:
`python3 scenes/textured.py`."""

import json
import math
import struct
import zlib
from pathlib import Path


def png(width, height, texel):
    """An 8-bit RGB PNG whose texel (x, y), y from the top row, is texel(x, y)."""

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    rows = b"".join(
        b"\0" + bytes(c for x in range(width) for c in texel(x, y)) for y in range(height)
    )
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(rows, 9))
        + chunk(b"IEND", b"")
    )


def tiles(x, y):
    """Terracotta and cream tiles, 8 to a side, with darker grout between them."""
    if x % 8 == 0 or y % 8 == 0:
        return (70, 60, 55)
    return (196, 98, 62) if (x // 8 + y // 8) % 2 == 0 else (232, 220, 190)


def planks(x, y):
    """Pine planks running across, their grain in bands, inside a dark frame."""
    if x < 3 or y < 3 or x > 28 or y > 28:
        return (84, 52, 28)
    if y % 7 == 2:
        return (120, 78, 40)
    grain = int(18 * math.sin(0.9 * x + 2.3 * (y // 7)) ** 2)
    return (200 - grain, 150 - grain, 90 - grain // 2)


def quad_floor():
    """The floor, y = 0 over [-3, 3] in x and z, facing up, its tiles repeated 3 times."""
    p = [(-3, 0, 3), (3, 0, 3), (3, 0, -3), (-3, 0, -3)]
    n = [(0, 1, 0)] * 4
    uv = [(0, 3), (3, 3), (3, 0), (0, 0)]
    return p, n, uv, [0, 1, 2, 0, 2, 3]


def cube():
    """A cube of side 1.4 standing on y = 0, each face the whole texture."""
    h = 0.7
    p, n, uv, ix = [], [], [], []
    for axis in range(3):
        for sign in (1, -1):
            normal = [0, 0, 0]
            normal[axis] = sign
            # Two edges of the face, so that u x v points along the normal.
            a = [0, 0, 0]
            b = [0, 0, 0]
            a[(axis + 1) % 3] = 1
            b[(axis + 2) % 3] = 1
            if sign < 0:
                a, b = b, a
            base = len(p)
            for du, dv in [(-1, -1), (1, -1), (1, 1), (-1, 1)]:
                c = [h * normal[k] + h * (du * a[k] + dv * b[k]) for k in range(3)]
                c[1] += h
                p.append(tuple(c))
                n.append(tuple(normal))
                uv.append(((du + 1) / 2, (1 - dv) / 2))
            ix += [base, base + 1, base + 2, base, base + 2, base + 3]
    return p, n, uv, ix


def look_at(eye, target):
    """The rotation (a quaternion x, y, z, w) that turns a glTF camera, looking down -Z
    with +Y up, to look from eye at target."""
    back = [e - t for e, t in zip(eye, target)]
    length = math.sqrt(sum(c * c for c in back))
    back = [c / length for c in back]
    right = [back[2], 0.0, -back[0]]
    length = math.sqrt(sum(c * c for c in right))
    right = [c / length for c in right]
    up = [
        back[1] * right[2] - back[2] * right[1],
        back[2] * right[0] - back[0] * right[2],
        back[0] * right[1] - back[1] * right[0],
    ]
    m = [[right[i], up[i], back[i]] for i in range(3)]
    w = math.sqrt(max(0.0, 1 + m[0][0] + m[1][1] + m[2][2])) / 2
    return [(m[2][1] - m[1][2]) / (4 * w), (m[0][2] - m[2][0]) / (4 * w), (m[1][0] - m[0][1]) / (4 * w), w]


def main():
    blob = bytearray()
    views, accessors = [], []

    def add(data, **accessor):
        while len(blob) % 4:
            blob.append(0)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        blob.extend(data)
        if accessor:
            accessors.append({"bufferView": len(views) - 1, **accessor})
            return len(accessors) - 1
        return len(views) - 1

    meshes = []
    for (p, n, uv, ix), material in [(quad_floor(), 0), (cube(), 1)]:
        lo = [min(c[k] for c in p) for k in range(3)]
        hi = [max(c[k] for c in p) for k in range(3)]
        flat = lambda vs: b"".join(struct.pack("<%df" % len(v), *v) for v in vs)
        attributes = {
            "POSITION": add(flat(p), componentType=5126, count=len(p), type="VEC3", min=lo, max=hi),
            "NORMAL": add(flat(n), componentType=5126, count=len(n), type="VEC3"),
            "TEXCOORD_0": add(flat(uv), componentType=5126, count=len(uv), type="VEC2"),
        }
        indices = add(struct.pack("<%dH" % len(ix), *ix), componentType=5123, count=len(ix), type="SCALAR")
        meshes.append({"primitives": [{"attributes": attributes, "indices": indices, "material": material}]})
    images = [
        {"bufferView": add(png(64, 64, tiles)), "mimeType": "image/png"},
        {"bufferView": add(png(32, 32, planks)), "mimeType": "image/png"},
    ]
    turn = math.radians(30)
    doc = {
        "asset": {"version": "2.0", "generator": "gpurt scenes/textured.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "color": [1, 1, 1]}]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3]}],
        "nodes": [
            {"mesh": 0},
            {"mesh": 1, "rotation": [0, math.sin(turn / 2), 0, math.cos(turn / 2)]},
            {"camera": 0, "translation": [3.2, 2.6, 4.4], "rotation": look_at([3.2, 2.6, 4.4], [0, 0.5, 0])},
            {"translation": [2.5, 4.5, 3.0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.75, "aspectRatio": 1.5, "znear": 0.1}}],
        "meshes": meshes,
        "materials": [
            {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0, "roughnessFactor": 0.6}},
            {"pbrMetallicRoughness": {"baseColorTexture": {"index": 1}, "metallicFactor": 0, "roughnessFactor": 1}},
        ],
        "textures": [{"source": 0, "sampler": 0}, {"source": 1, "sampler": 1}],
        "samplers": [{"wrapS": 10497, "wrapT": 10497}, {"wrapS": 33071, "wrapT": 33071}],
        "images": images,
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob)}],
    }
    while len(blob) % 4:
        blob.append(0)
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(blob), b"BIN\0") + blob
    out = Path(__file__).with_name("textured.glb")
    out.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body)


if __name__ == "__main__":
    main()
