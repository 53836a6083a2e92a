#!/usr/bin/env python3
"""The office room of docs/lighting-radiance.md, written for both `radiosity lighting` and Radiance.

A 6 × 4 × 2.8 m room (x along the 6 m side, z up, metres): floor ρ 0.2, walls 0.5, ceiling
0.7, two desks (1.6 × 0.8 m tops, 0.72–0.75 m high, on two side panels; ρ 0.45) and a 2 m
cabinet against the east wall (ρ 0.4), all grey and diffuse; six `maxwell-8-t4-iesna.ies`
luminaires (LUXEON 5050 square, 1,000 lm) recessed in the ceiling on a 2 × 2 m layout, photometric
centre 5 mm below the ceiling, aimed straight down, light-loss factor 0.8; the back row turned by
90° (C0 along +y) so that the conversion's orientation is exercised.

Writes, into --out:
  office.obj, office.mtl      our scene (one-sided faces, front towards the room)
  schedule.csv                our luminaire schedule (the photometric file read from ../shared)
  office.rad                  the same scene for Radiance: `plastic` materials with the same
                              reflectance, the luminaires from `ies2rad`, placed by `xform`
  lum-*.rad, lum-*.dat        ies2rad's luminaires, one per (file, multiplier)
  black.obj/.mtl/.rad         the same room with every reflectance 0 (direct light only:
                              the conversion's check, validate.py)
  tilt-schedule.csv, tilt.rad the black room lit by one strongly asymmetric roadway luminaire
                              aimed obliquely with a turned C0: the orientation's check

Usage: office.py --out DIR [--shared ../shared]
"""

import argparse
import math
import os
import subprocess

from common import radiance_env, repo_shared

W, D, H = 6.0, 4.0, 2.8
REFLECTANCE = {
    "floor": 0.2,
    "wall": 0.5,
    "ceiling": 0.7,
    "desk": 0.45,
    "cabinet": 0.4,
}
# name, file, position, aim (gamma = 0), C0 direction, multiplier
LIGHT_LOSS = 0.8
MAXWELL = "maxwell-8-t4-iesna.ies"
ROADWAY = "roadway-60w-lm63-2019.ies"
CEILING_OFFSET = 0.005


def luminaires():
    rows = []
    for j, y in enumerate((1.0, 3.0)):
        for i, x in enumerate((1.0, 3.0, 5.0)):
            c0 = (1.0, 0.0, 0.0) if j == 0 else (0.0, 1.0, 0.0)
            rows.append((f"L{j}{i}", MAXWELL, (x, y, H - CEILING_OFFSET), (0.0, 0.0, -1.0), c0, LIGHT_LOSS))
    return rows


def tilted_luminaire():
    """The orientation check: a road luminaire 0.8 m below the ceiling's middle, aimed 35° off
    the nadir towards −x, +y a little, its C0 turned towards +y."""
    return [("T", ROADWAY, (3.2, 1.8, 2.0), (-0.55, 0.25, -0.8), (0.3, 1.0, 0.0), 0.5)]


# ---------------------------------------------------------------- geometry


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def unit(a):
    n = math.sqrt(dot(a, a))
    return tuple(x / n for x in a)


def facing(quad, normal):
    """The quad's corners in the order whose right-hand normal is `normal`."""
    n = cross(sub(quad[1], quad[0]), sub(quad[2], quad[0]))
    return quad if dot(n, normal) > 0 else quad[::-1]


def box(lo, hi, skip=()):
    """A box's faces facing outwards; `skip` names faces left out ('-z' a bottom on the floor,
    '+x' a back against a wall)."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    faces = {
        "-x": ([(x0, y0, z0), (x0, y1, z0), (x0, y1, z1), (x0, y0, z1)], (-1, 0, 0)),
        "+x": ([(x1, y0, z0), (x1, y1, z0), (x1, y1, z1), (x1, y0, z1)], (1, 0, 0)),
        "-y": ([(x0, y0, z0), (x1, y0, z0), (x1, y0, z1), (x0, y0, z1)], (0, -1, 0)),
        "+y": ([(x0, y1, z0), (x1, y1, z0), (x1, y1, z1), (x0, y1, z1)], (0, 1, 0)),
        "-z": ([(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0)], (0, 0, -1)),
        "+z": ([(x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)], (0, 0, 1)),
    }
    return [facing(q, n) for k, (q, n) in faces.items() if k not in skip]


def polygons():
    """(material, corners) of every face, each facing into the room."""
    out = []
    out.append(("floor", facing([(0, 0, 0), (W, 0, 0), (W, D, 0), (0, D, 0)], (0, 0, 1))))
    out.append(("ceiling", facing([(0, 0, H), (W, 0, H), (W, D, H), (0, D, H)], (0, 0, -1))))
    out.append(("wall", facing([(0, 0, 0), (W, 0, 0), (W, 0, H), (0, 0, H)], (0, 1, 0))))
    out.append(("wall", facing([(0, D, 0), (W, D, 0), (W, D, H), (0, D, H)], (0, -1, 0))))
    out.append(("wall", facing([(0, 0, 0), (0, D, 0), (0, D, H), (0, 0, H)], (1, 0, 0))))
    out.append(("wall", facing([(W, 0, 0), (W, D, 0), (W, D, H), (W, 0, H)], (-1, 0, 0))))
    # Two desks: a 3 cm top at 0.72–0.75 m on two 3 cm side panels.
    for x0, y0 in ((1.2, 0.8), (3.2, 2.4)):
        x1, y1 = x0 + 1.6, y0 + 0.8
        out += [("desk", q) for q in box((x0, y0, 0.72), (x1, y1, 0.75))]
        out += [("desk", q) for q in box((x0, y0, 0.0), (x0 + 0.03, y1, 0.72), skip=("-z", "+z"))]
        out += [("desk", q) for q in box((x1 - 0.03, y0, 0.0), (x1, y1, 0.72), skip=("-z", "+z"))]
    # A cabinet against the east wall: no bottom (on the floor), no back (against the wall).
    out += [("cabinet", q) for q in box((W - 0.45, 1.5, 0.0), (W, 2.5, 2.0), skip=("-z", "+x"))]
    return out


# ---------------------------------------------------------------- writers


def write_obj(path, reflectance):
    stem = os.path.splitext(os.path.basename(path))[0]
    with open(os.path.join(os.path.dirname(path), stem + ".mtl"), "w") as f:
        for name, rho in reflectance.items():
            f.write(f"newmtl {name}\nKd {rho} {rho} {rho}\n")
    with open(path, "w") as f:
        f.write(f"mtllib {stem}.mtl\n")
        vi = 1
        for material, quad in polygons():
            f.write(f"usemtl {material}\n")
            for p in quad:
                f.write("v {:.6f} {:.6f} {:.6f}\n".format(*p))
            f.write("f " + " ".join(str(vi + k) for k in range(len(quad))) + "\n")
            vi += len(quad)


def write_schedule(path, rows, shared):
    with open(path, "w") as f:
        f.write("name,file,x,y,z,aim_x,aim_y,aim_z,c0_x,c0_y,c0_z,multiplier,group\n")
        for name, file, p, aim, c0, mult in rows:
            ies = os.path.abspath(os.path.join(shared, "photometry", file))
            f.write(f"{name},{ies},{p[0]},{p[1]},{p[2]},{aim[0]},{aim[1]},{aim[2]},"
                    f"{c0[0]},{c0[1]},{c0[2]},{mult},\n")


def frame(aim, c0):
    """Our luminaire frame (crates/radiosity/src/lighting/luminaire.rs): nadir = aim, c0 made
    perpendicular to it, c90 = c0 × nadir. Returns the rotation matrix M (rows) whose columns are
    the world images of the luminaire's +x (c0), +y (c90) and +z (−nadir): the same frame as
    ies2rad's output (nadir −z, C0 +x, C90 +y; source.cal's src_phi and src_theta)."""
    nadir = unit(aim)
    c = unit(sub(c0, tuple(dot(c0, nadir) * n for n in nadir)))
    c90 = cross(c, nadir)
    up = tuple(-n for n in nadir)
    return [[c[i], c90[i], up[i]] for i in range(3)]


def zyz(m):
    """Euler angles (degrees) with M = Rz(a) Ry(b) Rz(c), so that `xform -rz c -ry b -rz a`
    applies M (xform applies its transforms left to right)."""
    b = math.acos(max(-1.0, min(1.0, m[2][2])))
    if abs(math.sin(b)) < 1e-9:
        a, c = math.atan2(m[1][0], m[0][0]), 0.0
        if m[2][2] < 0:  # b = 180°: Rz(a) Ry(180) = [[-cos a, sin a], [-sin a, -cos a]] on x, y
            a = math.atan2(m[0][1], -m[0][0])
    else:
        a = math.atan2(m[1][2], m[0][2])
        c = math.atan2(m[2][1], -m[2][0])
    return tuple(math.degrees(t) for t in (a, b, c))


def check_euler(m, a, b, c):
    """Rz(a) Ry(b) Rz(c) must be M to 1e-9: the placement must be the schedule's frame."""

    def rz(t):
        t = math.radians(t)
        return [[math.cos(t), -math.sin(t), 0], [math.sin(t), math.cos(t), 0], [0, 0, 1]]

    def ry(t):
        t = math.radians(t)
        return [[math.cos(t), 0, math.sin(t)], [0, 1, 0], [-math.sin(t), 0, math.cos(t)]]

    def mul(p, q):
        return [[sum(p[i][k] * q[k][j] for k in range(3)) for j in range(3)] for i in range(3)]

    r = mul(mul(rz(a), ry(b)), rz(c))
    worst = max(abs(r[i][j] - m[i][j]) for i in range(3) for j in range(3))
    assert worst < 1e-9, f"Euler angles {a, b, c} miss the frame by {worst}"


def convert(out, shared, file, mult):
    """ies2rad's luminaire for a file and multiplier: `-dm` writes metres, `-m` scales the
    intensities (our schedule's multiplier), `-t default` makes the lamp white. Returns the
    .rad file's name (it lies in `out`, with its .dat)."""
    stem = "lum-" + os.path.splitext(file)[0] + f"-m{mult:g}"
    ies = os.path.abspath(os.path.join(shared, "photometry", file))
    subprocess.run(["ies2rad", "-dm", "-t", "default", "-m", str(mult), "-o", stem, ies],
                   cwd=out, check=True, env=radiance_env())
    return stem + ".rad"


def write_rad(path, reflectance, rows, out, shared):
    with open(path, "w") as f:
        for name, rho in reflectance.items():
            f.write(f"void plastic {name}\n0\n0\n5 {rho} {rho} {rho} 0 0\n\n")
        for k, (material, quad) in enumerate(polygons()):
            f.write(f"{material} polygon {material}.{k}\n0\n0\n{3 * len(quad)}\n")
            for p in quad:
                f.write("  {:.6f} {:.6f} {:.6f}\n".format(*p))
            f.write("\n")
        converted = {}
        for name, file, p, aim, c0, mult in rows:
            key = (file, mult)
            if key not in converted:
                converted[key] = convert(out, shared, file, mult)
            m = frame(aim, c0)
            a, b, c = zyz(m)
            check_euler(m, a, b, c)
            f.write(f"!xform -n {name} -rz {c:.9f} -ry {b:.9f} -rz {a:.9f} "
                    f"-t {p[0]} {p[1]} {p[2]} {converted[key]}\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--shared", default=repo_shared())
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    black = {name: 0.0 for name in REFLECTANCE}
    write_obj(os.path.join(args.out, "office.obj"), REFLECTANCE)
    write_obj(os.path.join(args.out, "black.obj"), black)
    write_schedule(os.path.join(args.out, "schedule.csv"), luminaires(), args.shared)
    write_schedule(os.path.join(args.out, "tilt-schedule.csv"), tilted_luminaire(), args.shared)
    write_rad(os.path.join(args.out, "office.rad"), REFLECTANCE, luminaires(), args.out, args.shared)
    write_rad(os.path.join(args.out, "black.rad"), black, luminaires(), args.out, args.shared)
    write_rad(os.path.join(args.out, "tilt.rad"), black, tilted_luminaire(), args.out, args.shared)
    print(f"wrote the office ({W} x {D} x {H} m, {len(polygons())} polygons, "
          f"{len(luminaires())} luminaires) to {args.out}")


if __name__ == "__main__":
    main()
