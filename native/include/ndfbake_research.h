/*
 * ndfbake research: the ground truth and the benchmark behind the library's figures, beside the
 * product API of ndfbake.h. Only the full library (libndfbake with image files: the command line,
 * the tests) carries them; the Blender add-on's library is built without this code and exports
 * none of it. Same conventions as ndfbake.h.
 */
#ifndef NDFBAKE_RESEARCH_H
#define NDFBAKE_RESEARCH_H

#include "ndfbake.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum ndfb_representation {
    NDFB_REPR_VMF_MIXTURE = 0, /* the budgeted vMF mixture (what bake writes) */
    NDFB_REPR_SINGLE_VMF = 1,  /* one lobe from the mean resultant */
    NDFB_REPR_TOKSVIG = 2      /* Toksvig's single lobe from the averaged normal's length */
} ndfb_representation;

/* ---- ground truth -------------------------------------------------------------------------- */
/* Exact effective BRDF of texel (x, y) of `level` (mean of f(ω·n_q) over its fine normals, eq. 4)
 * at `direction_count` unit directions (xyz triples), into values[direction_count]. */
NDFB_API ndfb_status ndfb_effective_brdf_reference(ndfb_context ctx, ndfb_normal_map map, ndfb_wrap wrap,
                                                   uint32_t level, uint32_t x, uint32_t y, ndfb_brdf brdf,
                                                   float brdf_parameter, const float* directions,
                                                   size_t direction_count, float* values);
/* The relative L2 error of a representation of texel (x, y) against the exact effective BRDF over
 * the library's fixed direction set for `brdf`. For NDFB_REPR_VMF_MIXTURE, pyramid supplies the lobes. */
NDFB_API ndfb_status ndfb_texel_error(ndfb_context ctx, ndfb_normal_map map, ndfb_pyramid pyramid,
                                      ndfb_representation representation, ndfb_wrap wrap, uint32_t level,
                                      uint32_t x, uint32_t y, ndfb_brdf brdf, float brdf_parameter,
                                      float* error);

/* ---- benchmark ----------------------------------------------------------------------------- */
typedef struct ndfb_bench_options {
    uint32_t struct_size;
    const char* const* map_paths;  /* normal maps to measure besides the synthetic patterns */
    size_t map_count;
    uint32_t synthetic_size;       /* side of the six synthetic patterns; 0 leaves them out */
    const char* methods;           /* comma-separated (see `ndfbake bench --help`); NULL: all */
    const char* brdfs;             /* comma-separated "ggx:R", "blinn-phong:S", …; NULL: ggx:0.3,ggx:0.6 */
    const char* levels;            /* comma-separated MIP levels; NULL: 2,4,6 */
    uint32_t texels_per_level;     /* measured texels per level; default 64 */
    uint32_t threads;              /* 0: all cores */
} ndfb_bench_options;

NDFB_API void ndfb_bench_options_init(ndfb_bench_options* options);
/* Measures every representation (the default bake, 1..8 vMF lobes, the hierarchical fit, naive,
 * Toksvig, LEAN, single vMF, Xu's partitions, SH orders 2..8) on the same footprints: build time,
 * storage per texel, mean and 95th-percentile effective-BRDF error. Writes bench.csv, bench.md
 * and per-level error heat maps (PNG) into out_dir. */
/* progress: stage is a line on the (map, method) just measured. */
NDFB_API ndfb_status ndfb_bench(ndfb_context ctx, const ndfb_bench_options* options, const char* out_dir,
                                ndfb_progress_fn progress, void* progress_user);

#ifdef __cplusplus
}
#endif

#endif /* NDFBAKE_RESEARCH_H */
