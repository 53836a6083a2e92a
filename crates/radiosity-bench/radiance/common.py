"""Shared by the Radiance comparison's scripts: where Radiance and our binary are, running each
on a points file with its wall and CPU time, and the errors against a reference."""

import csv
import os
import resource
import subprocess
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", "..", ".."))

# Radiance's fixed luminous efficacy (lm/W) and its photometric weights of R, G, B
# (rayinit.cal's `luminance`; ../shared/data/radiance.md).
EFFICACY = 179.0
WEIGHTS = np.array([0.265, 0.670, 0.065])


def repo_shared():
    """../shared beside the repository (the main checkout's and the worktrees' sibling)."""
    for root in (REPO, os.path.dirname(REPO)):
        cand = os.path.join(os.path.dirname(root), "shared")
        if os.path.isdir(os.path.join(cand, "photometry")):
            return cand
    return os.path.join(os.path.dirname(REPO), "shared")


def radiance_env():
    """The environment for Radiance's programs from the `pyradiance` wheel: its bin/ on PATH,
    RAYPATH=.:<its lib/> (without it rtrace cannot find rayinit.cal)."""
    import pyradiance

    root = os.path.dirname(pyradiance.__file__)
    env = dict(os.environ)
    env["PATH"] = os.path.join(root, "bin") + os.pathsep + env.get("PATH", "")
    env["RAYPATH"] = os.pathsep.join([".", os.path.join(root, "lib")])
    return env


def radiosity_binary():
    """`radiosity` from $RADIOSITY, else $CARGO_TARGET_DIR/release, else target/release."""
    if os.environ.get("RADIOSITY"):
        return os.environ["RADIOSITY"]
    target = os.environ.get("CARGO_TARGET_DIR", os.path.join(REPO, "target"))
    return os.path.join(target, "release", "radiosity")


def read_pts(path):
    """A Radiance points file: an (n, 6) array of x y z dx dy dz."""
    pts = np.loadtxt(path, ndmin=2)
    if pts.shape[1] != 6:
        raise SystemExit(f"{path}: expected 6 numbers a line, found {pts.shape[1]}")
    return pts


class Clock:
    """Wall time and the CPU time (user + system) of the children waited for meanwhile."""

    def __enter__(self):
        self.t0 = time.perf_counter()
        r = resource.getrusage(resource.RUSAGE_CHILDREN)
        self.c0 = r.ru_utime + r.ru_stime
        return self

    def __exit__(self, *exc):
        self.wall = time.perf_counter() - self.t0
        r = resource.getrusage(resource.RUSAGE_CHILDREN)
        self.cpu = r.ru_utime + r.ru_stime - self.c0


def oconv(rad, octree, cwd):
    """Compile a Radiance scene into an octree."""
    with open(octree, "wb") as f:
        subprocess.run(["oconv", rad], cwd=cwd, stdout=f, check=True, env=radiance_env())


def rtrace_command(octree, options, nproc):
    return ["rtrace", "-I+", "-h", "-n", str(nproc)] + list(options) + [octree]


def rtrace(octree, pts, options, nproc=2, order=0, cwd=None):
    """Illuminance (lux) at each point from `rtrace -I+ -h [options]`, and the Clock.

    `order` ≠ 0 feeds the points in a seeded random order (and puts the answers back): rtrace
    has no seed, its ambient sampling follows the running ray count, so another order is another
    independent set of samples, which is how the reference's own noise is measured."""
    perm = np.arange(len(pts)) if order == 0 else np.random.default_rng(order).permutation(len(pts))
    text = "\n".join(" ".join(f"{v:.9g}" for v in p) for p in pts[perm]) + "\n"
    with Clock() as clock:
        res = subprocess.run(rtrace_command(octree, options, nproc), input=text.encode(),
                             capture_output=True, cwd=cwd, env=radiance_env())
    if res.returncode != 0:
        raise SystemExit(f"rtrace failed: {res.stderr.decode().strip()}")
    rgb = np.array([float(v) for v in res.stdout.split()]).reshape(-1, 3)
    if len(rgb) != len(pts):
        raise SystemExit(f"rtrace returned {len(rgb)} values for {len(pts)} points")
    lux = np.empty(len(pts))
    lux[perm] = EFFICACY * rgb @ WEIGHTS
    return lux, clock


def ours_command(scene, schedule, grid, out, options):
    return [radiosity_binary(), "lighting", scene, "--luminaires", schedule, "--grid", grid,
            "--out", out] + list(options)


def ours(scene, schedule, grid, options, cwd=None):
    """Illuminance (lux) at the grid's points from `radiosity lighting`, and the Clock."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "grid.csv")
        with Clock() as clock:
            res = subprocess.run(ours_command(scene, schedule, grid, out, options),
                                 capture_output=True, cwd=cwd)
        if res.returncode != 0:
            raise SystemExit(f"radiosity lighting failed: {res.stderr.decode().strip()}")
        with open(out) as f:
            lux = np.array([float(row["illuminance"]) for row in csv.DictReader(f)])
    return lux, clock


def errors(values, reference):
    """RMS and max of the relative error over the points, and the mean's relative error."""
    rel = values / reference - 1.0
    return {
        "rms": float(np.sqrt(np.mean(rel**2))),
        "max": float(np.max(np.abs(rel))),
        "mean": float(np.mean(values) / np.mean(reference) - 1.0),
    }

