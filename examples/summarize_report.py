#!/usr/bin/env python3
"""Prints the per-level summary of an ndfbake report.json: lobes per texel and the error of the
fitted lobes beside the naive normal map (plain MIP-mapping), a single vMF lobe and Toksvig, all against the exact effective BRDF."""
import json
import sys


def main(path):
    with open(path) as f:
        report = json.load(f)
    source = report["input"]
    print(f"{source['source']}: {source['width']}x{source['height']} {source['format']}, "
          f"BRDF {report['settings']['brdf']}, tolerance {report['settings']['tolerance']}")
    for assumption in source["assumptions"]:
        print(f"  assumed: {assumption}")
    repairs = report["repairs"]
    print("  repairs: " + ", ".join(f"{k} {repairs[k]}" for k in
                                    ("non_finite", "zero_length", "renormalized", "below_horizon")))
    print(f"{'level':>5} {'size':>11} {'mean lobes':>10} {'ndfbake':>8} {'naive':>8} {'1 vMF':>8} {'Toksvig':>8}")
    for level in report["levels"]:
        histogram = level["lobe_histogram"]
        texels = sum(histogram)
        mean_lobes = sum(k * n for k, n in enumerate(histogram)) / texels
        print(f"{level['level']:>5} {level['width']:>5}x{level['height']:<5} {mean_lobes:>10.2f} "
              f"{level['error']['mean']:>8.3f} {level['error_naive']['mean']:>8.3f} "
              f"{level['error_single_vmf']['mean']:>8.3f} "
              f"{level['error_toksvig']['mean']:>8.3f}")
    t = report["timings_seconds"]
    print(f"time: decode {t['decode']:.2f} s, fit {t['fit']:.2f} s, measure {t['measure']:.2f} s, "
          f"write {t['write']:.2f} s")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: summarize_report.py REPORT.json")
    main(sys.argv[1])
