"""The receding-surface benchmark's small version: one real map, one light, 128x72.

Run: python tests/blender/test_addon_receding.py -- LIB     (also `blender -b --python ... -- LIB`)

examples/receding_bench.py's scene: the woven fabric of scripts/install-normal-maps.sh on a plane
receding from 1 m to the horizon, a sun 15 degrees above its far end, view exposure 0, baked with
the add-on's defaults (4 lobes, the scene camera's level of detail). Against each engine's own
truth (EEVEE: 8x8 supersampled with the map point-sampled; Cycles: REFERENCE_SAMPLES spp) the block
error of ndfbake's render (EEVEE 16 TAA samples, Cycles 16 spp) is divided by the plain map's.
First the references are checked: the plain map must be measurably off (PLAIN_ERROR_FLOOR), and
the Cycles reference's own noise (half the block difference of its two halves, different seeds)
under a tenth of the plain map's error, so the ratio measures ndfbake and not the reference.

Issue 40 asks for a ratio of at most 0.5 (ACCEPTED_RATIO) in both engines. The add-on does not
meet it yet, so each ratio is held to a regression bound over what it measured in the newest
series, where the test runs (REGRESSION_BOUNDS), and a miss of 0.5 is printed, not failed.
2026-12-07, ratios EEVEE Next / Cycles: Blender 5.3 1.40 / 5.79, Blender 5.0 0.65 / 5.03. The
miss is all in the specular (a black Base Color leaves the ratios as they are). In Cycles the plain
map's 16 spp are unbiased, its error (0.021-0.024) is noise, while ndfbake's far band is about 10%
too bright and its near band 10% too dark, a bias (0.12): the lobes' grazing narrowing
(cycles_lobes NARROWED, the default) concentrates the low sun's highlight; baked WIDENED, Cycles'
ratio is 1.74 in 5.0. docs/receding.md has the benchmark's table and what was tried.
"""
import os
import sys

import bpy
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import test_addon_helpers as h  # noqa: E402

sys.path.insert(0, os.path.join(h.REPO, "examples"))
import receding_bench  # noqa: E402

MAP, LIGHT = "fabric", "sun_far"
WIDTH, HEIGHT = 128, 72
REFERENCE_SAMPLES = 2048
ACCEPTED_RATIO = 0.5        # issue 40: ndfbake's error at most half the plain map's, with the defaults
REGRESSION_BOUNDS = {"eevee": 1.6, "cycles": 6.5}   # what the defaults measured in 5.3 (above), with a margin
PLAIN_ERROR_FLOOR = 0.005   # the plain map's block error must show (a broken scene renders alike)
REFERENCE_NOISE_SHARE = 0.1


def test_receding_fabric_under_a_low_sun():
    map_path = os.path.join(receding_bench.DEFAULT_MAPS, MAP + ".png")
    h.expect(os.path.exists(map_path), "%s is missing: scripts/install-normal-maps.sh puts it there" % map_path)
    with h.scratch_dir() as directory:
        h.reset_scene()
        result = receding_bench.run_map(MAP, map_path, directory, (LIGHT,), WIDTH, HEIGHT, REFERENCE_SAMPLES,
                                        repeats=0, variants=receding_bench.VARIANTS[:2],
                                        log=lambda s: print(s, flush=True))
    case = result["cases"][LIGHT]
    for name, pixels in case["images"].items():
        h.expect(np.isfinite(pixels).all(), "%s: non-finite pixels" % name)
    print("  %d plane pixels; bake: %s" % (result["pixels"], result["bakes"]["ndfbake"]["summary"]), flush=True)
    misses = []
    for engine, errors in case["errors"].items():
        ratio = errors["ndfbake"] / errors["plain"]
        print("  %-6s plain %.4f  ndfbake %.4f  ratio %.3f%s" % (
            engine, errors["plain"], errors["ndfbake"], ratio,
            "  (reference noise %.4f)" % case["reference_noise"] if engine == "cycles" else ""), flush=True)
        h.expect(errors["plain"] > PLAIN_ERROR_FLOOR, "%s: the plain map's error %.4f shows nothing to filter"
                 % (engine, errors["plain"]))
        if ratio > ACCEPTED_RATIO:
            print("  MISS %s: ndfbake / plain %.3f is above issue 40's %.2f" % (engine, ratio, ACCEPTED_RATIO))
        if ratio > REGRESSION_BOUNDS[engine]:
            misses.append("%s %.3f > %.2f" % (engine, ratio, REGRESSION_BOUNDS[engine]))
    noise = case["reference_noise"]
    h.expect(noise < REFERENCE_NOISE_SHARE * case["errors"]["cycles"]["plain"],
             "the Cycles reference's noise %.4f is not under a tenth of the plain map's error %.4f"
             % (noise, case["errors"]["cycles"]["plain"]))
    h.expect(not misses, "ndfbake / plain above its regression bound: %s" % ", ".join(misses))


if __name__ == "__main__":
    h.import_addon()
    h.run([test_receding_fabric_under_a_low_sun])
