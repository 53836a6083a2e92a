#!/usr/bin/env python3
"""Daylight factors under the CIE overcast sky: ours against converged rtrace runs on the
side-lit office that window.py writes.

The sky: `gensky -c -B 55.866 -g 0.2` (horizontal diffuse irradiance 10,000 lx / 179 lm/W, ground
reflectance 0.2, as ours' defaults), in two forms:
  gensky  as gensky writes it: skybright.cal blends sky and ground across the horizon with
          weights (Dz + 1.01)^±10 (at the horizon 55 % sky, 45 % ground; 98 % sky at 11.5°),
  sharp   the same zenith and ground brightness, no blend (sharp.cal): the sky that ours and
          the issue define, L = L_z (1 + 2 sin θ)/3 above the horizon, ρ_g E_h/π below.
In Radiance the sky is a `glow` of radius 0, found by the ambient calculation only, so the sky
component is `rtrace -ab 1` in the black room (its every reflectance 0).

1. Sky component (the conversion's check): black rooms, glazed and unglazed, ours (every
   reflectance 0) against `rtrace -ab 1 -aa 0 -ad 65536` (one bounce: sky and ground seen
   directly, through the pane or the opening).
2. Daylight factors: the grey rooms, glazed and unglazed, rtrace `-ab 8 -aa 0 -ad AD
   -lw 1e-3/AD` at increasing AD, each twice (the points in two seeded orders: rtrace has no
   seed), the reference the average of the last pair; ours at the defaults and at high settings
   (two seeds each).

DF = 100 E / 10,000 lx at every point. Runs are cached in DIR/runs/ (delete it to redo).
Writes DIR/daylight.json and DIR/daylight.md. Usage: daylight.py --dir DIR [--ads 4096,16384]
"""

import argparse
import csv
import json
import os
import subprocess
import tempfile
from types import SimpleNamespace

import numpy as np

from common import Clock, errors, oconv, radiance_env, radiosity_binary, read_pts, rtrace

E_H = 10_000.0  # lx, the sky's unobstructed horizontal illuminance (ours' default)
EFFICACY = 179.0
GROUND = 0.2
SHARP_CAL = """{ CIE overcast sky above the horizon, the ground's constant brightness below, no
  blend across the horizon (gensky's skybright.cal has one). A1 zenith brightness, A2 ground
  brightness: gensky -c's A2 and A3. }
skybr = if(Dz, A1*(1 + 2*Dz)/3, A2);
"""
SOURCES = """skyfunc glow skyglow 0 0 4 1 1 1 0
skyglow source sky 0 0 4 0 0 1 180
skyfunc glow groundglow 0 0 4 1 1 1 0
groundglow source ground 0 0 4 0 0 -1 180
"""
SKY_COMPONENT = ["-ab", "1", "-aa", "0", "-ad", "65536", "-lw", "1e-7"]
OURS_HIGH = ["--patches", "40000", "--indirect-samples", "4096", "--sky-rays", "65536",
             "--tolerance", "1e-5"]


def write_skies(d):
    """gensky.rad (gensky's own) and sharp.rad (its parameters, no horizon blend)."""
    out = subprocess.run(["gensky", "3", "21", "12", "-c", "-B", f"{E_H / EFFICACY:.6f}",
                          "-g", str(GROUND)], capture_output=True, check=True, text=True,
                         env=radiance_env()).stdout
    with open(os.path.join(d, "gensky.rad"), "w") as f:
        f.write(out + SOURCES)
    args = next(line for line in out.splitlines() if line.startswith("3 2 ")).split()
    zenith, ground = float(args[2]), float(args[3])
    with open(os.path.join(d, "sharp.cal"), "w") as f:
        f.write(SHARP_CAL)
    with open(os.path.join(d, "sharp.rad"), "w") as f:
        f.write(f"void brightfunc skyfunc\n2 skybr sharp.cal\n0\n2 {zenith} {ground}\n" + SOURCES)
    return zenith, ground


def cached(d, key, fn):
    """A run's (values, clock), kept in DIR/runs/KEY.npz."""
    os.makedirs(os.path.join(d, "runs"), exist_ok=True)
    path = os.path.join(d, "runs", key.replace(" ", "").replace("-", "_").replace("/", "_") + ".npz")
    if os.path.exists(path):
        z = np.load(path)
        return z["v"], SimpleNamespace(wall=float(z["wall"]), cpu=float(z["cpu"]))
    v, clock = fn()
    np.savez(path, v=v, wall=clock.wall, cpu=clock.cpu)
    return v, clock


def radiance_df(d, room, sky, pts, opts, nproc, order):
    octree = os.path.join(d, f"{room}-{sky}.oct")
    if not os.path.exists(octree):
        with open(os.path.join(d, f"{room}-{sky}-all.rad"), "w") as f:
            f.write(f"!cat {room}.rad\n!cat {sky}.rad\n")
        oconv(f"{room}-{sky}-all.rad", octree, d)
    key = f"rtrace-{room}-{sky}-{'_'.join(opts)}-order{order}"
    lux, clock = cached(d, key, lambda: rtrace(octree, pts, opts, nproc, order=order, cwd=d))
    return 100.0 * lux / E_H, clock


def ours_command(room, options):
    glazing = ["--glazing", "glass=0.8"] if room in ("office", "black") else []
    return [radiosity_binary(), "lighting", f"{room}.obj", "--sky", "cie-overcast",
            "--sky-illuminance", f"{E_H:g}", "--ground-reflectance", str(GROUND),
            "--grid", "df.pts", "--out", "df.csv"] + glazing + list(options)


def ours_df(d, room, options, seed):
    def run():
        with tempfile.TemporaryDirectory() as tmp:
            cmd = ours_command(room, options + ["--seed", str(seed)])
            cmd[cmd.index("df.csv")] = os.path.join(tmp, "df.csv")
            with Clock() as clock:
                res = subprocess.run(cmd, capture_output=True, cwd=d)
            if res.returncode != 0:
                raise SystemExit(f"radiosity lighting failed: {res.stderr.decode().strip()}")
            with open(os.path.join(tmp, "df.csv")) as f:
                df = np.array([float(r["daylight_factor"]) for r in csv.DictReader(f)])
        return df, clock

    return cached(d, f"ours-{room}-{'_'.join(options)}-seed{seed}", run)


def pair_noise(a, b):
    return float(np.sqrt(np.mean(((a - b) / (a + b)) ** 2)))


def row(name, df, ref, clock=None):
    e = errors(df, ref)
    t = "" if clock is None else f" | {clock.cpu:.1f} | {clock.wall:.1f}"
    return (f"| {name} | {df.mean():.3f} | {df.min():.3f} | {df.max():.3f} | "
            f"{100 * e['mean']:+.2f} % | {100 * e['rms']:.2f} % | {100 * e['max']:.2f} %{t} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dir", required=True)
    ap.add_argument("--ads", default="4096,16384")
    ap.add_argument("--ab", type=int, default=8)
    ap.add_argument("--nproc", type=int, default=2)
    args = ap.parse_args()
    d = os.path.abspath(args.dir)
    pts = read_pts(os.path.join(d, "df.pts"))
    zenith, ground = write_skies(d)
    lines = [f"gensky -c -B {E_H / EFFICACY:.6f} -g {GROUND}: zenith {zenith} W/m²/sr, ground "
             f"{ground} W/m²/sr; ours `--sky cie-overcast --sky-illuminance {E_H:g}`", ""]
    result = {"sky_component": {}, "daylight_factor": {}}

    # 1. The sky component.
    lines += ["### Sky component (black room; DF of the sky and ground seen directly)", "",
              "| room, run | mean DF % | min | max | mean vs rtrace sharp | RMS | worst |",
              "|---|---|---|---|---|---|---|"]
    for room in ("black-open", "black"):
        ref, _ = radiance_df(d, room, "sharp", pts, SKY_COMPONENT, args.nproc, 0)
        gen, _ = radiance_df(d, room, "gensky", pts, SKY_COMPONENT, args.nproc, 0)
        mine, _ = ours_df(d, room, [], 1)
        lines.append(row(f"{room}: rtrace -ab 1, sharp sky", ref, ref))
        lines.append(row(f"{room}: rtrace -ab 1, gensky's sky", gen, ref))
        lines.append(row(f"{room}: ours, defaults", mine, ref))
        result["sky_component"][room] = {"rtrace_sharp": ref.tolist(), "rtrace_gensky": gen.tolist(),
                                         "ours": mine.tolist(), "errors": errors(mine, ref),
                                         "gensky_vs_sharp": errors(gen, ref)}
        print("\n".join(lines[-3:]), flush=True)
    lines.append("")

    # 2. Daylight factors, converged.
    for room in ("office", "open"):
        lines += [f"### Daylight factor, {room} ({'glazed, T 0.8' if room == 'office' else 'unglazed opening'})",
                  "", "| run | mean DF % | min | max | mean vs reference | RMS | worst | CPU s | wall s |",
                  "|---|---|---|---|---|---|---|---|---|"]
        ladder, prev = [], None
        for ad in [int(a) for a in args.ads.split(",")]:
            opts = ["-ab", str(args.ab), "-aa", "0", "-ad", str(ad), "-lw", f"{1e-3 / ad:.3g}"]
            a, ca = radiance_df(d, room, "sharp", pts, opts, args.nproc, 1)
            b, cb = radiance_df(d, room, "sharp", pts, opts, args.nproc, 2)
            avg = 0.5 * (a + b)
            ladder.append({"options": " ".join(opts), "df": avg, "noise": pair_noise(a, b),
                           "clock": ca, "change": None if prev is None else errors(avg, prev)})
            prev = avg
        ref = prev
        for step in ladder:
            lines.append(row(f"rtrace {step['options']} (2 orders; per-point noise "
                             f"{100 * step['noise']:.2f} %)", step["df"], ref, step["clock"]))
        gen, cg = radiance_df(d, room, "gensky", pts, ladder[-1]["options"].split(), args.nproc, 1)
        lines.append(row(f"rtrace, gensky's blended horizon, {ladder[-1]['options']}", gen, ref, cg))
        res = {"reference": ref.tolist(), "ladder": [
            {"options": s["options"], "noise": s["noise"], "mean": float(s["df"].mean()),
             "cpu": s["clock"].cpu, "wall": s["clock"].wall,
             "change_to_next": None} for s in ladder]}
        for name, opts in (("defaults", []), ("high", OURS_HIGH)):
            runs = [ours_df(d, room, opts, s) for s in (1, 2)]
            for s, (v, c) in zip((1, 2), runs):
                lines.append(row(f"ours {name} (`{' '.join(opts) or 'defaults'}`), seed {s}", v, ref, c))
            res[f"ours_{name}"] = {"options": " ".join(opts), "df": runs[0][0].tolist(),
                                   "errors": errors(runs[0][0], ref),
                                   "seed_noise": pair_noise(runs[0][0], runs[1][0]),
                                   "cpu": runs[0][1].cpu}
        result["daylight_factor"][room] = res
        lines.append("")
        print("\n".join(lines[-12:]), flush=True)

    text = "\n".join(lines)
    with open(os.path.join(d, "daylight.md"), "w") as f:
        f.write(text + "\n")
    with open(os.path.join(d, "daylight.json"), "w") as f:
        json.dump(result, f, indent=1)
    print(text)


if __name__ == "__main__":
    main()
