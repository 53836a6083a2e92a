#!/usr/bin/env python3
"""Write the small test scenes of this folder (standard library only).

  room.gltf + room.bin + checker.png   a 4 x 2.5 x 3 m room (glTF 2.0, +y up, metres)
  room.ply                             a 2 m closed box with a ceiling light (ASCII PLY)
  room_be.ply                          the same box, binary big-endian, colours per vertex

What the glTF room exercises, with the values the tests check:
  - floor as a TRIANGLE_STRIP (4 vertices, 2 triangles), reflectance 0.5;
  - back wall textured: baseColorFactor 0.8 x checker.png (2x2 texels, sRGB 255 and 0, so a
    linear mean of 0.5): reflectance 0.4;
  - left wall red (0.63, 0.065, 0.05), right wall green (0.14, 0.45, 0.091), front wall and
    ceiling white 0.75 (front wall a TRIANGLE_FAN of 4 vertices);
  - a 1 x 1 m light 1 cm under the ceiling facing down, emissiveFactor (1, 0.9, 0.8) x
    KHR_materials_emissive_strength 5, so E = (5, 4.5, 4) W/m2;
  - one unit cube mesh (12 triangles, outward) instanced twice: under a parent node translated
    by (1, 0, 0) then a child scaled 0.5 and lifted 0.25 m, and once mirrored (scale
    (-0.6, 0.6, 0.6), rotated 30 degrees about y);
  - a camera node at (2, 1.3, 2.9) looking down -z (glTF's camera axis) pitched 20 degrees
    down, yfov 1.0 rad.
"""
import json, math, struct, zlib, os

HERE = os.path.dirname(os.path.abspath(__file__))


def png(path, w, h, rows):
    raw = b"".join(b"\x00" + bytes(r) for r in rows)
    def chunk(t, d):
        c = t + d
        return struct.pack(">I", len(d)) + c + struct.pack(">I", zlib.crc32(c) & 0xFFFFFFFF)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    data += chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")
    open(path, "wb").write(data)


def gltf_room():
    buf = bytearray()
    views, accessors = [], []

    def add(data, fmt, count, kind, comp, target, minmax=None):
        while len(buf) % 4:
            buf.append(0)
        off = len(buf)
        buf.extend(struct.pack("<" + fmt * (len(data)), *data))
        views.append({"buffer": 0, "byteOffset": off, "byteLength": len(buf) - off, "target": target})
        a = {"bufferView": len(views) - 1, "componentType": comp, "count": count, "type": kind}
        if minmax:
            a["min"], a["max"] = minmax
        accessors.append(a)
        return len(accessors) - 1

    def positions(pts):
        flat = [c for p in pts for c in p]
        lo = [min(p[k] for p in pts) for k in range(3)]
        hi = [max(p[k] for p in pts) for k in range(3)]
        return add(flat, "f", len(pts), "VEC3", 5126, 34962, (lo, hi))

    def indices(ix):
        return add(ix, "H", len(ix), "SCALAR", 5123, 34963)

    X, Y, Z = 4.0, 2.5, 3.0
    prims = []
    # Floor, y = 0, facing +y: strip (0,0,0) (0,0,Z) (X,0,0) (X,0,Z).
    prims.append({"attributes": {"POSITION": positions([(0, 0, 0), (0, 0, Z), (X, 0, 0), (X, 0, Z)])},
                  "mode": 5, "material": 0})
    # Ceiling, y = Y, facing -y.
    prims.append({"attributes": {"POSITION": positions([(0, Y, 0), (X, Y, 0), (X, Y, Z), (0, Y, Z)])},
                  "indices": indices([0, 1, 2, 0, 2, 3]), "material": 4})
    # Back wall z = 0 facing +z, with texture coordinates.
    back = positions([(0, 0, 0), (X, 0, 0), (X, Y, 0), (0, Y, 0)])
    uv = add([0, 1, 1, 1, 1, 0, 0, 0], "f", 4, "VEC2", 5126, 34962)
    prims.append({"attributes": {"POSITION": back, "TEXCOORD_0": uv},
                  "indices": indices([0, 1, 2, 0, 2, 3]), "material": 1})
    # Front wall z = Z facing -z, as a fan.
    prims.append({"attributes": {"POSITION": positions([(0, 0, Z), (0, Y, Z), (X, Y, Z), (X, 0, Z)])},
                  "mode": 6, "material": 4})
    # Left wall x = 0 facing +x (red), right wall x = X facing -x (green).
    prims.append({"attributes": {"POSITION": positions([(0, 0, 0), (0, Y, 0), (0, Y, Z), (0, 0, Z)])},
                  "indices": indices([0, 1, 2, 0, 2, 3]), "material": 2})
    prims.append({"attributes": {"POSITION": positions([(X, 0, 0), (X, 0, Z), (X, Y, Z), (X, Y, 0)])},
                  "indices": indices([0, 1, 2, 0, 2, 3]), "material": 3})
    # Light: 1 x 1 m at y = Y - 0.01, facing down.
    ly = Y - 0.01
    prims.append({"attributes": {"POSITION": positions([(1.5, ly, 1.0), (2.5, ly, 1.0), (2.5, ly, 2.0), (1.5, ly, 2.0)])},
                  "indices": indices([0, 1, 2, 0, 2, 3]), "material": 5})
    # Unit cube centred at the origin, outward faces.
    h = 0.5
    cube_pts, cube_ix = [], []
    for axis in range(3):
        for s in (-1, 1):
            n = [0, 0, 0]
            n[axis] = s
            u = [0, 0, 0]
            u[(axis + 1) % 3] = 1
            v = [0, 0, 0]
            v[(axis + 2) % 3] = 1
            base = len(cube_pts)
            for (a, b) in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                cube_pts.append(tuple(h * (n[k] + a * u[k] + b * v[k]) for k in range(3)))
            quad = [0, 1, 2, 0, 2, 3] if s > 0 else [0, 2, 1, 0, 3, 2]
            cube_ix += [base + q for q in quad]
    cube = {"attributes": {"POSITION": positions(cube_pts)}, "indices": indices(cube_ix), "material": 4}

    png(os.path.join(HERE, "checker.png"), 2, 2, [[255, 255, 255, 0, 0, 0], [0, 0, 0, 255, 255, 255]])
    open(os.path.join(HERE, "room.bin"), "wb").write(bytes(buf))
    half = math.radians(30) / 2
    doc = {
        "asset": {"version": "2.0", "generator": "radiosity tests/data/make_scenes.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 3, 4]}],
        "nodes": [
            {"name": "room", "mesh": 0},
            {"name": "box parent", "translation": [1.0, 0.0, 0.0], "children": [2]},
            {"name": "small box", "mesh": 1, "translation": [0.0, 0.25, 1.5], "scale": [0.5, 0.5, 0.5]},
            {"name": "mirrored box", "mesh": 1, "translation": [3.0, 0.3, 1.5],
             "rotation": [0.0, math.sin(half), 0.0, math.cos(half)], "scale": [-0.6, 0.6, 0.6]},
            {"name": "camera", "camera": 0, "translation": [2.0, 1.3, 2.9],
             "rotation": [math.sin(math.radians(-10)), 0.0, 0.0, math.cos(math.radians(-10))]},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 1.0, "znear": 0.01}}],
        "meshes": [{"name": "room", "primitives": prims}, {"name": "cube", "primitives": [cube]}],
        "materials": [
            {"name": "floor", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0}},
            {"name": "checker wall", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1],
                                                              "baseColorTexture": {"index": 0}, "metallicFactor": 0}},
            {"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.63, 0.065, 0.05, 1], "metallicFactor": 0}},
            {"name": "green", "pbrMetallicRoughness": {"baseColorFactor": [0.14, 0.45, 0.091, 1], "metallicFactor": 0}},
            {"name": "white", "pbrMetallicRoughness": {"baseColorFactor": [0.75, 0.75, 0.75, 1], "metallicFactor": 0}},
            {"name": "light", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0},
             "emissiveFactor": [1.0, 0.9, 0.8],
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 5.0}}},
        ],
        "textures": [{"source": 0}],
        "images": [{"uri": "checker.png"}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"uri": "room.bin", "byteLength": len(buf)}],
    }
    open(os.path.join(HERE, "room.gltf"), "w").write(json.dumps(doc, indent=1) + "\n")


# PLY box: 2 m cube, faces inward; a 0.5 m light quad 1 cm under the ceiling, facing down.
BOX = [(0, 0, 0), (2, 0, 0), (2, 2, 0), (0, 2, 0), (0, 0, 2), (2, 0, 2), (2, 2, 2), (0, 2, 2),
       (0.75, 1.99, 0.75), (1.25, 1.99, 0.75), (1.25, 1.99, 1.25), (0.75, 1.99, 1.25)]
# (vertex indices, colour as uchar sRGB, emission W/m2)
FACES = [
    ([0, 4, 5, 1], (128, 128, 128), 0.0),      # floor y=0 facing +y (quad)
    ([3, 2, 6], (200, 200, 200), 0.0),         # ceiling y=2 facing -y, as two triangles
    ([3, 6, 7], (200, 200, 200), 0.0),
    ([0, 1, 2, 3], (200, 200, 200), 0.0),      # back z=0 facing +z
    ([4, 7, 6, 5], (200, 200, 200), 0.0),      # front z=2 facing -z
    ([0, 3, 7, 4], (180, 40, 30), 0.0),        # left x=0 facing +x (red)
    ([1, 5, 6, 2], (40, 150, 40), 0.0),        # right x=2 facing -x (green)
    ([8, 9, 10, 11], (255, 255, 255), 16.0),   # light facing -y
]


def ply_ascii():
    lines = ["ply", "format ascii 1.0", "comment radiosity test box, made by make_scenes.py",
             f"element vertex {len(BOX)}", "property float x", "property float y", "property float z",
             f"element face {len(FACES)}", "property list uchar int vertex_indices",
             "property uchar red", "property uchar green", "property uchar blue", "property float emission",
             "end_header"]
    lines += [f"{x} {y} {z}" for (x, y, z) in BOX]
    lines += [f"{len(ix)} {' '.join(map(str, ix))} {r} {g} {b} {e}" for (ix, (r, g, b), e) in FACES]
    open(os.path.join(HERE, "room.ply"), "w").write("\n".join(lines) + "\n")


def ply_be():
    # Colours per vertex: every vertex of the box grey 200, the light's vertices white; emission
    # per face. Faces that share box corners average their vertices' colours, so every box face
    # is grey 200 here.
    head = ["ply", "format binary_big_endian 1.0", f"element vertex {len(BOX)}",
            "property double x", "property double y", "property double z",
            "property uchar red", "property uchar green", "property uchar blue",
            f"element face {len(FACES)}", "property list uchar uint vertex_indices",
            "property float emission_red", "property float emission_green", "property float emission_blue",
            "end_header"]
    out = bytearray(("\n".join(head) + "\n").encode())
    for i, p in enumerate(BOX):
        c = 255 if i >= 8 else 200
        out += struct.pack(">dddBBB", *p, c, c, c)
    for (ix, _, e) in FACES:
        out += struct.pack(">B", len(ix)) + struct.pack(">" + "I" * len(ix), *ix) + struct.pack(">fff", e, e, e)
    open(os.path.join(HERE, "room_be.ply"), "wb").write(bytes(out))


if __name__ == "__main__":
    gltf_room()
    ply_ascii()
    ply_be()
