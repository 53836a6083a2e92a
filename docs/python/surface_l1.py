"""Per-surface accuracy of `radiosity solve` CSVs against a reference CSV of the same mesh.

    python3 docs/python/surface_l1.py reference.csv run.csv [run.csv ...]

For each run: the area-weighted L1 difference of the surfaces' mean radiosity over the
non-emitting input polygons, sum |A_s (B_run - B_ref)| / sum A_s B_ref (channels summed), its
signed counterpart, and the surfaces that contribute most. Standard library only.
"""
import collections
import csv
import sys


def load(path):
    surfaces = collections.defaultdict(lambda: [0.0, 0.0, 0.0])
    with open(path, newline="") as fh:
        for row in csv.DictReader(fh):
            area = float(row["area"])
            b = sum(float(row["radiosity_" + c]) for c in "rgb")
            e = sum(float(row["emission_" + c]) for c in "rgb")
            s = surfaces[row["surface"]]
            s[0] += area
            s[1] += area * b
            s[2] += e
    return surfaces


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    ref = load(sys.argv[1])
    for path in sys.argv[2:]:
        run = load(path)
        total = sum(v[1] for v in ref.values() if v[2] == 0)
        diffs = [(run[k][1] - v[1], k, v[0]) for k, v in ref.items() if v[2] == 0]
        l1 = sum(abs(d) for d, _, _ in diffs) / total
        signed = sum(d for d, _, _ in diffs) / total
        print(f"{path}: L1 {100 * l1:.3f} %, signed {100 * signed:+.3f} %")
        for d, k, area in sorted(diffs, key=lambda t: -abs(t[0]))[:5]:
            print(f"    surface {k} (area {area:.3g}): {100 * d / total:+.3f} % of the total")


if __name__ == "__main__":
    main()
