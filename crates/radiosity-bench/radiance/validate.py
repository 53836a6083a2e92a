#!/usr/bin/env python3
"""The conversion's check before any comparison: direct light only, ours against `rtrace -ab 0`.

Both run on the black room that office.py writes (every reflectance 0, so our result is the
direct illuminance alone) at the work-plane grid and at sensors on the walls and the ceiling:
first the office's six luminaires (two orientations), then one strongly asymmetric road
luminaire aimed 37° off the vertical with a turned C0 (tilt.rad), which a wrong axis, a mirrored
C angle or a wrong multiplier cannot pass. Prints each set's worst and RMS relative difference
over the points that get more than 1 % of the set's largest illuminance, and exits non-zero
past --tolerance.

Usage: validate.py --dir DIR [--tolerance 0.01]   (DIR: office.py's --out, holding grid.pts)
"""

import argparse
import os

import numpy as np

from common import errors, oconv, ours, read_pts, rtrace, rtrace_command

DIRECT = ["-ab", "0", "-dj", "0", "-dt", "0", "-dc", "1", "-ds", "0.01"]


def sensors(grid):
    """The grid, 1.2 m high sensors along each wall 5 cm off it facing in, and sensors 5 cm under
    the ceiling facing down."""
    pts = [tuple(p) for p in grid]
    for x in np.linspace(0.5, 5.5, 6):
        pts.append((x, 0.05, 1.2, 0, 1, 0))
        pts.append((x, 3.95, 1.2, 0, -1, 0))
    for y in np.linspace(0.5, 3.5, 4):
        pts.append((0.05, y, 1.2, 1, 0, 0))
        pts.append((5.5, y, 1.2, -1, 0, 0))  # the cabinet's front is at x = 5.55
    for x in np.linspace(0.5, 5.5, 6):
        for y in (0.5, 2.0, 3.5):
            pts.append((x, y, 2.75, 0, 0, -1))
    return np.array(pts, dtype=float)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dir", required=True)
    ap.add_argument("--tolerance", type=float, default=0.01)
    args = ap.parse_args()
    d = os.path.abspath(args.dir)
    pts = sensors(read_pts(os.path.join(d, "grid.pts")))
    pts_file = os.path.join(d, "validate.pts")
    np.savetxt(pts_file, pts, fmt="%.6f")
    worst = 0.0
    for name, rad, schedule in (("office", "black.rad", "schedule.csv"),
                                ("tilted road luminaire", "tilt.rad", "tilt-schedule.csv")):
        octree = os.path.join(d, rad.replace(".rad", ".oct"))
        oconv(rad, octree, d)
        ref, _ = rtrace(octree, pts, DIRECT, nproc=1, cwd=d)
        got, _ = ours(os.path.join(d, "black.obj"), os.path.join(d, schedule), pts_file, [], cwd=d)
        lit = ref > 0.01 * ref.max()
        e = errors(got[lit], ref[lit])
        i = np.argmax(np.abs(got[lit] / ref[lit] - 1))
        print(f"{name}: {lit.sum()} of {len(pts)} points lit; direct illuminance "
              f"{ref[lit].min():.2f}–{ref[lit].max():.2f} lx; ours against rtrace -ab 0: "
              f"RMS {100 * e['rms']:.3f} %, worst {100 * e['max']:.3f} % "
              f"(at {pts[lit][i][:3]}, {got[lit][i]:.3f} vs {ref[lit][i]:.3f} lx), "
              f"mean {100 * e['mean']:+.3f} %")
        worst = max(worst, e["max"])
    print("rtrace: " + " ".join(rtrace_command("black.oct", DIRECT, 1)) + " < validate.pts")
    if worst > args.tolerance:
        raise SystemExit(f"the conversion's check failed: worst {100 * worst:.2f} % "
                         f"> {100 * args.tolerance:.2f} %")


if __name__ == "__main__":
    main()
