#!/usr/bin/env python3
"""A year of hourly illuminance at 1,000 points of window.py's glazed office: ours against
Radiance's 2-phase method (daylight coefficients), both against a converged reference.

The weather: an EPW file (--epw; docs/daylight-radiance.md names the one used), its dew point
set to 11 °C in every record (year.epw in DIR): gendaymtx and gendaylit read no dew point and
take precipitable water 2 cm, which is exp(0.07 × 11 − 0.075) in Perez' model, so all three
skies see the same atmosphere. `epw2wea` makes Radiance's year.wea from it.

- ours: `radiosity lighting office.obj --glazing glass=0.8 --weather year.epw --grid annual.pts
  --annual annual.csv --hourly hourly.npy` (Tregenza's 145 patches + the ground, the Perez sky,
  the sun at its true position unless `--sun-method patch`).
- Radiance 2-phase: `gendaymtx -m 1 -of year.wea > sky.mtx` (146 rows: the ground, then the 145
  Reinhart MF:1 patches; the sun spread over its nearest patches), `rfluxmtx -I+ -y 1000 -ab AB
  -ad AD -lw LW -faf - skyrf.rad office.rad < annual.pts > dc.mtx` (skyrf.rad: the ground glow
  `h=u`, the sky glow `h=r1 u=+Y`), `dctimestep -of dc.mtx sky.mtx > ill.mtx`; lux = 179 ×
  (0.265 R + 0.670 G + 0.065 B).
- The reference: for --hours occupied lit hours drawn at random (seeded) and 100 of the 1,000
  points (a 10 × 10 subset), `gendaylit M D H-0.5 -a LAT -o −LON -m −15·ZONE -W DNI DHI -g 0.2`
  (the Perez sky's shape and the sun as a 0.533° source at its true position), renormalised
  (`renormalised`: the sky's horizontal illuminance exactly DHI × Perez' diffuse efficacy and the
  ground ρ_g (E_d + E_n sin α)/π, as gendaymtx and ours define them; gendaylit's own differ), its
  perezlum.cal swapped for perezsharp.cal (the same function without the blend across the
  horizon, as the patch skies have none), then `rtrace -I+ -h -ab 8 -aa 0 -ad 4096 -lw 1e-6
  -dj 0 -dt 0 -dc 1` each hour; the first --noise-hours hours run twice (points in two orders)
  for its noise.

The error of each year against the reference over the sampled hours × points: RMSE (lx), that
RMSE relative to the reference's mean, and the mean bias. Time: every setting runs --reps times,
interleaved in a seeded random order a round, CPU seconds (user + system of the children) and
wall; the load average is printed before and after.

`--sky-check` instead compares the skies alone at an open point (`sky_check`), writing
DIR/sky-check.md. Writes DIR/annual.json and DIR/annual.md.
Usage: annual.py --dir DIR --epw FILE [--reps 2] [--hours 48] [--sky-check]
"""

import argparse
import json
import os
import subprocess

import numpy as np

from common import Clock, EFFICACY, WEIGHTS, radiance_env, radiosity_binary, read_pts

SKYRF = """#@rfluxmtx h=u
void glow groundglow 0 0 4 1 1 1 0
groundglow source ground 0 0 4 0 0 -1 180
#@rfluxmtx h=r1 u=+Y
void glow skyglow 0 0 4 1 1 1 0
skyglow source skydome 0 0 4 0 0 1 180
"""
SOURCES = """skyfunc glow skyglow 0 0 4 1 1 1 0
skyglow source sky 0 0 4 0 0 1 180
skyfunc glow groundglow 0 0 4 1 1 1 0
groundglow source ground 0 0 4 0 0 -1 180
"""
# rfluxmtx settings: (-ab, -ad, -lw).
TWO_PHASE = [(4, 1024, 1e-3), (6, 4096, 2.5e-4), (8, 16384, 6e-5)]
# Ours: the default set; `--ours` replaces it ("A;B": settings separated by semicolons).
OURS = ["", "--patches 300 --sky-rays 8192 --sky-refine 4", "--patches 600 --sky-rays 8192 --sky-refine 4",
        "--patches 600 --sky-rays 1024", "--sun-method patch"]
# The sampled hours split by the direct normal irradiance: the sun's discretisation (in its
# patch, or over its nearest patches) dominates the error where there is direct sun.
SUNLESS = 50.0  # W/m²
REFERENCE = ["-ab", "8", "-aa", "0", "-ad", "4096", "-lw", "1e-6", "-dj", "0", "-dt", "0",
             "-dc", "1"]


def run(cmd, cwd, stdin=None, stdout=None):
    res = subprocess.run(cmd, cwd=cwd, stdin=stdin, stdout=stdout or subprocess.PIPE,
                         stderr=subprocess.PIPE, env=radiance_env())
    if res.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed: {res.stderr.decode().strip()}")
    return res


def write_inputs(d, epw):
    """year.epw (dew point 11 °C), year.wea, skyrf.rad, perezsharp.cal; the site."""
    with open(epw) as f:
        lines = f.read().splitlines()
    loc = lines[0].split(",")
    site = {"city": loc[1], "lat": float(loc[6]), "lon": float(loc[7]), "zone": float(loc[8])}
    records = []
    with open(os.path.join(d, "year.epw"), "w") as f:
        for k, line in enumerate(lines):
            if k >= 8 and line.strip():
                fields = line.split(",")
                fields[7] = "11.0"
                records.append((int(fields[1]), int(fields[2]), int(fields[3]),
                                float(fields[14]), float(fields[15])))
                line = ",".join(fields)
            f.write(line + "\n")
    run(["epw2wea", "year.epw", "year.wea"], d)
    with open(os.path.join(d, "skyrf.rad"), "w") as f:
        f.write(SKYRF)
    root = os.path.dirname(radiance_env()["RAYPATH"].split(os.pathsep)[1] + "/")
    with open(os.path.join(root, "perezlum.cal")) as f:
        cal = f.read()
    blend = "skybright = wmean((Dz+1.01)^10, intersky, (Dz+1.01)^-10, A2 );"
    assert blend in cal, "perezlum.cal changed: its horizon blend not found"
    with open(os.path.join(d, "perezsharp.cal"), "w") as f:
        f.write("{ perezlum.cal without the blend of sky and ground across the horizon }\n"
                + cal.replace(blend, "skybright = if(Dz, intersky, A2);"))
    return site, records


def ours_year(d, options):
    cmd = [radiosity_binary(), "lighting", "office.obj", "--glazing", "glass=0.8", "--weather",
           "year.epw", "--grid", "annual.pts", "--annual", "annual.csv", "--hourly",
           "hourly.npy"] + options
    with Clock() as clock:
        run(cmd, d)
    return clock, " ".join(cmd[1:])


def read_ours(d):
    """Hourly lux, (hours, points): the float32 matrix `--hourly hourly.npy` writes."""
    return np.load(os.path.join(d, "hourly.npy")).astype(float)


def two_phase_year(d, ab, ad, lw, npts):
    cmds = [["gendaymtx", "-m", "1", "-of", "year.wea"],
            ["rfluxmtx", "-I+", "-y", str(npts), "-n", "2", "-ab", str(ab), "-ad", str(ad),
             "-lw", f"{lw:g}", "-faf", "-", "skyrf.rad", "office.rad"],
            ["dctimestep", "-of", "dc.mtx", "sky.mtx"]]
    with Clock() as clock:
        with open(os.path.join(d, "sky.mtx"), "wb") as f:
            run(cmds[0], d, stdout=f)
        with open(os.path.join(d, "annual.pts"), "rb") as i, \
                open(os.path.join(d, "dc.mtx"), "wb") as f:
            run(cmds[1], d, stdin=i, stdout=f)
        with open(os.path.join(d, "ill.mtx"), "wb") as f:
            run(cmds[2], d, stdout=f)
    text = " | ".join(" ".join(c) for c in cmds)
    return clock, text


def read_mtx(path):
    """A Radiance float matrix (header, then rows × cols × 3 floats): lux, (rows, cols)."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"\n\n") + 2
    head = dict(line.split("=", 1) for line in data[:end].decode().split("\n") if "=" in line)
    rows, cols = int(head["NROWS"]), int(head["NCOLS"])
    rgb = np.frombuffer(data[end:], dtype="<f4").reshape(rows, cols, 3)
    return EFFICACY * rgb @ WEIGHTS


# Perez, Ineichen, Seals, Michalsky & Stewart (1990), table 4: the diffuse luminous efficacy
# a + b W + c cos Z + d ln Δ (lm/W) per clearness bin (as gendaylit's glob_h_diffuse_effi_PEREZ).
BINS = [1.065, 1.230, 1.500, 1.950, 2.800, 4.500, 6.200]
DIFFUSE_EFFICACY = [(97.24, -0.46, 12.00, -8.91), (107.22, 1.15, 0.59, -3.95),
                    (104.97, 2.96, -5.53, -8.77), (102.39, 5.59, -13.95, -13.90),
                    (100.71, 5.94, -22.75, -23.74), (106.42, 3.83, -36.15, -28.83),
                    (141.88, 1.90, -53.24, -14.03), (152.23, 0.35, -45.27, -7.98)]
WATER = 2.0  # cm, gendaylit's precipitable water (= the 11 °C dew point of year.epw)
SUN_SOLID_ANGLE = 2 * np.pi * (1 - np.cos(np.radians(0.533 / 2)))


def perez_shape(coef, sun, mu, phi):
    """perezlum.cal's relative luminance at cos ζ = mu, azimuth phi (x east, y north)."""
    a, b, c, d, e = coef
    sz = np.sqrt(np.maximum(0.0, 1 - mu**2))
    dirs = np.stack([sz * np.sin(phi), sz * np.cos(phi), mu])
    cosg = np.clip(np.tensordot(sun, dirs, axes=1), -1, 1)
    g = np.arccos(cosg)
    return (1 + a * np.exp(b / np.maximum(mu, 0.01))) * (1 + c * np.exp(d * g) + e * cosg**2)


def renormalised(sky, dhi):
    """gendaylit's sky with the issue's (and gendaymtx's, and ours') normalisation: the sky's
    horizontal illuminance exactly E_d = DHI × Perez' diffuse efficacy (gendaylit sums the
    shape over 145 directions with equal weights instead), and the ground ρ_g (E_d + E_n sin
    α)/π (gendaylit derives it from the zenith luminance with CIE sky ratios). The integral:
    the midpoint rule on 1,500 × 3,000 cells uniform in cos ζ and azimuth."""
    head = [l for l in sky.splitlines() if l.startswith("#")]
    eps, delta = (float(v) for v in next(l for l in head if "epsilon" in l).split(":")[1].split()[:2])
    lines = sky.splitlines()
    k = next(i for i, l in enumerate(lines) if l.startswith("10 "))
    args = [float(v) for v in lines[k].split()[1:]]
    coef, sun = args[2:7], np.array(args[7:10])
    en = 0.0
    if "void light solar" in sky:
        j = lines.index("void light solar")
        en = float(lines[j + 3].split()[1]) * EFFICACY * SUN_SOLID_ANGLE
    zen = np.arccos(np.clip(sun[2], -1, 1))
    a, b, c, dd = DIFFUSE_EFFICACY[int(np.searchsorted(BINS, eps, side="right"))]
    ed = dhi * (a + b * WATER + c * np.cos(zen) + dd * np.log(delta))
    n = 1500
    mu = (np.arange(n) + 0.5) / n
    phi = (np.arange(2 * n) + 0.5) * np.pi / n
    m, p = np.meshgrid(mu, phi, indexing="ij")
    integral = float(np.sum(perez_shape(coef, sun, m.ravel(), p.ravel()) * m.ravel())) \
        * (1.0 / n) * (np.pi / n)
    a1 = ed / integral / EFFICACY
    a2 = 0.2 * (ed + en * max(sun[2], 0.0)) / np.pi / EFFICACY
    lines[k] = "10 " + " ".join(f"{v:.9g}" for v in [a1, a2] + args[2:])
    return "\n".join(lines) + "\n"


def reference(d, site, records, hours, ref_idx, pts, noise_hours, nproc):
    """rtrace per sampled hour (cached in DIR/ref/): (hours, ref points) lux, the noise."""
    os.makedirs(os.path.join(d, "ref"), exist_ok=True)
    sub = pts[ref_idx]
    out, noise, cpu, skipped = [], [], 0.0, []
    for n, h in enumerate(hours):
        m, day, hr, dni, dhi = records[h]
        path = os.path.join(d, "ref", f"h{h}.npz")
        if os.path.exists(path):
            z = np.load(path)
            out.append(z["a"] if z["b"].size == 0 else 0.5 * (z["a"] + z["b"]))
            if z["b"].size:
                noise.append(z["b"] / np.maximum(z["a"], 1e-9))
            cpu += float(z["cpu"])
            continue
        sky = run(["gendaylit", str(m), str(day), f"{hr - 0.5:g}", "-a", f"{site['lat']}",
                   "-o", f"{-site['lon']}", "-m", f"{-15 * site['zone']:g}", "-W", f"{dni:g}",
                   f"{dhi:g}", "-g", "0.2"], d).stdout.decode()
        if "epsilon" not in sky:  # the sun below the horizon at mid-hour: an error sky
            print(f"reference: {m}/{day} {hr}:00 left out: gendaylit's sun is below the horizon")
            skipped.append(n)
            continue
        sky = renormalised(sky, dhi).replace("perezlum.cal", "perezsharp.cal")
        with open(os.path.join(d, "ref", f"h{h}.rad"), "w") as f:
            f.write(sky + SOURCES)
        octree = os.path.join(d, "ref", f"h{h}.oct")
        with open(octree, "wb") as f:
            run(["oconv", "office.rad", f"ref/h{h}.rad"], d, stdout=f)
        runs = []
        for order in ((1, 2) if n < noise_hours else (1,)):
            perm = np.random.default_rng(order).permutation(len(sub))
            t = "\n".join(" ".join(f"{v:.9g}" for v in p) for p in sub[perm]) + "\n"
            with Clock() as c:
                res = subprocess.run(["rtrace", "-I+", "-h", "-n", str(nproc)] + REFERENCE
                                     + [octree], input=t.encode(), capture_output=True, cwd=d,
                                     env=radiance_env())
            if res.returncode != 0:
                raise SystemExit(f"rtrace failed: {res.stderr.decode().strip()}")
            rgb = np.array([float(v) for v in res.stdout.split()]).reshape(-1, 3)
            lux = np.empty(len(sub))
            lux[perm] = EFFICACY * rgb @ WEIGHTS
            runs.append(lux)
            cpu += c.cpu
        a = runs[0]
        b = runs[1] if len(runs) > 1 else np.array([])
        np.savez(path, a=a, b=b, cpu=c.cpu * len(runs))
        os.remove(octree)
        out.append(a if b.size == 0 else 0.5 * (a + b))
        if b.size:
            noise.append(b / np.maximum(a, 1e-9))
        print(f"reference hour {n + 1}/{len(hours)}: {m}/{day} {hr}:00, DNI {dni:g}, DHI "
              f"{dhi:g}: mean {out[-1].mean():.1f} lx", flush=True)
    return np.array(out), noise, cpu, skipped


def sky_check(d, site, records, hours):
    """The skies at an open point (sensors facing up, south, north, east, 1 cm above a tiny
    black polygon 100 m away): ours (`--sky-rays 262144`) against rtrace -ab 1 under the
    renormalised reference sky, for the sampled hours with DNI < SUNLESS (their weak sun
    included: ours in its patch, rtrace's at its position)."""
    root = os.path.join(d, "sky-check")
    os.makedirs(root, exist_ok=True)
    quad = "v 100 100 -100\nv 100.001 100 -100\nv 100.001 100.001 -100\nv 100 100.001 -100\n"
    with open(os.path.join(root, "far.obj"), "w") as f:
        f.write("mtllib far.mtl\nusemtl black\n" + quad + "f 1 2 3 4\n")
    with open(os.path.join(root, "far.mtl"), "w") as f:
        f.write("newmtl black\nKd 0 0 0\n")
    with open(os.path.join(root, "far.rad"), "w") as f:
        f.write("void plastic black 0 0 5 0 0 0 0 0\nblack polygon tiny 0 0 9 "
                "100 100 -100 100.001 100 -100 100 100.001 -100\n")
    sensors = "0 0 0.01 0 0 1\n0 0 0.01 0 -1 0\n0 0 0.01 0 1 0\n0 0 0.01 1 0 0\n"
    with open(os.path.join(root, "p.pts"), "w") as f:
        f.write(sensors)
    run([radiosity_binary(), "lighting", "far.obj", "--weather", "../year.epw", "--grid",
         "p.pts", "--annual", "a.csv", "--hourly", "h.csv", "--sky-rays", "262144"], root)
    with open(os.path.join(root, "h.csv")) as f:
        f.readline()
        ours = [np.array(line.split(",")[3:], dtype=float) for line in f]
    env = radiance_env()
    env["RAYPATH"] += os.pathsep + d  # perezsharp.cal
    lines = ["| hour | DHI W/m² | rtrace: up, south, north, east (lx) | ours / rtrace |",
             "|---|---|---|---|"]
    worst = 0.0
    for h in hours:
        m, day, hr, dni, dhi = records[h]
        if dni >= SUNLESS:
            continue
        sky = run(["gendaylit", str(m), str(day), f"{hr - 0.5:g}", "-a", f"{site['lat']}",
                   "-o", f"{-site['lon']}", "-m", f"{-15 * site['zone']:g}", "-W", f"{dni:g}",
                   f"{dhi:g}", "-g", "0.2"], d).stdout.decode()
        if "epsilon" not in sky:
            continue
        sky = renormalised(sky, dhi).replace("perezlum.cal", "perezsharp.cal")
        with open(os.path.join(root, "s.rad"), "w") as f:
            f.write(sky + SOURCES)
        with open(os.path.join(root, "s.oct"), "wb") as f:
            subprocess.run(["oconv", "far.rad", "s.rad"], cwd=root, stdout=f, check=True, env=env)
        res = subprocess.run(["rtrace", "-I+", "-h", "-ab", "1", "-aa", "0", "-ad", "65536",
                              "-lw", "1e-7", "s.oct"], input=sensors.encode(),
                             capture_output=True, cwd=root, env=env, check=True)
        rad = EFFICACY * np.array(res.stdout.split(), dtype=float).reshape(-1, 3) @ WEIGHTS
        ratio = ours[h] / rad
        worst = max(worst, float(np.max(np.abs(ratio - 1))))
        lines.append(f"| {m}/{day} {hr}:00 (DNI {dni:g}) | {dhi:g} | "
                     + ", ".join(f"{v:.0f}" for v in rad) + " | "
                     + ", ".join(f"{v:.3f}" for v in ratio) + " |")
    lines.append(f"\nworst |ours/rtrace − 1| {100 * worst:.2f} %")
    return "\n".join(lines)


def tregenza_solid_angles():
    """The solid angle of each of the 146 rows of `gendaymtx -m 1`: the ground (2π), then
    Tregenza's bands of 12° (30, 30, 24, 24, 18, 12, 6 patches) and the 6° cap."""
    out = [2 * np.pi]
    for band, n in enumerate((30, 30, 24, 24, 18, 12, 6)):
        lo, hi = np.radians(12 * band), np.radians(12 * (band + 1))
        out += [2 * np.pi * (np.sin(hi) - np.sin(lo)) / n] * n
    out.append(2 * np.pi * (1 - np.sin(np.radians(84))))
    return np.array(out)


def tregenza_horizontal():
    """∫ sin θ dω over each row of `gendaymtx -m 1` (θ the altitude): what an unobstructed
    horizontal surface receives from the patch at unit luminance (the ground: 0)."""
    out = [0.0]
    for band, n in enumerate((30, 30, 24, 24, 18, 12, 6)):
        lo, hi = np.radians(12 * band), np.radians(12 * (band + 1))
        out += [np.pi * (np.sin(hi) ** 2 - np.sin(lo) ** 2) / n] * n
    out.append(np.pi * np.cos(np.radians(84)) ** 2)
    return np.array(out)


def sun_study(d, records, hours, ref, ref_idx):
    """The sun's share of the error on the sunny hours: one daylight matrix (rfluxmtx at
    TWO_PHASE[-1]) under two skies, gendaymtx's own (the sun over its 4 nearest patches) and
    the same with the sun put whole into its nearest patch (`gendaymtx -d`'s sun moved there,
    its normal illuminance kept, as `gendaymtx -5` places it), and the same patch with its
    horizontal illuminance kept instead, E_n sin α / ∫_p sin θ dω (ours' rule; α from the
    reference's gendaylit sun). Returns the RMSE (lx) of each against the reference over the
    hours with DNI ≥ SUNLESS."""
    ab, ad, lw = TWO_PHASE[-1]
    two_phase_year(d, ab, ad, lw, 1000)
    dc = read_mtx(os.path.join(d, "dc.mtx"))[ref_idx] / EFFICACY  # lux per (W/m²/sr)
    skies = {}
    for name, flag in (("sky", "-s"), ("sun", "-d")):
        with open(os.path.join(d, f"sky{flag}.mtx"), "wb") as f:
            run(["gendaymtx", "-m", "1", flag, "-of", "year.wea"], d, stdout=f)
        skies[name] = read_mtx(os.path.join(d, f"sky{flag}.mtx")) / EFFICACY
    omega = tregenza_solid_angles()
    spread = skies["sun"][:, hours]
    energy = spread * omega[:, None]
    one = np.zeros_like(spread)
    cols = np.arange(len(hours))
    near = np.argmax(energy, axis=0)
    one[near, cols] = energy.sum(axis=0) / omega[near]  # 0 where there is no sun
    sin_alt = np.empty(len(hours))
    for k, h in enumerate(hours):
        with open(os.path.join(d, "ref", f"h{h}.rad")) as f:
            arg = next(line for line in f if line.startswith("10 "))
        sin_alt[k] = max(float(arg.split()[10]), 0.0)
    ours_rule = np.zeros_like(spread)
    lit = energy.sum(axis=0) > 0
    ours_rule[near[lit], cols[lit]] = (energy.sum(axis=0) * sin_alt)[lit] \
        / tregenza_horizontal()[near[lit]]
    sunny = np.array([records[h][3] >= SUNLESS for h in hours])
    out = {}
    for name, sun in (("4 nearest patches (gendaymtx)", spread), ("its nearest patch", one),
                      ("its nearest patch, horizontal kept", ours_rule)):
        year = EFFICACY * (dc @ (skies["sky"][:, hours] + sun)).T
        diff = (year - ref)[sunny]
        out[name] = float(np.sqrt(np.mean(diff**2)))
    return out


def agreement(year, ref, hours, ref_idx, records):
    """RMSE (lx), relative RMSE (of the reference's mean), mean bias over hours × points: all
    sampled hours, those with DNI < SUNLESS (the sky alone, nearly) and the others."""
    got = year[np.ix_(hours, ref_idx)]
    sunless = np.array([records[h][3] < SUNLESS for h in hours])
    out = {}
    for key, mask in (("all", np.ones(len(hours), bool)), ("sunless", sunless),
                      ("sun", ~sunless)):
        diff = got[mask] - ref[mask]
        rmse = float(np.sqrt(np.mean(diff**2)))
        out[key] = {"hours": int(mask.sum()), "rmse": rmse,
                    "rel_rmse": rmse / float(ref[mask].mean()),
                    "bias": float(diff.mean() / ref[mask].mean())}
    return out


def load():
    return os.getloadavg()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dir", required=True)
    ap.add_argument("--epw", required=True)
    ap.add_argument("--hours", type=int, default=48)
    ap.add_argument("--noise-hours", type=int, default=4)
    ap.add_argument("--reps", type=int, default=2)
    ap.add_argument("--nproc", type=int, default=2)
    ap.add_argument("--ours", help="our settings, separated by ';' (empty: the defaults); "
                    "default: " + "; ".join(o or "(defaults)" for o in OURS))
    ap.add_argument("--two-phase", default="all", choices=["all", "none"],
                    help="run Radiance's 2-phase years too (all three settings) or not")
    ap.add_argument("--two-phase-settings",
                    help="the 2-phase runs' rfluxmtx settings as 'AB,AD,LW' separated by ';' "
                    "(default: " + "; ".join(f"{ab},{ad},{lw:g}" for ab, ad, lw in TWO_PHASE) + ")")
    ap.add_argument("--sun-study", action="store_true",
                    help="also the sun's share of the error on Radiance's matrix (one more "
                    "rfluxmtx -ab 8 -ad 16384 run)")
    ap.add_argument("--sky-check", action="store_true",
                    help="only the skies at an open point, ours against the reference sky")
    args = ap.parse_args()
    d = os.path.abspath(args.dir)
    pts = read_pts(os.path.join(d, "annual.pts"))
    site, records = write_inputs(d, args.epw)
    # The 10 × 10 reference points: columns 2, 6, …, 38 of 40 and 10 of the 25 rows.
    rows = np.round(np.linspace(1, 23, 10)).astype(int)
    ref_idx = np.array([r * 40 + c for r in rows for c in range(2, 40, 4)])
    occupied = [k for k, (_, _, hr, dni, dhi) in enumerate(records) if 9 <= hr <= 18 and dhi > 0]
    hours = np.sort(np.random.default_rng(58).choice(occupied, args.hours, replace=False))

    # The years, side by side.
    ours_sets = OURS if args.ours is None else [o.strip() for o in args.ours.split(";")]
    settings = [("ours " + (o or "defaults"), "ours", o.split()) for o in ours_sets]
    two_phase = TWO_PHASE if args.two_phase_settings is None else [
        (int(ab), int(ad), float(lw))
        for ab, ad, lw in (s.split(",") for s in args.two_phase_settings.split(";"))]
    if args.two_phase == "all":
        settings += [(f"2-phase -ab {ab} -ad {ad} -lw {lw:g}", "2phase", (ab, ad, lw))
                     for ab, ad, lw in two_phase]
    times = {name: [] for name, _, _ in settings}
    commands, errs = {}, {}
    if args.sky_check:
        text = sky_check(d, site, records, hours)
        with open(os.path.join(d, "sky-check.md"), "w") as f:
            f.write(text + "\n")
        print(text)
        return
    ref, noise, ref_cpu, skipped = reference(d, site, records, hours, ref_idx, pts,
                                             args.noise_hours, args.nproc)
    hours = np.delete(hours, skipped)
    load0 = load()
    for rep in range(1, args.reps + 1):
        for k in np.random.default_rng(rep).permutation(len(settings)):
            name, side, opts = settings[k]
            if side == "ours":
                clock, commands[name] = ours_year(d, opts)
            else:
                clock, commands[name] = two_phase_year(d, *opts, len(pts))
            times[name].append({"cpu": clock.cpu, "wall": clock.wall})
            print(f"round {rep}: {name}: {clock.cpu:.2f} CPU-s, {clock.wall:.2f} s wall",
                  flush=True)
            if rep == 1:
                year = read_ours(d) if side == "ours" else read_mtx(os.path.join(d, "ill.mtx")).T
                errs[name] = agreement(year, ref, hours, ref_idx, records)
    load1 = load()
    study = sun_study(d, records, hours, ref, ref_idx) if args.sun_study else {}
    noise_rel = float(np.sqrt(np.mean([np.mean((n - 1) ** 2) for n in noise])) / np.sqrt(2)) \
        if noise else None

    lines = [f"Weather: {site['city']} ({site['lat']}° N, {site['lon']}° E, zone {site['zone']:g} h), "
             f"dew point set to 11 °C; {len(occupied)} occupied lit hours, {len(hours)} drawn "
             f"for the reference; {len(ref_idx)} reference points of {len(pts)}.",
             f"Reference: `gendaylit … | rtrace -I+ -h -n {args.nproc} {' '.join(REFERENCE)}` per hour "
             f"(perezsharp.cal), {ref_cpu:.0f} CPU-s in all; per-point noise of a two-run "
             f"average {100 * noise_rel:.2f} % (first {args.noise_hours} hours run twice)"
             if noise_rel is not None else "",
             f"Reference mean {ref.mean():.1f} lx over the sampled hours and points; "
             f"{errs[settings[0][0]]['sunless']['hours']} of the hours have DNI < {SUNLESS:g} W/m².",
             f"Load average (1, 5, 15 min) before {load0[0]:.1f} {load0[1]:.1f} {load0[2]:.1f}, "
             f"after {load1[0]:.1f} {load1[1]:.1f} {load1[2]:.1f}.", "",
             "| year | CPU s (median) | wall s | RMSE lx, all sampled hours | / mean | bias "
             f"| RMSE, DNI < {SUNLESS:g} W/m² | / mean | bias | RMSE, DNI ≥ {SUNLESS:g} | / mean | bias |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for name, _, _ in settings:
        cpu = float(np.median([t["cpu"] for t in times[name]]))
        wall = float(np.median([t["wall"] for t in times[name]]))
        cells = "".join(f" {e['rmse']:.1f} | {100 * e['rel_rmse']:.2f} % | "
                        f"{100 * e['bias']:+.2f} % |" for e in (errs[name][k] for k in
                                                                ("all", "sunless", "sun")))
        lines.append(f"| {name} | {cpu:.2f} | {wall:.2f} |" + cells)
    lines.append("")
    if study:
        lines.append(f"The sun's share (one daylight matrix, rfluxmtx -ab {TWO_PHASE[-1][0]} -ad "
                 f"{TWO_PHASE[-1][1]}; RMSE over the hours with DNI ≥ {SUNLESS:g} W/m²): "
                     + "; ".join(f"the sun in {k}: {v:.0f} lx" for k, v in study.items()))
        lines.append("")
    lines += [f"- {name}: `{cmd}`" for name, cmd in commands.items()]
    text = "\n".join(lines)
    with open(os.path.join(d, "annual.md"), "w") as f:
        f.write(text + "\n")
    with open(os.path.join(d, "annual.json"), "w") as f:
        json.dump({"times": times, "errors": errs, "sun_study": study, "commands": commands, "load": [load0, load1],
                   "hours": hours.tolist(), "ref_points": ref_idx.tolist(),
                   "reference_noise": noise_rel}, f, indent=1)
    print(text)


if __name__ == "__main__":
    main()
