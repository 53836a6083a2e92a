#!/usr/bin/env python3
"""The converged reference: rtrace without ambient caching, -ad raised until the grid's mean
settles, two independent sample sets at each step; then our own run at high settings as a
cross-check.

  rtrace -I+ -h -n 2 -ab AB -aa 0 -ad AD -lw 0.001/AD -dj 0 -dt 0 -dc 1 office.oct < grid.pts

Each -ad runs twice, the points in two seeded orders (rtrace has no seed; its sampling follows
the running ray count, so another order is another set of samples). The reference is the two
runs' average at the largest -ad; its noise per point is the RMS relative difference of the two
divided by 2 (σ/√2 for the average of two runs of noise σ each, their difference having σ√2).

Writes DIR/reference.csv (x,y,z,dx,dy,dz,lux,lux_a,lux_b) and DIR/reference.json (the ladder,
the cross-check). Usage: reference.py --dir DIR [--ads 1024,4096,16384] [--ab 12]
"""

import argparse
import json
import os
from types import SimpleNamespace

import numpy as np

from common import errors, oconv, ours, ours_command, read_pts, rtrace, rtrace_command


def reference_options(ab, ad):
    return ["-ab", str(ab), "-aa", "0", "-ad", str(ad), "-lw", f"{1e-3 / ad:.3g}",
            "-dj", "0", "-dt", "0", "-dc", "1"]


def pair_noise(a, b):
    """Per-point noise of the average of two independent runs (relative, RMS over points)."""
    return float(np.sqrt(np.mean(((a - b) / (a + b)) ** 2)))


def cached_rtrace(d, octree, pts, opts, args, order):
    """rtrace's run, kept in DIR/runs/ so that a rerun with a longer ladder redoes nothing
    (a reference run takes minutes)."""
    os.makedirs(os.path.join(d, "runs"), exist_ok=True)
    path = os.path.join(d, "runs", "rtrace" + "".join(opts).replace("-", "_") + f"_order{order}.npz")
    if os.path.exists(path):
        z = np.load(path)
        return z["lux"], SimpleNamespace(wall=float(z["wall"]), cpu=float(z["cpu"]))
    lux, clock = rtrace(octree, pts, opts, args.nproc, order=order, cwd=d)
    np.savez(path, lux=lux, wall=clock.wall, cpu=clock.cpu)
    return lux, clock


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dir", required=True)
    ap.add_argument("--ads", default="1024,4096,16384")
    ap.add_argument("--ab", type=int, default=12)
    ap.add_argument("--nproc", type=int, default=2)
    ap.add_argument("--ours", default="--patches 160000 --indirect-samples 16384 --tolerance 1e-5",
                    help="our high settings for the cross-check")
    args = ap.parse_args()
    d = os.path.abspath(args.dir)
    grid = os.path.join(d, "grid.pts")
    pts = read_pts(grid)
    octree = os.path.join(d, "office.oct")
    oconv("office.rad", octree, d)
    ladder, prev = [], None
    for ad in [int(a) for a in args.ads.split(",")]:
        opts = reference_options(args.ab, ad)
        a, ca = cached_rtrace(d, octree, pts, opts, args, 1)
        b, cb = cached_rtrace(d, octree, pts, opts, args, 2)
        avg = 0.5 * (a + b)
        step = {
            "ad": ad, "mean": float(avg.mean()), "mean_a": float(a.mean()),
            "mean_b": float(b.mean()), "noise": pair_noise(a, b),
            "wall": [ca.wall, cb.wall], "cpu": [ca.cpu, cb.cpu],
            "change": None if prev is None else float(avg.mean() / prev.mean() - 1),
            "rms_change": None if prev is None else errors(avg, prev)["rms"],
        }
        ladder.append(step)
        print(f"-ad {ad:6d}: mean {step['mean']:.3f} lx (orders {step['mean_a']:.3f}, "
              f"{step['mean_b']:.3f}), per-point noise {100 * step['noise']:.3f} %, "
              + ("" if prev is None else f"mean change {100 * step['change']:+.3f} %, "
                 f"RMS change {100 * step['rms_change']:.3f} %, ")
              + f"{np.mean(step['cpu']):.0f} CPU-s, {np.mean(step['wall']):.0f} s wall a run",
              flush=True)
        prev = avg
    ref = prev
    np.savetxt(os.path.join(d, "reference.csv"), np.column_stack([pts, ref, a, b]),
               delimiter=",", header="x,y,z,dx,dy,dz,lux,lux_a,lux_b", comments="", fmt="%.9g")
    # The cross-check: ours at high settings, two seeds.
    opts = args.ours.split()
    runs = [ours("office.obj", "schedule.csv", grid, opts + ["--seed", str(s)], cwd=d)
            for s in (1, 2)]
    o = 0.5 * (runs[0][0] + runs[1][0])
    e = errors(o, ref)
    noise = {"reference": ladder[-1]["noise"], "ours": pair_noise(runs[0][0], runs[1][0])}
    combined = float(np.hypot(noise["reference"], noise["ours"]))
    print(f"cross-check: {' '.join(ours_command('office.obj', 'schedule.csv', 'grid.pts', 'hi.csv', opts))}"
          f" (seeds 1 and 2, {np.mean([r[1].cpu for r in runs]):.0f} CPU-s a run): mean "
          f"{o.mean():.3f} lx, {100 * e['mean']:+.3f} % from the reference; RMS "
          f"{100 * e['rms']:.3f} %, worst {100 * e['max']:.3f} %; per-point noise: reference "
          f"{100 * noise['reference']:.3f} %, ours {100 * noise['ours']:.3f} %, combined "
          f"{100 * combined:.3f} %")
    with open(os.path.join(d, "reference.json"), "w") as f:
        json.dump({"rtrace": " ".join(rtrace_command("office.oct", reference_options(args.ab, ad), 2)),
                   "ladder": ladder, "cross_check": {"options": args.ours, "errors": e,
                                                      "mean": float(o.mean()), "noise": noise,
                                                      "combined_noise": combined}},
                  f, indent=1)


if __name__ == "__main__":
    main()
