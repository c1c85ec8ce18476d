/*
 * ndfbake: normal-map NDF filtering (Han et al. 2007) behind a plain C interface.
 *
 * Conventions
 * - Every call returns an ndfb_status; NDFB_OK is 0. On failure, ndfb_last_error() on the same
 *   context gives a one-line message naming the input and the problem. No call throws, aborts or
 *   leaves a partial file behind.
 * - Objects are opaque handles created and destroyed by the library. Buffers are caller-owned and
 *   passed with explicit element counts; a count that does not match is NDFB_ERROR_INVALID_ARGUMENT.
 * - Normals are unit float3 in tangent space, +Z out of the surface, OpenGL convention (+Y up V),
 *   rows top to bottom as stored in image files.
 * - Option structs start with struct_size; fill them with the matching *_init function first, so
 *   that a program built against an older header keeps working with a newer library.
 * - A context may be used by one thread at a time; separate contexts are independent.
 */
#ifndef NDFBAKE_H
#define NDFBAKE_H

#include <stddef.h>
#include <stdint.h>

#if defined(NDFBAKE_BUILDING)
#define NDFB_API __attribute__((visibility("default")))
#else
#define NDFB_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

#define NDFB_MAX_LOBES 8

typedef enum ndfb_status {
    NDFB_OK = 0,
    NDFB_ERROR_INVALID_ARGUMENT = 1,  /* bad option, null pointer, size mismatch, bad handle */
    NDFB_ERROR_FILE_NOT_FOUND = 2,
    NDFB_ERROR_UNSUPPORTED_FORMAT = 3, /* not an image, or channels we cannot read as normals */
    NDFB_ERROR_CORRUPT_FILE = 4,      /* empty, truncated or damaged image */
    NDFB_ERROR_IO = 5,                /* cannot write the output folder or a file in it */
    NDFB_ERROR_OUT_OF_MEMORY = 6,     /* the image is larger than the memory allowed */
    NDFB_ERROR_CANCELLED = 7,         /* the progress callback asked to stop */
    NDFB_ERROR_INTERNAL = 8
} ndfb_status;

typedef enum ndfb_convention { NDFB_CONVENTION_OPENGL = 0, NDFB_CONVENTION_DIRECTX = 1 } ndfb_convention;
typedef enum ndfb_wrap { NDFB_WRAP_REPEAT = 0, NDFB_WRAP_CLAMP = 1 } ndfb_wrap;
typedef enum ndfb_brdf { NDFB_BRDF_GGX = 0, NDFB_BRDF_BLINN_PHONG = 1, NDFB_BRDF_LAMBERT = 2 } ndfb_brdf;
typedef enum ndfb_precision { NDFB_PRECISION_HALF = 0, NDFB_PRECISION_FLOAT = 1 } ndfb_precision;
typedef enum ndfb_srgb_policy {
    NDFB_SRGB_AS_DATA = 0,   /* sRGB-tagged files: raw values are the encoded normal (usual case) */
    NDFB_SRGB_LINEARIZE = 1  /* decode the sRGB curve first (a map saved through a colour pipeline) */
} ndfb_srgb_policy;
typedef enum ndfb_representation {
    NDFB_REPR_VMF_MIXTURE = 0, /* the budgeted vMF mixture (what bake writes) */
    NDFB_REPR_SINGLE_VMF = 1,  /* one lobe from the mean resultant */
    NDFB_REPR_TOKSVIG = 2      /* Toksvig's single lobe from the averaged normal's length */
} ndfb_representation;

/* Progress: fraction in [0, 1] and a stage name ("decode", "fit", "align", "write"). Called on the
 * thread that called the library. Return non-zero to cancel: the call then returns
 * NDFB_ERROR_CANCELLED and leaves no output behind. */
typedef int (*ndfb_progress_fn)(void* user, const char* stage, float fraction);

typedef struct ndfb_context_s* ndfb_context;
typedef struct ndfb_normal_map_s* ndfb_normal_map;
typedef struct ndfb_pyramid_s* ndfb_pyramid;

typedef struct ndfb_decode_options {
    uint32_t struct_size;
    ndfb_convention convention;   /* of the input; the result is always OpenGL */
    ndfb_srgb_policy srgb;
    uint64_t max_pixels;          /* refuse larger images before reading them */
} ndfb_decode_options;

typedef struct ndfb_fit_options {
    uint32_t struct_size;
    uint32_t max_lobes;           /* 1..NDFB_MAX_LOBES, default 4 */
    float tolerance;              /* relative effective-BRDF error per texel, default 0.05; 0: always max_lobes */
    ndfb_brdf brdf;               /* the base BRDF the tolerance is measured with, default GGX */
    float brdf_parameter;         /* GGX roughness (Blender's, α = r²) or Blinn-Phong exponent */
    ndfb_wrap wrap;
    int32_t align;                /* non-zero: aligned lobes (eq. 23) for hardware filtering, default 1 */
    float alignment_strength;     /* C of eq. 23, default 0.25 */
    uint32_t max_iterations;      /* EM iterations per texel, default 20 */
    uint32_t threads;             /* 0: all cores */
    ndfb_progress_fn progress;
    void* progress_user;
} ndfb_fit_options;

typedef struct ndfb_write_options {
    uint32_t struct_size;
    ndfb_precision precision;     /* default half */
    const char* color_path;       /* optional base-colour image of the same size: per-lobe colour (eq. 22) */
    const char* source_name;      /* recorded in the files; default: the input path */
} ndfb_write_options;

typedef struct ndfb_repairs {
    uint64_t non_finite, zero_length, renormalized, below_horizon;
} ndfb_repairs;

typedef struct ndfb_level_stats {
    uint32_t width, height;
    uint64_t lobe_histogram[NDFB_MAX_LOBES + 1]; /* texels with k lobes */
    float mean_error;   /* relative effective-BRDF error, mean over the measured texels */
    float p95_error;
    uint32_t measured_texels;
} ndfb_level_stats;

/* ---- library and context ------------------------------------------------------------------ */
NDFB_API const char* ndfb_version(void);
NDFB_API uint32_t ndfb_abi_version(void);  /* bumped on any incompatible change of this header */
NDFB_API ndfb_status ndfb_context_create(ndfb_context* out);
NDFB_API void ndfb_context_destroy(ndfb_context ctx);
/* The message of the last failed call on ctx ("" if none). Valid until the next call on ctx.
 * With ctx == NULL: the message of the last failed ndfb_context_create on this thread. */
NDFB_API const char* ndfb_last_error(ndfb_context ctx);
NDFB_API const char* ndfb_status_name(ndfb_status status);

NDFB_API void ndfb_decode_options_init(ndfb_decode_options* options);
NDFB_API void ndfb_fit_options_init(ndfb_fit_options* options);
NDFB_API void ndfb_write_options_init(ndfb_write_options* options);

/* ---- normal maps --------------------------------------------------------------------------- */
/* Any format OpenImageIO reads; 8/16/32-bit; 2 channels (z reconstructed), 3 or 4 (alpha ignored). */
NDFB_API ndfb_status ndfb_normal_map_load(ndfb_context ctx, const char* path,
                                          const ndfb_decode_options* options, ndfb_normal_map* out);
/* From memory: width*height*channels floats, encoded in [0,1] (signed == 0) or [-1,1]. */
NDFB_API ndfb_status ndfb_normal_map_from_pixels(ndfb_context ctx, const float* pixels, size_t count,
                                                 uint32_t width, uint32_t height, uint32_t channels,
                                                 int32_t signed_encoding,
                                                 const ndfb_decode_options* options, ndfb_normal_map* out);
NDFB_API void ndfb_normal_map_destroy(ndfb_normal_map map);
NDFB_API ndfb_status ndfb_normal_map_size(ndfb_normal_map map, uint32_t* width, uint32_t* height);
/* Copies the decoded unit normals out: count must be width*height*3. */
NDFB_API ndfb_status ndfb_normal_map_read(ndfb_normal_map map, float* xyz, size_t count);
NDFB_API ndfb_status ndfb_normal_map_repairs(ndfb_normal_map map, ndfb_repairs* out);

/* ---- fitting ------------------------------------------------------------------------------- */
NDFB_API ndfb_status ndfb_fit(ndfb_context ctx, ndfb_normal_map map, const ndfb_fit_options* options,
                              ndfb_pyramid* out);
NDFB_API void ndfb_pyramid_destroy(ndfb_pyramid pyramid);
NDFB_API uint32_t ndfb_pyramid_level_count(ndfb_pyramid pyramid);
NDFB_API uint32_t ndfb_pyramid_lobe_slots(ndfb_pyramid pyramid);
NDFB_API ndfb_status ndfb_pyramid_level_size(ndfb_pyramid pyramid, uint32_t level, uint32_t* width,
                                             uint32_t* height);
/* Lobe texture `lobe` of `level`: width*height RGBA floats, R = α, GBA = α·r, where r = R·μ and R is
 * the resultant length whose κ = (3R − R³)/(1 − R²) (Algorithm 2, line 9) is the lobe's. */
NDFB_API ndfb_status ndfb_pyramid_read_lobe(ndfb_pyramid pyramid, uint32_t level, uint32_t lobe,
                                            float* rgba, size_t count);
/* Error statistics of a level against the exact effective BRDF (eq. 4) of `brdf`, measured on at
 * most max_texels texels spread evenly over the level (0: every texel). */
NDFB_API ndfb_status ndfb_pyramid_level_stats(ndfb_context ctx, ndfb_pyramid pyramid, uint32_t level,
                                              ndfb_brdf brdf, float brdf_parameter,
                                              uint32_t max_texels, ndfb_level_stats* out);

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

/* ---- files --------------------------------------------------------------------------------- */
/* Writes level{L}_lobe{j}.exr for every level and lobe slot, optional level{L}_color{j}.exr, and
 * report.json into out_dir, each atomically (temp name, then rename). On failure or cancel, no
 * file of this call remains. */
NDFB_API ndfb_status ndfb_pyramid_write(ndfb_context ctx, ndfb_pyramid pyramid, ndfb_normal_map map,
                                        const char* out_dir, const ndfb_fit_options* fit_options,
                                        const ndfb_write_options* options);
/* Decode, fit and write in one call: what `ndfbake bake` and the Blender add-on run. */
NDFB_API ndfb_status ndfb_bake(ndfb_context ctx, const char* input_path, const char* out_dir,
                               const ndfb_decode_options* decode, const ndfb_fit_options* fit,
                               const ndfb_write_options* write);

/* ---- synthetic normal maps ----------------------------------------------------------------- */
/* pattern: "vgroove", "bumps", "fbm", "brushed", "scratches", "weave". Tileable, deterministic. */
NDFB_API ndfb_status ndfb_synthesize(ndfb_context ctx, const char* pattern, uint32_t width, uint32_t height,
                                     uint32_t seed, ndfb_normal_map* out);
/* A readable description of any image file: format, size, channels, pixel type and every header
 * attribute (ndfbake's own among them), one per line. Copies at most capacity bytes including the
 * terminating NUL; *length (if not NULL) receives the full length without it. */
NDFB_API ndfb_status ndfb_describe_image(ndfb_context ctx, const char* path, char* text, size_t capacity,
                                         size_t* length);
/* Writes a normal map as an image (8/16-bit PNG/TIFF/TGA, or float EXR by extension), atomically. */
NDFB_API ndfb_status ndfb_normal_map_save(ndfb_context ctx, ndfb_normal_map map, const char* path);

#ifdef __cplusplus
}
#endif

#endif /* NDFBAKE_H */
