"""The grazing study's run: main() parses the command line, fits one constant per family, and writes
DIR/report.md (every table), DIR/fit.json and DIR/lobes.json. Calls every other module of
studies/grazing/; called by studies/grazing_fit.py."""
import argparse
import json
import os
import time

import numpy as np

from . import __doc__ as STUDY_DOC
from .correction import make_correction
from .fit import FarGround, aggregate, finite_check, furnace_check, lobe_summary, lobe_table, objective
from .lighting import Lighting
from .texels import BASE_ALPHA, FAR_AZIMUTHS, FAR_THETAS


def fmt(x):
    return "%.2f" % x


def main(argv=None):
    ap = argparse.ArgumentParser(description=STUDY_DOC.split("\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--quick", action="store_true", help="skip the single-lobe table")
    ap.add_argument("--alpha", type=float, default=BASE_ALPHA,
                    help="the material's GGX α for the far ground (default 0.04: roughness 0.2)")
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    report = []

    def log(*a):
        s = " ".join(str(x) for x in a)
        print(s, flush=True)
        report.append(s)

    t0 = time.time()
    lighting = Lighting()
    worlds = lighting.names
    keys = worlds + ["furnace", "horizon", "overhead"]
    far = FarGround(lighting, alpha=args.alpha, log=log)
    log("far ground at α = %g (roughness %.3g)" % (args.alpha, np.sqrt(args.alpha)))

    # Fit: one constant per family on the far-ground objective.
    fits = {}
    for kind, grid in (("iso", (1.0, 2.0, 3.0, 4.0, 6.0, 8.0)), ("aniso", (0.25, 0.5, 1.0, 2.0))):
        scores = []
        for c in grid:
            res = far.evaluate(make_correction(kind, c))
            scores.append((objective(res, worlds), c))
            log("fit %s c=%g objective %.4f" % (kind, c, scores[-1][0]))
        fits[kind] = min(scores)[1]
    log("fitted: iso c=%g, aniso c=%g" % (fits["iso"], fits["aniso"]))

    corrs = {"none": None, "eevee_rule": make_correction("iso", 1.0),
             "iso": make_correction("iso", fits["iso"]), "aniso": make_correction("aniso", fits["aniso"])}
    results = {name: far.evaluate(corr) for name, corr in corrs.items()}

    # Far-ground table per world.
    lines = ["| light | " + " | ".join(corrs) + " |", "|---|" + "---:|" * len(corrs)]
    aggs = {name: aggregate(res, keys) for name, res in results.items()}
    for k in keys:
        lines.append("| %s | " % k + " | ".join(fmt(aggs[n][k]) for n in corrs) + " |")
    within = {n: sum(abs(np.log(aggs[n][w])) < np.log(1.1) for w in worlds) for n in corrs}
    lines.append("| worlds within 10% | " + " | ".join("%d/8" % within[n] for n in corrs) + " |")
    log("\n## Far ground (all texels, θv %s, sun azimuths %s): closure / map\n" % (FAR_THETAS, FAR_AZIMUTHS))
    log("\n".join(lines))

    # Per θv.
    for n in corrs:
        log("\n### %s: far ground per view angle (closure / map)\n" % n)
        log("| θv | " + " | ".join(k for k in keys) + " |")
        log("|---:|" + "---:|" * len(keys))
        for th in FAR_THETAS:
            a = aggregate(results[n], keys, lambda name, t, th=th: t == th)
            log("| %g | " % th + " | ".join(fmt(a[k]) for k in keys) + " |")
    # Per texel.
    for n in ("none", "iso", "aniso"):
        log("\n### %s: per texel (all θv, azimuths)\n" % n)
        log("| texel | " + " | ".join(keys) + " |")
        log("|---|" + "---:|" * len(keys))
        for name, _ in far.texels:
            a = aggregate(results[n], keys, lambda nm, t, name=name: nm == name)
            log("| %s | " % name + " | ".join(fmt(a[k]) for k in keys) + " |")

    # Furnace.
    log("\n## White furnace, flat map (κ → ∞): corrected / plain material, corrected / map\n")
    log("| α | θv | " + " | ".join("%s / plain | %s / map" % (n, n) for n in ("iso", "aniso")) + " |")
    log("|---:|---:|" + "---:|" * 4)
    f_iso = furnace_check(corrs["iso"])
    f_an = furnace_check(corrs["aniso"])
    worst = 0.0
    for (a, th, p1, m1), (_, _, p2, m2) in zip(f_iso, f_an):
        log("| %g | %g | %.4f | %.4f | %.4f | %.4f |" % (a, th, p1, m1, p2, m2))
        worst = max(worst, abs(p1 - 1), abs(p2 - 1))
    log("\nworst |corrected/plain − 1| = %.2e" % worst)

    bad, ranges = finite_check(fits["iso"], 1.0, 10.0)
    log("\n## Finite check (cos θμ ∈ [−1, 1], 1/κ ∈ [0, 1e6], α ∈ [0, 1])\n")
    for k in bad:
        log("- %s: %d non-finite or negative; range [%.3g, %.3g]" % (k, bad[k], *ranges[k]))

    if not args.quick:
        rows = lobe_table(lighting, {"none": None, "iso": corrs["iso"], "aniso": corrs["aniso"]}, log=log)
        with open(os.path.join(args.out, "lobes.json"), "w") as f:
            json.dump(rows, f, indent=1)
        log("\n## Single vMF lobes, summary (κ ≥ 10)\n")
        log(lobe_summary(rows, worlds))
        log("\n## Single vMF lobes (sun 4° from the mirror azimuth): median over worlds of closure/map,"
            " [min, max], and the furnace ratio\n")
        log("| θv | κ | α | lobe | θμ | none | iso | aniso | furnace none / iso / aniso |")
        log("|---:|---:|---:|---|---:|---|---|---|---|")
        for r in rows:
            cells = []
            for n in ("none", "iso", "aniso"):
                vals = np.array([r[n][w] for w in worlds])
                cells.append("%.2f [%.2f, %.2f]" % (np.median(vals), vals.min(), vals.max()))
            fur = " / ".join("%.2f" % r[n]["furnace"] for n in ("none", "iso", "aniso"))
            log("| %g | %g | %g | %s | %.0f | %s | %s |" % (r["theta"], r["kappa"], r["alpha"], r["tilt"],
                                                        r["theta_mu"], " | ".join(cells), fur))
    log("\ntotal %.0f s" % (time.time() - t0))
    with open(os.path.join(args.out, "report.md"), "w") as f:
        f.write("\n".join(report) + "\n")
    with open(os.path.join(args.out, "fit.json"), "w") as f:
        json.dump(dict(fits=fits, far_ground=aggs, within_10pct={k: int(v) for k, v in within.items()}), f, indent=1)
