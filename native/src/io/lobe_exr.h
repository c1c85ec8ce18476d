// Self-describing RGBA EXR files: the lobe textures ndfbake writes carry their parameters as
// typed header attributes, so a file explains itself to `ndfbake info` and to the add-on.
// Written with OpenEXR alone, in both builds of the library (reading them back needs OpenImageIO:
// io/image_read.h).
#pragma once

#include <span>
#include <string>
#include <variant>
#include <vector>

namespace ndfbake {

using AttributeValue = std::variant<int, float, std::string>;

struct ExrAttribute {
    std::string name;  // e.g. "ndfbake:level"; stored with its C++ type (int stays int)
    AttributeValue value;
};

enum class PixelPrecision { half, single };

// How far off 1/κ may read for a lobe stored in half floats whose |r| is 1 (a single normal):
// each component rounds, so |r| comes back within about ±2.5e-4 of 1 and 1/κ ≈ 1 − R that much
// above 0 (measured on 200,000 unit vectors: 99th percentile 2.5e-4, largest 3.6e-4). Decoders
// subtract it from 1/κ so that a sharp lobe reads sharp rather than as noise in the roughness
// (for roughness 0.05, up to 0.14 at 1% of texels); for single floats the rounding is negligible.
inline constexpr float kHalfInvKappaResolution = 4e-4f;

// Both lossless. zlib (at its fastest level) for dense texels; run-length for images that are
// mostly runs of equal texels, such as a level-0 lobe slot, zero wherever the texel's one lobe
// sits in another slot: measured on a 2048² fbm bake, RLE writes level 0 1.4× faster than zlib
// for 14% more bytes in all.
enum class ExrCompression { zlib, run_length };

// Writes `rgba` (width * height * 4 floats, row-major, top row first) as a compressed EXR
// with the given header attributes, atomically (see write_file_atomic). Throws Error(io_error).
void write_rgba_exr(const std::string& path, int width, int height, const float* rgba,
                    PixelPrecision precision, const std::vector<ExrAttribute>& attributes,
                    ExrCompression compression = ExrCompression::zlib);

// One level of a MIP chain: width * height * 4 floats, row-major, top row first.
struct RgbaLevel {
    int width = 0;
    int height = 0;
    const float* rgba = nullptr;
};

// Tiles of the MIP-mapped file: OpenImageIO's texture cache reads a file tile by tile, and 64² is
// its own maketx's default.
inline constexpr int kMipTileSize = 64;

// Writes every level of a MIP chain as one tiled OpenEXR file (MIPMAP_LEVELS, ROUND_UP, tiles of
// kMipTileSize²), RGBA, with the given header attributes, atomically (see write_file_atomic).
// `levels` must be the whole chain OpenEXR lays out for levels[0]'s size: with ROUND_UP, level L
// is ⌈w / 2^L⌉ × ⌈h / 2^L⌉ (at least 1) for L = 0 .. ⌈log₂ max(w, h)⌉, the bake's own level sizes
// (pyramid/footprint.h); ROUND_DOWN (one level fewer for most non-powers of two) would not hold
// the fitted levels of such a map. The sizes are checked against OpenEXR's own layout.
// Throws Error(invalid_argument) for a chain of other sizes, Error(io_error) for a failed write.
void write_mip_rgba_exr(const std::string& path, std::span<const RgbaLevel> levels, PixelPrecision precision,
                        const std::vector<ExrAttribute>& attributes,
                        ExrCompression compression = ExrCompression::zlib);

}  // namespace ndfbake
