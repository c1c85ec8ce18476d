#!/usr/bin/env python3
"""Draws `ndfbake bench` results: mean effective-BRDF error against build time, one point per
method, with the Pareto front (no other method both faster and more accurate) marked, for each
BRDF of the run. Usage: plot_bench.py BENCH.csv OUT.png [--map NAME]"""
import argparse
import csv
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(path, only_map):
    """(brdf → method → [seconds, error sum, count]) with build time summed over maps once."""
    table = defaultdict(lambda: defaultdict(lambda: [0.0, 0.0, 0]))
    seen_times = set()
    with open(path) as f:
        for row in csv.DictReader(f):
            if only_map and row["map"] != only_map:
                continue
            entry = table[row["brdf"]][row["method"]]
            if (row["brdf"], row["method"], row["map"]) not in seen_times:
                seen_times.add((row["brdf"], row["method"], row["map"]))
                entry[0] += float(row["build_seconds"])
            entry[1] += float(row["mean_error"])
            entry[2] += 1
    return table


def pareto(points):
    return {name for name, (t, e) in points.items()
            if not any(t2 < t and e2 < e for t2, e2 in points.values())}


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("csv")
    parser.add_argument("png")
    parser.add_argument("--map", default=None, help="only this map's rows")
    args = parser.parse_args()
    table = load(args.csv, args.map)
    if not table:
        with open(args.csv) as f:
            maps = sorted({row["map"] for row in csv.DictReader(f)})
        raise SystemExit("plot_bench.py: no rows%s in %s (its maps: %s)" % (
            " for map %r" % args.map if args.map else "", args.csv, ", ".join(maps) or "none"))
    fig, axes = plt.subplots(1, len(table), figsize=(6.5 * len(table), 5.5), squeeze=False)
    for ax, (brdf, methods) in zip(axes[0], sorted(table.items())):
        points = {m: (max(s, 1e-4), e / n) for m, (s, e, n) in methods.items()}
        front = pareto(points)
        for name, (t, e) in points.items():
            on_front = name in front
            ax.scatter(t, e, s=60 if on_front else 30, c="tab:red" if on_front else "tab:gray",
                       zorder=3 if on_front else 2)
            ax.annotate(name, (t, e), textcoords="offset points", xytext=(4, 3), fontsize=8,
                        fontweight="bold" if name == "bake-default" else "normal")
        ordered = sorted((points[n] for n in front))
        ax.plot([p[0] for p in ordered], [p[1] for p in ordered], c="tab:red", lw=1, zorder=1,
                label="Pareto front")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("build time of the whole pyramid (s, log)")
        ax.set_ylabel("mean relative effective-BRDF error (log)")
        ax.set_title(f"{brdf}" + (f" — {args.map}" if args.map else ""))
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(loc="upper right")
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)


if __name__ == "__main__":
    main()
