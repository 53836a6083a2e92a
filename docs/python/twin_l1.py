"""Per-surface accuracy of `radiosity solve` CSVs against path-traced surface means, with
coincident twins (the same polygon twice, same side) scored as one surface.

    python3 docs/python/twin_l1.py surfaces.csv run.csv [run.csv ...] [--one]

`surfaces.csv` is the reference `radiosity bench --hierarchical` writes
(`surface,b_r,b_g,b_b,se_r,se_g,se_b`); it lights every twin as the surface. A shooting or
gathering method lights whichever twin each ray meets first and leaves the other dark there,
so by default a twin group's radiosity is the *sum* of its members' means; with `--one`
(hierarchical radiosity, which lights every twin) it is their largest. Twins are found from the
run CSV: same area-weighted centre (1 cm), same normal (0.1) and same area (1e-3). Emitters are
left out. Prints the area-weighted L1 over the groups and its signed counterpart. Standard
library only.
"""
import collections
import csv
import sys


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    one = "--one" in sys.argv[1:]
    if len(args) < 2:
        sys.exit(__doc__)
    ref = {}
    with open(args[0], newline="") as fh:
        for r in csv.DictReader(fh):
            ref[int(r["surface"])] = sum(float(r["b_" + c]) for c in "rgb")
    for path in args[1:]:
        s = collections.defaultdict(lambda: [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, None])
        with open(path, newline="") as fh:
            for r in csv.DictReader(fh):
                a = float(r["area"])
                x = s[int(r["surface"])]
                x[0] += a
                x[1] += a * sum(float(r["radiosity_" + c]) for c in "rgb")
                x[2] += sum(float(r["emission_" + c]) for c in "rgb")
                for i, k in enumerate(("cx", "cy", "cz")):
                    x[3 + i] += a * float(r[k])
                x[6] = tuple(round(float(r[k]), 1) for k in ("nx", "ny", "nz"))
        groups = collections.defaultdict(list)
        for k, x in s.items():
            if x[2] > 0:
                continue
            centre = tuple(round(x[3 + i] / x[0], 2) for i in range(3))
            groups[(centre, x[6], round(x[0], 3))].append(k)
        total = l1 = signed = 0.0
        for ks in groups.values():
            area = s[ks[0]][0]
            means = [s[k][1] / s[k][0] for k in ks]
            run = max(means) if one else sum(means)
            b = sum(ref[k] for k in ks) / len(ks)
            total += area * b
            l1 += area * abs(run - b)
            signed += area * (run - b)
        print(f"{path}: L1 {100 * l1 / total:.2f} %, signed {100 * signed / total:+.2f} %")


if __name__ == "__main__":
    main()
