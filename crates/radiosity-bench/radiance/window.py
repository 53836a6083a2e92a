#!/usr/bin/env python3
"""The side-lit office of docs/daylight-radiance.md, written for both `radiosity lighting` and
Radiance.

A 6 × 4 × 2.8 m room (x along the 6 m side, y into the room, z up, metres; north +y, so the
window faces south), empty, grey and diffuse: floor ρ 0.2, walls 0.5, ceiling 0.7. One window
in the south wall (y = 0), 4 × 1.5 m, x 1–5 m, sill 0.9 m, head 2.4 m, glazed with a clear
pane of normal transmittance 0.8 (ours `--glazing glass=0.8`; Radiance `glass` of
transmissivity tn = (√(0.8402528435 + 0.0072522239 T²) − 0.9166530661)/0.0036261119/T, the
conversion of Radiance's reference manual for n = 1.52). Walls are zero-thickness polygons;
outside there is nothing but the sky and the ground (at infinity in both tools).

Writes, into --out:
  office.obj/.mtl, office.rad          the glazed room, grey
  open.obj/.mtl, open.rad              the same with the window an unglazed opening
  black.obj/.mtl, black.rad            the glazed room with every reflectance 0 (sky component
  black-open.obj/.mtl, black-open.rad  only: the conversion's check), and its unglazed twin
  df.pts                               the daylight-factor grid: 0.8 m high, facing up, 0.5 m
                                       spacing, 0.25 m from the walls (12 × 8 = 96 points)
  annual.pts                           the annual grid: 0.8 m, 40 × 25 = 1,000 points, 0.15 ×
                                       0.16 m spacing, half a step from the walls

The skies are written by daylight.py and annual.py. Usage: window.py --out DIR
"""

import argparse
import math
import os

import numpy as np

W, D, H = 6.0, 4.0, 2.8
WINDOW = (1.0, 5.0, 0.9, 2.4)  # x0, x1, z0, z1 in the wall y = 0
TRANSMITTANCE = 0.8
REFLECTANCE = {"floor": 0.2, "wall": 0.5, "ceiling": 0.7}
WORKPLANE = 0.8


def transmissivity(t):
    """Radiance's `glass` takes the transmissivity (the internal transmittance of one pass,
    with its Fresnel losses folded in as Radiance defines it), not the transmittance at normal
    incidence: the reference manual's conversion for n = 1.52."""
    return (math.sqrt(0.8402528435 + 0.0072522239 * t * t) - 0.9166530661) / 0.0036261119 / t


def facing(quad, normal):
    """The quad's corners in the order whose right-hand normal is `normal`."""
    a, b, c = (np.array(p, float) for p in quad[:3])
    return quad if np.dot(np.cross(b - a, c - a), normal) > 0 else quad[::-1]


def rect_y0(x0, x1, z0, z1):
    return [(x0, 0.0, z0), (x1, 0.0, z0), (x1, 0.0, z1), (x0, 0.0, z1)]


def polygons(glazed):
    """(material, corners) of every face, each facing into the room; the window last."""
    out = [
        ("floor", facing([(0, 0, 0), (W, 0, 0), (W, D, 0), (0, D, 0)], (0, 0, 1))),
        ("ceiling", facing([(0, 0, H), (W, 0, H), (W, D, H), (0, D, H)], (0, 0, -1))),
        ("wall", facing([(0, D, 0), (W, D, 0), (W, D, H), (0, D, H)], (0, -1, 0))),
        ("wall", facing([(0, 0, 0), (0, D, 0), (0, D, H), (0, 0, H)], (1, 0, 0))),
        ("wall", facing([(W, 0, 0), (W, D, 0), (W, D, H), (W, 0, H)], (-1, 0, 0))),
    ]
    x0, x1, z0, z1 = WINDOW
    for q in (rect_y0(0, W, 0, z0), rect_y0(0, W, z1, H), rect_y0(0, x0, z0, z1),
              rect_y0(x1, W, z0, z1)):
        out.append(("wall", facing(q, (0, 1, 0))))
    if glazed:
        out.append(("glass", facing(rect_y0(x0, x1, z0, z1), (0, 1, 0))))
    return out


def write_obj(path, reflectance, glazed):
    stem = os.path.splitext(os.path.basename(path))[0]
    with open(os.path.join(os.path.dirname(path), stem + ".mtl"), "w") as f:
        for name, rho in reflectance.items():
            f.write(f"newmtl {name}\nKd {rho} {rho} {rho}\n")
        if glazed:
            # Named on the command line: --glazing glass=0.8.
            f.write("newmtl glass\nKd 0 0 0\n")
    with open(path, "w") as f:
        f.write(f"mtllib {stem}.mtl\n")
        vi = 1
        for material, quad in polygons(glazed):
            f.write(f"usemtl {material}\n")
            for p in quad:
                f.write("v {:.6f} {:.6f} {:.6f}\n".format(*p))
            f.write("f " + " ".join(str(vi + k) for k in range(len(quad))) + "\n")
            vi += len(quad)


def write_rad(path, reflectance, glazed):
    with open(path, "w") as f:
        for name, rho in reflectance.items():
            f.write(f"void plastic {name}\n0\n0\n5 {rho} {rho} {rho} 0 0\n\n")
        if glazed:
            tn = transmissivity(TRANSMITTANCE)
            f.write(f"void glass glass\n0\n0\n3 {tn:.9f} {tn:.9f} {tn:.9f}\n\n")
        for k, (material, quad) in enumerate(polygons(glazed)):
            f.write(f"{material} polygon {material}.{k}\n0\n0\n{3 * len(quad)}\n")
            for p in quad:
                f.write("  {:.6f} {:.6f} {:.6f}\n".format(*p))
            f.write("\n")


def grid(nx, ny):
    """nx × ny points at the work plane, half a step from the walls, facing up."""
    xs = (np.arange(nx) + 0.5) * W / nx
    ys = (np.arange(ny) + 0.5) * D / ny
    return np.array([(x, y, WORKPLANE, 0, 0, 1) for y in ys for x in xs])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    black = {name: 0.0 for name in REFLECTANCE}
    for stem, refl, glazed in (("office", REFLECTANCE, True), ("open", REFLECTANCE, False),
                               ("black", black, True), ("black-open", black, False)):
        write_obj(os.path.join(args.out, stem + ".obj"), refl, glazed)
        write_rad(os.path.join(args.out, stem + ".rad"), refl, glazed)
    np.savetxt(os.path.join(args.out, "df.pts"), grid(12, 8), fmt="%.6f")
    np.savetxt(os.path.join(args.out, "annual.pts"), grid(40, 25), fmt="%.6f")
    print(f"wrote the side-lit office ({W} x {D} x {H} m, window {WINDOW[1] - WINDOW[0]:g} x "
          f"{WINDOW[3] - WINDOW[2]:g} m, T {TRANSMITTANCE}, Radiance tn "
          f"{transmissivity(TRANSMITTANCE):.6f}) to {args.out}")


if __name__ == "__main__":
    main()
