"""Solve the Cornell box with three solvers, plot their convergence (the eq. 22 error of
Gortler, Cohen & Slusallek 1993 against iterations in sweeps) and show the picture.

    pip install ./crates/radiosity-py matplotlib
    python docs/python/convergence.py [OUT_DIR]

Without a display (MPLBACKEND=Agg) the figures are written to OUT_DIR (default: .).
"""

import pathlib
import sys

import matplotlib

if "--show" not in sys.argv:
    matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import radiosity  # noqa: E402

out = pathlib.Path(next((a for a in sys.argv[1:] if not a.startswith("--")), "."))
out.mkdir(parents=True, exist_ok=True)

scene = radiosity.builtin("cornell")
fig, ax = plt.subplots(figsize=(7, 4.5))
last = None
for solver in ["gauss-seidel", "southwell", "progressive"]:
    s = radiosity.solve(scene, solver=solver, patches=1500, tolerance=1e-4, trace=True)
    t = s.trace
    n = s.radiosity.shape[0]
    ax.semilogy(t["iteration"] / n, t["error"], label=f"{solver} ({s.info['iterations']} iterations)")
    last = s
ax.set_xlabel("iterations / N (sweeps)")
ax.set_ylabel("error (eq. 22)")
ax.set_title("Cornell box, 1,500 patches")
ax.legend()
fig.tight_layout()
fig.savefig(out / "convergence.png", dpi=100)

image = last.render(256, 256)
# Expose like the CLI: the 97th percentile of luminance to 0.9, then the sRGB curve.
lum = image @ np.array([0.2126, 0.7152, 0.0722])
scale = 0.9 / max(np.percentile(lum, 97), 1e-12)
srgb = np.where(image * scale <= 0.0031308, 12.92 * image * scale, 1.055 * np.power(np.clip(image * scale, 0, None), 1 / 2.4) - 0.055)
fig2, ax2 = plt.subplots(figsize=(4, 4))
ax2.imshow(np.clip(srgb, 0, 1))
ax2.set_axis_off()
fig2.savefig(out / "cornell.png", dpi=100, bbox_inches="tight")
print(f"wrote {out / 'convergence.png'} and {out / 'cornell.png'}")
if "--show" in sys.argv:
    plt.show()
