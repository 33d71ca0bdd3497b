#!/usr/bin/env python3
"""Writes textured-cornell.obj, .mtl and checker.png (run from this folder).

Three sides of a Cornell-like box [-1, 1]^3 (OBJ files have no camera, so
the box is open towards the loader's framing camera): a red left wall with a
square area light just in front of it, a white box on the floor, and a floor
and back wall whose material `checker` has map_Kd checker.png, tiled twice
across each face (UVs 0..2, the map repeats). The map is a 16 x 16 checker of 4-texel cells,
warm at the top of the image and cool at the bottom, so that a flipped or
transposed lookup shows. Standard library only.
"""
import struct
import zlib

SIDE, CELL = 16, 4


def texel(x, y):
    """sRGB bytes of texel (x, y), y = 0 the top row."""
    light = ((x // CELL) + (y // CELL)) % 2 == 0
    t = y / (SIDE - 1)  # 0 at the top, 1 at the bottom
    if light:
        return (int(235 - 90 * t), 225, int(130 + 100 * t))
    return (int(150 - 110 * t), 60, int(40 + 120 * t))


def png(path):
    rows = b"".join(
        b"\x00" + bytes(c for x in range(SIDE) for c in texel(x, y)) for y in range(SIDE)
    )

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", SIDE, SIDE, 8, 2, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(rows, 9)) + chunk(b"IEND", b""))


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def main():
    png("checker.png")
    # (name, material, corners counter-clockwise seen from the lit side, uv of each corner, that side's normal).
    # Open towards +x, +y and +z, where the loader's framing camera (a three-quarter view from above) stands,
    # so that it sees only front faces (Mitsuba's BSDFs are one-sided).
    faces = [
        ("floor", "checker", [(-1, -1, 1), (1, -1, 1), (1, -1, -1), (-1, -1, -1)], [(0, 0), (2, 0), (2, 2), (0, 2)], (0, 1, 0)),
        ("back", "checker", [(-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1)], [(0, 0), (2, 0), (2, 2), (0, 2)], (0, 0, 1)),
        ("left", "red", [(-1, -1, 1), (-1, -1, -1), (-1, 1, -1), (-1, 1, 1)], [(0, 0), (1, 0), (1, 1), (0, 1)], (1, 0, 0)),
        ("light", "light", [(-0.99, 0.2, 0.3), (-0.99, 0.2, -0.4), (-0.99, 0.8, -0.4), (-0.99, 0.8, 0.3)], [(0, 0), (1, 0), (1, 1), (0, 1)], (1, 0, 0)),
    ]
    # A white box on the floor (no bottom face, which would lie in the floor's plane).
    x0, x1, y0, y1, z0, z1 = 0.1, 0.6, -1.0, -0.4, -0.5, 0.0
    unit = [(0, 0), (1, 0), (1, 1), (0, 1)]
    faces += [
        ("box-top", "white", [(x0, y1, z1), (x1, y1, z1), (x1, y1, z0), (x0, y1, z0)], unit, (0, 1, 0)),
        ("box-front", "white", [(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], unit, (0, 0, 1)),
        ("box-back", "white", [(x1, y0, z0), (x0, y0, z0), (x0, y1, z0), (x1, y1, z0)], unit, (0, 0, -1)),
        ("box-right", "white", [(x1, y0, z1), (x1, y0, z0), (x1, y1, z0), (x1, y1, z1)], unit, (1, 0, 0)),
        ("box-left", "white", [(x0, y0, z0), (x0, y0, z1), (x0, y1, z1), (x0, y1, z0)], unit, (-1, 0, 0)),
    ]
    out = ["# Textured three-sided Cornell-like box for Lustre's reference checks (make_scene.py)", "mtllib textured-cornell.mtl"]
    v = 0
    for name, material, corners, uvs, normal in faces:
        n = cross(sub(corners[1], corners[0]), sub(corners[2], corners[0]))
        assert sum(a * b for a, b in zip(n, normal)) > 0, name
        out.append(f"o {name}")
        out += [f"v {x:g} {y:g} {z:g}" for x, y, z in corners]
        out += [f"vt {s:g} {t:g}" for s, t in uvs]
        out.append(f"vn {normal[0]} {normal[1]} {normal[2]}")
        out.append(f"usemtl {material}")
        k = v // 4 + 1
        i = [v + 1, v + 2, v + 3, v + 4]
        out.append(f"f {i[0]}/{i[0]}/{k} {i[1]}/{i[1]}/{k} {i[2]}/{i[2]}/{k}")
        out.append(f"f {i[2]}/{i[2]}/{k} {i[3]}/{i[3]}/{k} {i[0]}/{i[0]}/{k}")
        v += 4
    with open("textured-cornell.obj", "w") as f:
        f.write("\n".join(out) + "\n")
    with open("textured-cornell.mtl", "w") as f:
        f.write(
            "newmtl checker\nKd 0.8 0.8 0.8\nmap_Kd checker.png\n\n"
            "newmtl white\nKd 0.75 0.75 0.75\n\n"
            "newmtl red\nKd 0.63 0.065 0.05\n\n"
            "newmtl light\nKd 0 0 0\nKe 12 10 7\n"
        )


if __name__ == "__main__":
    main()
