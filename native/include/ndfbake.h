/*
 * ndfbake: normal-map NDF filtering (Han et al. 2007) behind a plain C interface: decoding a
 * normal map, fitting and writing its lobe files, reading them back, and tangent frames. The
 * ground truth and the benchmark behind the project's figures are in ndfbake_research.h.
 *
 * Conventions
 * - Every call returns an ndfb_status; NDFB_OK is 0. On failure, ndfb_last_error() on the same
 *   context gives a one-line message naming the input and the problem. No call throws, aborts or
 *   leaves a partial file behind.
 * - Objects are opaque handles created and destroyed by the library. A call that creates one sets
 *   its output handle to NULL when it fails, for any reason (so a variable that still holds an
 *   object must not be passed as the output: the object would be lost). Buffers are caller-owned
 *   and passed with explicit element counts; a count that does not match is
 *   NDFB_ERROR_INVALID_ARGUMENT.
 * - Normals are unit float3 in tangent space, +Z out of the surface, OpenGL convention (+Y up V),
 *   rows top to bottom as stored in image files.
 * - Option structs start with struct_size, from which the library reads only the fields the caller
 *   has; fill them with the matching *_init function first (and see NDFB_ABI_MAJOR). The fields
 *   a struct had in minor version 0 of this ABI are always read: a struct_size that does not
 *   cover them is NDFB_ERROR_INVALID_ARGUMENT. Fields a later minor version adds go at the end,
 *   read only where struct_size covers them.
 * - Limits and defaults are the library's: ndfb_max_lobes(), and the *_init functions' values.
 * - Calls that run long take a progress callback of their own (NULL: none).
 * - A context may be used by one thread at a time; separate contexts are independent.
 * - Paths (files and folders) are UTF-8 strings on every platform, Windows included; messages name
 *   them in UTF-8.
 */
#ifndef NDFBAKE_H
#define NDFBAKE_H

#include <stddef.h>
#include <stdint.h>

/* NDFB_API marks the functions the library exports; it is built with every other symbol hidden.
 * The library's own sources define NDFBAKE_BUILDING. On Windows a DLL exports what is marked
 * __declspec(dllexport); a program linking its import library gets __declspec(dllimport), and one
 * that compiles the library's sources into itself defines NDFBAKE_STATIC. Loading the library at
 * run time (ctypes, dlopen, LoadLibrary) needs none of this. */
#if defined(_WIN32) || defined(__CYGWIN__)
#if defined(NDFBAKE_BUILDING)
#define NDFB_API __declspec(dllexport)
#elif defined(NDFBAKE_STATIC)
#define NDFB_API
#else
#define NDFB_API __declspec(dllimport)
#endif
#elif defined(NDFBAKE_BUILDING)
#define NDFB_API __attribute__((visibility("default")))
#else
#define NDFB_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

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
typedef enum ndfb_brdf {
    NDFB_BRDF_GGX = 0,         /* parameter: Blender roughness r, α = r² */
    NDFB_BRDF_BLINN_PHONG = 1, /* parameter: exponent s */
    NDFB_BRDF_LAMBERT = 2,
    NDFB_BRDF_BECKMANN = 3     /* parameter: RMS slope m */
} ndfb_brdf;
typedef enum ndfb_precision { NDFB_PRECISION_HALF = 0, NDFB_PRECISION_FLOAT = 1 } ndfb_precision;
typedef enum ndfb_srgb_policy {
    NDFB_SRGB_AS_DATA = 0,   /* sRGB-tagged files: raw values are the encoded normal (usual case) */
    NDFB_SRGB_LINEARIZE = 1  /* decode the sRGB curve first (a map saved through a colour pipeline) */
} ndfb_srgb_policy;
typedef enum ndfb_fit_method {
    NDFB_FIT_PER_LEVEL = 0,    /* every level from all the fine normals it covers (Han §7.1): the
                                  reference the default is measured against */
    NDFB_FIT_HIERARCHICAL = 1  /* every level from the binned normals of the level below (default):
                                  as accurate, 4-5x faster (docs/speed.md, "Bake speed") */
} ndfb_fit_method;
/* Progress: fraction in [0, 1] and a stage name: "decode", "fit" (the lobe alignment included),
 * "measure" (the report's error statistics), "write". Every stage a call goes through is reported
 * at least once, however fast it runs (more often while it runs long). Called on the thread that
 * called the library. Return non-zero to cancel: the call then returns NDFB_ERROR_CANCELLED and
 * leaves no output behind. */
typedef int (*ndfb_progress_fn)(void* user, const char* stage, float fraction);

typedef struct ndfb_context_s* ndfb_context;
typedef struct ndfb_normal_map_s* ndfb_normal_map;
typedef struct ndfb_pyramid_s* ndfb_pyramid;
typedef struct ndfb_bake_result_s* ndfb_bake_result;

typedef struct ndfb_decode_options {
    uint32_t struct_size;
    ndfb_convention convention;   /* of the input; the result is always OpenGL */
    ndfb_srgb_policy srgb;
    uint64_t max_pixels;          /* refuse larger images before reading them */
} ndfb_decode_options;

typedef struct ndfb_fit_options {
    uint32_t struct_size;
    uint32_t max_lobes;           /* 1..ndfb_max_lobes(), default 4 */
    float tolerance;              /* relative effective-BRDF error a texel may keep: fewer lobes where it
                                     suffices (costs fitting time); default 0: max_lobes everywhere */
    ndfb_brdf brdf;               /* the base BRDF the tolerance is measured with, default GGX */
    float brdf_parameter;         /* GGX roughness (Blender's, α = r²) or Blinn-Phong exponent */
    ndfb_wrap wrap;
    int32_t align;                /* non-zero: aligned lobes (eq. 23) for hardware filtering, default 1 */
    float alignment_strength;     /* C of eq. 23, default 0 (slots are reordered, lobes not pulled) */
    uint32_t max_iterations;      /* EM iterations per texel at most, default 10 (hierarchical, unrefined:
                                     one k-means step on footprints of at most 64 fine normals, at
                                     most 3 iterations up to 1024, 5 above) */
    ndfb_fit_method method;       /* default NDFB_FIT_HIERARCHICAL */
    uint32_t threads;             /* 0: all cores */
    /* Memory a fit or bake may use (its estimated peak: the decoded map, the lobe pyramid, the
       largest working set of the fit, the texture being written). A larger job is refused up
       front with NDFB_ERROR_OUT_OF_MEMORY, before any pixel is read, with the estimate and the
       limit in the message. 0 (default): the machine's physical memory. report.json records the
       estimate and the process's measured peak ("peak_memory_bytes"). */
    uint64_t max_memory_bytes;
    /* Levels to fit and write, from level 0 up (1: level 0 only); 0 (default): every level down
       to 1x1. A scene whose cameras never see the map smaller than 2^(n-1) texels per pixel needs
       n levels, and the fit of each level costs about as much as any other. */
    uint32_t max_levels;
    /* EM starts per texel: 1 seeds EM from the finer level's lobes only (Han §7.1); 2 (default)
       also from the farthest-apart samples where a texel has more than 64 (the hierarchical fit,
       unrefined: on footprints of more than 1024 fine normals), keeping the likelier fit (lower
       error on wide footprints, where the finer level's lobes trap EM). */
    uint32_t starts;
    /* Non-zero: after EM, move every texel's lobes to where their convolved mixture is closest to
       the exact effective BRDF of `brdf` (Levenberg-Marquardt on the relative L2 error; see
       docs/fit.md, "Refining for the BRDF"). Lower error for that BRDF (a fifth less on a 1024² fBm map
       at GGX roughness 0.3) at 100-300x the fitting time (a refined fit also skips the
       hierarchical fit's shortcuts for texels of few normals); default 0. */
    int32_t refine;
} ndfb_fit_options;

typedef struct ndfb_write_options {
    uint32_t struct_size;
    ndfb_precision precision;     /* default half */
    const char* color_path;       /* optional base-colour image of the same size: per-lobe colour (eq. 22) */
    const char* source_name;      /* recorded in the files; default: the input path */
    /* Non-zero: also write atlas_lobeJ.exr, every level of lobe slot J in one image, for renderers
       without MIP levels of their own: level 0 on the left, levels 1, 2, ... stacked top-down in a
       column to its right, each framed by a one-texel border of the texels the wrap mode puts
       there, so bilinear filtering inside a level is exact. report.json's "atlas" gives the size
       and, per level, the frame's top-left corner (x, y; texels start at x + 1, y + 1) and size. */
    int32_t atlas;
    /* Non-zero: also write mip_lobeJ.exr, lobe slot J as one tiled, MIP-mapped OpenEXR file
       (MIPMAP_LEVELS, ROUND_UP, 64x64 tiles) whose MIP level L is fitted level L, for renderers
       that pick and filter levels themselves (OpenImageIO's texture system: OSL's texture(), a
       real-time engine's MIP chain). Level L is ceil(w / 2^L) x ceil(h / 2^L), the bake's own
       sizes (ROUND_UP: OpenEXR's ROUND_DOWN would drop levels of a non-power-of-two map). The
       chain always runs down to 1x1: where max_levels fitted fewer, the rest are footprint-weighted
       averages of the level below (attribute ndfbake:fitted_levels says how many are fitted).
       Channels and ndfbake:* attributes as the per-level files, with ndfbake:level -1 and the
       per-level fit errors in ndfbake:level_errors. */
    int32_t mipmap;
} ndfb_write_options;

typedef struct ndfb_repairs {
    uint64_t non_finite, zero_length, renormalized, below_horizon;
} ndfb_repairs;

typedef struct ndfb_level_stats {
    uint32_t width, height;
    float mean_error;   /* relative effective-BRDF error, mean over the measured texels */
    float p95_error;
    uint32_t measured_texels;
} ndfb_level_stats;

/* ---- library and context ------------------------------------------------------------------ */
NDFB_API const char* ndfb_version(void);
/* The ABI: the major version changes where a layout or a signature does (a program built for
 * another major must call nothing but ndfb_version, ndfb_abi_version and ndfb_abi_minor: the *_init
 * functions write the option structs as this header lays them out); the minor grows where calls or trailing struct fields are
 * added (a program built for minor m runs on any library of its major whose minor is >= m). A
 * program compares ndfb_abi_version() with its NDFB_ABI_MAJOR before anything else. */
#define NDFB_ABI_MAJOR 2
#define NDFB_ABI_MINOR 0
NDFB_API uint32_t ndfb_abi_version(void); /* the library's NDFB_ABI_MAJOR */
NDFB_API uint32_t ndfb_abi_minor(void);
/* The most lobes a texel may have (fit option max_lobes): 8. */
NDFB_API uint32_t ndfb_max_lobes(void);
NDFB_API ndfb_status ndfb_context_create(ndfb_context* out);
NDFB_API void ndfb_context_destroy(ndfb_context ctx);
/* The message of the last failed call on ctx ("" if none). Valid until the next call on ctx.
 * With ctx == NULL: the message of the last failed ndfb_context_create on this thread. */
NDFB_API const char* ndfb_last_error(ndfb_context ctx);
NDFB_API const char* ndfb_status_name(ndfb_status status);
/* Non-zero where the library reads and writes image files (through OpenImageIO): the full library,
 * which `ndfbake` and the tests use. The Blender add-on's library is built without image files, to
 * need nothing beyond the C runtime (docs/blender-versions.md); it writes the lobe
 * textures (OpenEXR) and report.json, but ndfb_normal_map_load, ndfb_bake, ndfb_describe_image,
 * ndfb_normal_map_save and a write_options color_path fail there with
 * NDFB_ERROR_UNSUPPORTED_FORMAT and a message naming what to call instead: decode the image in
 * the host, then ndfb_normal_map_from_pixels and ndfb_bake_map. */
NDFB_API int32_t ndfb_has_image_files(void);

NDFB_API void ndfb_decode_options_init(ndfb_decode_options* options);
NDFB_API void ndfb_fit_options_init(ndfb_fit_options* options);
NDFB_API void ndfb_write_options_init(ndfb_write_options* options);
/* Checks fit options as ndfb_fit and the bakes do, without fitting: NDFB_ERROR_INVALID_ARGUMENT
 * naming the first bad field (a host checks its settings so before it starts a bake). */
NDFB_API ndfb_status ndfb_fit_options_check(ndfb_context ctx, const ndfb_fit_options* options);

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
                              ndfb_progress_fn progress, void* progress_user, ndfb_pyramid* out);
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
/* How many texels of `level` have k lobes, for k = 0..slots: count = ndfb_pyramid_lobe_slots + 1. */
NDFB_API ndfb_status ndfb_pyramid_lobe_histogram(ndfb_pyramid pyramid, uint32_t level, uint64_t* counts,
                                                 size_t count);

/* ---- files --------------------------------------------------------------------------------- */
/* Writes level{L}_lobe{j}.exr for every level and lobe slot, optional level{L}_color{j}.exr,
 * atlas_lobe{j}.exr and mip_lobe{j}.exr (write options atlas, mipmap), ndfbake.glsl and report.json
 * into out_dir, each atomically (temp name, then rename). On failure or cancel, no file of this call
 * remains, and an earlier bake's files in out_dir are all kept: they are replaced together or not
 * at all (on Windows a file open in another program cannot be replaced: the call then fails with
 * NDFB_ERROR_IO naming the file). The files and the report record the options the pyramid was
 * fitted with, and it is written with the threads it was fitted with.
 * out (may be NULL): what the call wrote, an ndfb_bake_result; NULL after a failure. */
NDFB_API ndfb_status ndfb_pyramid_write(ndfb_context ctx, ndfb_pyramid pyramid, ndfb_normal_map map,
                                        const char* out_dir, const ndfb_write_options* options,
                                        ndfb_progress_fn progress, void* progress_user, ndfb_bake_result* out);
/* Decode, fit and write in one call: what `ndfbake bake` runs. out as ndfb_pyramid_write. */
NDFB_API ndfb_status ndfb_bake(ndfb_context ctx, const char* input_path, const char* out_dir,
                               const ndfb_decode_options* decode, const ndfb_fit_options* fit,
                               const ndfb_write_options* write, ndfb_progress_fn progress, void* progress_user,
                               ndfb_bake_result* out);
/* ndfb_bake for a map already decoded (ndfb_normal_map_from_pixels, ndfb_synthesize): fit and write
 * in one call, with ndfb_bake's checks before the fit (out_dir writable, memory, colour image) and
 * its report (repairs, assumptions and source hash of the map's decode, timings). Progress stages
 * "fit", "measure", "write"; cancel as ndfb_bake. The files name write->source_name as their
 * source (default "memory"). What the Blender add-on runs, with pixels Blender decoded. */
NDFB_API ndfb_status ndfb_bake_map(ndfb_context ctx, ndfb_normal_map map, const char* out_dir,
                                   const ndfb_fit_options* fit, const ndfb_write_options* write,
                                   ndfb_progress_fn progress, void* progress_user, ndfb_bake_result* out);

/* What a bake wrote, so that a host needs neither to list the folder nor to parse report.json:
 * the levels and their sizes, the lobe slots and which of them any texel uses, the atlas layout
 * and every file by kind, level and slot. Valid until ndfb_bake_result_destroy. */
typedef enum ndfb_file_kind {
    NDFB_FILE_LOBE = 0,    /* level{L}_lobe{j}.exr: slot j of level L */
    NDFB_FILE_COLOR = 1,   /* level{L}_color{j}.exr */
    NDFB_FILE_ATLAS = 2,   /* atlas_lobe{j}.exr: every level of slot j (level -1) */
    NDFB_FILE_MIP = 3,     /* mip_lobe{j}.exr: slot j, MIP-mapped (level -1) */
    NDFB_FILE_SHADER = 4,  /* ndfbake.glsl (level and slot -1) */
    NDFB_FILE_REPORT = 5   /* report.json (level and slot -1) */
} ndfb_file_kind;
typedef struct ndfb_bake_file {
    ndfb_file_kind kind;
    int32_t level;         /* -1: not one level's */
    int32_t slot;          /* -1: not one slot's */
    const char* name;      /* the file's name in out_dir (ASCII) */
} ndfb_bake_file;
/* A level's frame in the atlas files: its texels start at (x + 1, y + 1), top row 0. */
typedef struct ndfb_atlas_frame {
    uint32_t x, y, width, height;
} ndfb_atlas_frame;

NDFB_API void ndfb_bake_result_destroy(ndfb_bake_result result);
NDFB_API uint32_t ndfb_bake_result_level_count(ndfb_bake_result result);
NDFB_API ndfb_status ndfb_bake_result_level_size(ndfb_bake_result result, uint32_t level, uint32_t* width,
                                                 uint32_t* height);
NDFB_API uint32_t ndfb_bake_result_lobe_slots(ndfb_bake_result result);
/* used[slot] = 1 where some texel of some level has a lobe in the slot (a tolerance can leave a
 * slot empty everywhere: its textures are all zero); count = ndfb_bake_result_lobe_slots. */
NDFB_API ndfb_status ndfb_bake_result_slots_used(ndfb_bake_result result, uint8_t* used, size_t count);
/* The atlas files' size (0 x 0 where write option atlas was off) and each level's frame in them. */
NDFB_API ndfb_status ndfb_bake_result_atlas_size(ndfb_bake_result result, uint32_t* width, uint32_t* height);
NDFB_API ndfb_status ndfb_bake_result_atlas_frame(ndfb_bake_result result, uint32_t level, ndfb_atlas_frame* out);
NDFB_API uint32_t ndfb_bake_result_file_count(ndfb_bake_result result);
NDFB_API ndfb_status ndfb_bake_result_file(ndfb_bake_result result, uint32_t index, ndfb_bake_file* out);
/* Non-zero where `name` (a file name, no folder) is one a bake writes: the files a host may
 * remove with a bake, and no other. */
NDFB_API int32_t ndfb_is_bake_file(const char* name);

/* ---- tangent frames ------------------------------------------------------------------------ */
/* MikkTSpace-compatible tangent frames (Mikkelsen 2008, §3), equal to what Blender's
 * Mesh.calc_tangents() gives: quads split along the shorter UV diagonal, corners welded when
 * position, normal and UV are bitwise equal, groups that never cross a mirror seam (UV winding),
 * corner-angle weighted averages, degenerate triangles handled as MikkTSpace does.
 *
 * Meshes are passed as plain arrays in an ndfb_mesh (fill it with ndfb_mesh_init first):
 * positions per vertex, faces as corner counts plus one vertex index per corner (faces one after
 * another, counter-clockwise seen from the front), normals and UVs per corner (Blender: loop
 * normals and the UV layer) or per vertex. Frames need the exact normals the renderer uses. The
 * library keeps no pointer after a call returns. Non-finite values, indices out of range, empty
 * meshes and sizes that do not add up are NDFB_ERROR_INVALID_ARGUMENT with a message naming the
 * element. Frames are defined for triangles and quads only: a mesh with n-gons is refused
 * (as calc_tangents does); ndfb_mesh_diagnose and ndfb_texel_density accept n-gons.
 *
 * Per corner the tangent array holds x, y, z, sign (Blender: loop.tangent, loop.bitangent_sign):
 * a unit tangent perpendicular to the corner normal, and bitangent = sign * cross(normal, tangent).
 * A corner no usable triangle reaches gets MikkTSpace's default (1, 0, 0), sign -1.
 * threads: 0 uses every core; results do not depend on it. */
typedef enum ndfb_domain { NDFB_PER_CORNER = 0, NDFB_PER_VERTEX = 1 } ndfb_domain;

typedef struct ndfb_mesh {
    uint32_t struct_size;
    const float* positions;          /* vertex_count * 3 */
    size_t vertex_count;
    const uint32_t* face_sizes;      /* face_count entries, each >= 3 */
    size_t face_count;
    const uint32_t* corner_vertices; /* corner_count entries; corner_count = sum of face_sizes */
    size_t corner_count;
    const float* normals;            /* 3 per corner or per vertex (normal_domain) */
    ndfb_domain normal_domain;       /* default NDFB_PER_CORNER */
    const float* uvs;                /* 2 per corner or per vertex (uv_domain) */
    ndfb_domain uv_domain;           /* default NDFB_PER_CORNER */
} ndfb_mesh;

NDFB_API void ndfb_mesh_init(ndfb_mesh* mesh);

/* tangents: tangent_count = corner_count * 4. magnitudes (may be NULL with magnitude_count 0):
 * corner_count * 2 floats, the world length per unit of U and of V at the corner (|dP/du|,
 * |dP/dv|, averaged over the corner's group like the tangent; capped at 1e30). */
NDFB_API ndfb_status ndfb_tangents(ndfb_context ctx, const ndfb_mesh* mesh, uint32_t threads, float* tangents,
                                   size_t tangent_count, float* magnitudes, size_t magnitude_count);

/* Mirroring-safe vertex splits: an indexed mesh for engines, where the corners of one input
 * vertex share an output vertex only if normal, UV, tangent and sign are all equal, so a vertex is
 * never welded across a mirror seam. tangents: as from ndfb_tangents (NULL: computed here).
 * corner_to_vertex[corner_count] receives the output vertex of every corner; vertex_source
 * (capacity >= corner_count entries) the input vertex of every output vertex. Output vertices are
 * numbered by input vertex, so a mesh that needs no split keeps its numbering (minus unused
 * vertices). Each extra copy of a vertex is counted once, under the first reason that applies in
 * the order UV, normal, sign, tangent. */
typedef struct ndfb_split_stats {
    uint64_t input_vertices;  /* input vertices used by at least one corner */
    uint64_t output_vertices;
    uint64_t uv_seams;        /* copies made because the UVs differ */
    uint64_t hard_edges;      /* ... same UV, different normals */
    uint64_t mirror_seams;    /* ... same UV and normal, opposite bitangent sign */
    uint64_t tangent_splits;  /* ... only the tangent differs (fan split by connectivity, quads) */
} ndfb_split_stats;

NDFB_API ndfb_status ndfb_split_vertices(ndfb_context ctx, const ndfb_mesh* mesh, const float* tangents,
                                         size_t tangent_count, uint32_t threads, uint32_t* corner_to_vertex,
                                         size_t corner_count, uint32_t* vertex_source, size_t capacity,
                                         ndfb_split_stats* stats);

/* UV texel density for level-of-detail selection: per face, sqrt(UV area / world area), i.e. UV
 * units per world unit (times the texture's size in texels: texels per world unit). 0 for faces
 * without world or UV area (or so little world area that the density passes float's range). mesh_density (may be NULL): the same over the whole mesh,
 * sqrt(total UV area / total world area). */
NDFB_API ndfb_status ndfb_texel_density(ndfb_context ctx, const ndfb_mesh* mesh, float* face_density,
                                        size_t face_count, double* mesh_density);

/* What in a mesh will make tangent frames, and so normal maps, go wrong, in counts a user can act
 * on; the *_first fields name an example face (-1: none). UV islands are sets of triangles joined
 * by edges whose two ends share position and UV. */
typedef struct ndfb_mesh_report {
    uint64_t faces, triangles, quads, ngons;  /* ngons: refused by ndfb_tangents; triangulate them */
    uint64_t degenerate_triangles;    /* zero world area (e.g. two corners at one position) */
    uint64_t zero_area_uv_triangles;  /* UV area ~0: no tangent of their own (MikkTSpace "group with any") */
    uint64_t uv_islands;
    uint64_t mirrored_islands;        /* UVs run clockwise: bitangent sign -1, split at their border (fine) */
    uint64_t flipped_islands;         /* islands with triangles of both windings: UV fold-overs */
    uint64_t flipped_triangles;       /* triangles wound against their island: a tangent split inside it */
    uint64_t inverted_normal_faces;   /* corner normals point against the face winding */
    int64_t ngon_first, degenerate_first, zero_area_uv_first, flipped_first, inverted_normal_first;
} ndfb_mesh_report;

/* text (may be NULL with capacity 0): a readable report, one finding per line; at most capacity
 * bytes including the NUL; *length (may be NULL) receives the full length. */
NDFB_API ndfb_status ndfb_mesh_diagnose(ndfb_context ctx, const ndfb_mesh* mesh, ndfb_mesh_report* report,
                                        char* text, size_t capacity, size_t* length);

/* Object-space <-> tangent-space normal maps, by rasterizing the mesh in UV space. Per texel the
 * frame is rebuilt exactly as a renderer's normal map does it: barycentric, unnormalized
 * interpolation of the corner tangent T, sign s and normal N (MikkTSpace's rule, and Cycles' Normal
 * Map node up to Blender 5.0), or N normalized first (frame_normal below), B = s * cross(N, T),
 * n_object = normalize(x T + y B + z N). ndfb_object_to_tangent applies the exact inverse of that
 * map, so rendering its output through the node gives back the object-space normals.
 * Images: width*height*3 floats in [-1, 1] (count = width*height*3), rows top to bottom (row 0 at
 * v = 1), texel (x, y) centred at u = (x + 0.5)/width, v = 1 - (y + 0.5)/height. Triangles are
 * rasterized where they lie in [0,1]^2; where UVs overlap, the face listed first wins. Quads are
 * interpolated split along 0-2 (1-3 when folded over 0-2), as Blender's renderer tessellates them;
 * triangulate them first to be safe. tangents: NULL computes them with ndfb_tangents. */
typedef struct ndfb_space_options {
    uint32_t struct_size;
    uint32_t padding;   /* texels grown around islands (default 16); NDFB_PAD_ALL fills the image.
                           2^k texels keep k MIP levels free of bleeding across island borders */
    uint32_t threads;   /* 0: all cores */
    uint32_t frame_normal;  /* an ndfb_frame_normal (default NDFB_FRAME_NORMAL_INTERPOLATED) */
} ndfb_space_options;
#define NDFB_PAD_ALL 0xffffffffu
/* The frame's N. The two differ where the corner normals of a triangle differ (a curved low-poly
 * surface): up to ~10 degrees on Suzanne's ears. */
typedef enum ndfb_frame_normal {
    NDFB_FRAME_NORMAL_INTERPOLATED = 0, /* as interpolated: MikkTSpace's rule; Cycles up to 5.0 */
    NDFB_FRAME_NORMAL_UNIT = 1          /* normalized before use: Cycles from 5.1 on */
} ndfb_frame_normal;
/* coverage (may be NULL): width*height bytes, 0 = outside every island and the padding,
 * 1 = inside a triangle, 2 = padding. Texels outside both hold (0, 0, 1) in tangent space and
 * (0, 0, 0) in object space. */
NDFB_API void ndfb_space_options_init(ndfb_space_options* options);
NDFB_API ndfb_status ndfb_object_to_tangent(ndfb_context ctx, const ndfb_mesh* mesh, const float* tangents,
                                            size_t tangent_count, const float* object_normals,
                                            uint32_t width, uint32_t height, size_t count,
                                            const ndfb_space_options* options, float* tangent_normals,
                                            uint8_t* coverage);
NDFB_API ndfb_status ndfb_tangent_to_object(ndfb_context ctx, const ndfb_mesh* mesh, const float* tangents,
                                            size_t tangent_count, const float* tangent_normals,
                                            uint32_t width, uint32_t height, size_t count,
                                            const ndfb_space_options* options, float* object_normals,
                                            uint8_t* coverage);

/* ---- synthetic normal maps ----------------------------------------------------------------- */
/* pattern: "vgroove", "bumps", "fbm", "brushed", "scratches", "weave". Tileable, deterministic. */
NDFB_API ndfb_status ndfb_synthesize(ndfb_context ctx, const char* pattern, uint32_t width, uint32_t height,
                                     uint32_t seed, ndfb_normal_map* out);
/* A readable description of any image file: format, size, channels, pixel type, its MIP levels
 * and their sizes where it has more than one, the lobe slot of an ndfbake lobe file, and every
 * header attribute (ndfbake's own among them), one per line. Copies at most capacity bytes including the
 * terminating NUL; *length (if not NULL) receives the full length without it. */
NDFB_API ndfb_status ndfb_describe_image(ndfb_context ctx, const char* path, char* text, size_t capacity,
                                         size_t* length);
/* Writes a normal map as an image (8/16-bit PNG/TIFF/TGA, or float EXR by extension), atomically. */
NDFB_API ndfb_status ndfb_normal_map_save(ndfb_context ctx, ndfb_normal_map map, const char* path);

#ifdef __cplusplus
}
#endif

#endif /* NDFBAKE_H */
