// Decoding tangent-space normal maps, from any format OpenImageIO reads or from pixels in memory,
// into unit OpenGL-convention normals. Every choice the file does not state for itself (sRGB handling, float encoding, channel
// meaning, convention) is made explicitly and written down in DecodeResult::assumptions.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "normal_map.h"

namespace ndfbake {

// Below this length a normal has no direction worth keeping: 8-bit files cannot store an exact
// zero, and mid-grey (128, 128, 128) decodes to length 0.0068, whose "direction" is quantization
// noise. Replacing it with +Z is the neutral choice; no real normal map has texels this short.
inline constexpr float kMinNormalLength = 0.01f;
// How far |n| may be from 1 before renormalizing counts as a repair (it happens regardless).
// Correctly encoded 8-bit maps are off by up to sqrt(3)/255 = 0.0068 when rounded and 0.0136 when
// truncated; 0.02 keeps such maps at zero repairs while still flagging genuinely non-unit data
// (unnormalized exports, averaged or hand-painted normals).
inline constexpr float kUnitLengthTolerance = 0.02f;
// With FloatEncoding::automatic, float data with any component below this is read as signed
// [-1, 1]. Not 0: lossy half-float or filtered [0, 1] data can dip a hair below zero.
inline constexpr float kSignedDetectThreshold = -0.01f;

enum class Convention { opengl, directx };  // directx: green channel is -Y, flipped on decode
enum class SrgbPolicy { treat_as_data, linearize };  // a normal map is data: default treat_as_data
enum class FloatEncoding { automatic, signed_unit, unsigned_unit };

struct DecodeOptions {
    Convention convention = Convention::opengl;
    SrgbPolicy srgb = SrgbPolicy::treat_as_data;
    FloatEncoding float_encoding = FloatEncoding::automatic;
    uint64_t max_pixels = uint64_t(1) << 28;  // checked from the header, before any pixel is read
};

struct DecodeResult {
    NormalMap map;
    RepairCounts repairs;
    std::string format;         // OpenImageIO format name ("png", "openexr"), "memory" for pixels
    int bits_per_channel = 0;
    int channels = 0;
    bool srgb_tagged = false;   // OpenImageIO reports the file as sRGB
    bool float_data = false;    // half, float or double samples
    bool signed_encoding = false;  // samples were taken as [-1, 1] rather than [0, 1]
    uint64_t source_hash = 0;   // FNV-1a 64 of the file's bytes (of the pixel bytes for memory)
    std::vector<std::string> assumptions;  // one human sentence per assumption made
};

// Decodes subimage 0, MIP level 0 of the image at `path` (io/normal_file_decode.cpp; the library
// built without OpenImageIO refuses, io/no_image_files.cpp). Unsigned integer samples map
// v -> 2v - 1; float samples follow options.float_encoding; 2 channels are X, Y with Z rebuilt,
// 3 are XYZ, 4 are XYZ plus an ignored alpha. Throws Error on any unreadable or unsuitable file.
DecodeResult decode_normal_map(const std::string& path, const DecodeOptions& options);

// Decodes interleaved in-memory pixels (row 0 at the top) already in [0, 1] (unsigned) or
// [-1, 1] (signed), with the same channel, convention and repair rules as decode_normal_map.
DecodeResult decode_normal_pixels(const float* pixels, int width, int height, int channels,
                                  bool signed_encoding, const DecodeOptions& options);

// The repair rule applied to every decoded normal, in order: non-finite -> +Z; shorter than
// kMinNormalLength -> +Z; z < 0 -> z = -z; then normalized to unit length, counted as
// renormalized only when |n| was off 1 by more than kUnitLengthTolerance. Adds to `counts`.
void repair_normals(NormalMap& map, RepairCounts& counts);

}  // namespace ndfbake
