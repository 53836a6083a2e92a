#!/usr/bin/env python3
"""How both sides' time grows with the number of calculation points.

The same office, with finer work-plane grids at 0.8 m (spacing 0.7 m = the EN 12464-1 grid's,
0.35 m, 0.175 m; the 0.5 m border band left out), timed for our default and for the rtrace
settings on its front (compare.py) near our default's error. No errors here: the settings are
those whose errors compare.py measured, and a point's error does not depend on how many other
points there are (rtrace traces each point alone; our gather too, after one shared solve).

Usage: scaling.py --dir DIR [--reps 3] [--nproc 2]
"""

import argparse
import os

import numpy as np

from common import oconv, ours, rtrace

RTRACE = [
    ["-ab", "8", "-aa", "0", "-ad", "4096", "-lw", "0.000244", "-dj", "0", "-dt", "0", "-dc", "1"],
    ["-ab", "8", "-aa", "0", "-ad", "8192", "-lw", "0.000122", "-dj", "0", "-dt", "0", "-dc", "1"],
]


def grid(spacing, width=6.0, depth=4.0, border=0.5, height=0.8):
    """A grid of cells of about `spacing` over the floor less its border, a point at each
    cell's centre (EN 12464-1's layout), facing up."""
    nx = int(np.ceil((width - 2 * border) / spacing - 1e-9))
    ny = int(np.ceil((depth - 2 * border) / spacing - 1e-9))
    xs = border + (np.arange(nx) + 0.5) * (width - 2 * border) / nx
    ys = border + (np.arange(ny) + 0.5) * (depth - 2 * border) / ny
    return np.array([(x, y, height, 0, 0, 1) for y in ys for x in xs])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dir", required=True)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--nproc", type=int, default=2)
    args = ap.parse_args()
    d = os.path.abspath(args.dir)
    octree = os.path.join(d, "office.oct")
    oconv("office.rad", octree, d)
    print("| points | ours default: wall s, CPU s | "
          + " | ".join("rtrace " + " ".join(o) + ": wall s, CPU s" for o in RTRACE) + " |")
    print("|---|---|" + "---|" * len(RTRACE))
    for spacing in (0.7, 0.35, 0.175):
        pts = grid(spacing)
        path = os.path.join(d, f"grid-{spacing}.pts")
        np.savetxt(path, pts, fmt="%.6f")
        times = {k: [] for k in range(len(RTRACE) + 1)}
        for rep in range(1, args.reps + 1):
            for k in np.random.default_rng(rep).permutation(len(RTRACE) + 1):
                if k == 0:
                    _, clock = ours("office.obj", "schedule.csv", path, ["--seed", str(rep)], cwd=d)
                else:
                    _, clock = rtrace(octree, pts, RTRACE[k - 1], args.nproc, order=rep, cwd=d)
                times[k].append((clock.wall, clock.cpu))
        cells = [f"{np.median([t[0] for t in times[k]]):.2f}, {np.median([t[1] for t in times[k]]):.2f}"
                 for k in range(len(RTRACE) + 1)]
        print(f"| {len(pts)} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
