// What the io/ tests share: reference normal fields, their storage in every format, files
// written with OpenImageIO, and the IoTest fixture (a fresh folder per test).
#pragma once

#include <gtest/gtest.h>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <ostream>
#include <string>
#include <vector>
#include <OpenImageIO/imageio.h>
#include <unistd.h>
#include "error.h"
#include "io/atomic_file.h"
#include "io/json_writer.h"
#include "io/image_files.h"
#include "io/lobe_exr.h"
#include "io/normal_decode.h"
#include "test_support.h"

namespace ndfbake::io_fixtures {

namespace fs = std::filesystem;
using testing_support::read_bytes;
using testing_support::write_bytes;

inline constexpr int kWidth = 32;  // not square, so a transposed read shows up
inline constexpr int kHeight = 16;

// ---- fixtures --------------------------------------------------------------------------------

// A smooth field tilting up to 48° in both axes; smooth so that lossy JPEG stays close to it.
inline std::vector<Vec3> smooth_normals(int width, int height)
{
    std::vector<Vec3> normals;
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const float sx = 0.8f * std::sin(6.2831853f * float(x) / float(width));
            const float sy = 0.8f * std::cos(6.2831853f * float(y) / float(height));
            normals.push_back(normalize_or({-sx, -sy, 1.0f}, {0, 0, 1}));
        }
    }
    return normals;
}

// Directions over the whole upper hemisphere down to 85° from +Z: every combination of signs and
// magnitudes, the worst case for 8-bit length error.
inline std::vector<Vec3> hemisphere_normals(int width, int height)
{
    std::vector<Vec3> normals;
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const float theta = 1.4835f * (float(y) + 0.5f) / float(height);
            const float phi = 6.2831853f * (float(x) + 0.37f) / float(width);
            normals.push_back({std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                               std::cos(theta)});
        }
    }
    return normals;
}

// Channel values as a file stores them: X, Y, [Z], [alpha]; unsigned maps c -> (c + 1) / 2.
// Alpha varies and is never 1, so a reader that premultiplies by it shows up.
inline std::vector<float> stored_values(const std::vector<Vec3>& normals, int channels, bool signed_values)
{
    std::vector<float> values;
    for (size_t i = 0; i < normals.size(); ++i) {
        for (int c = 0; c < std::min(channels, 3); ++c)
            values.push_back(signed_values ? normals[i][c] : 0.5f * (normals[i][c] + 1.0f));
        if (channels == 4)
            values.push_back(i % 2 ? 0.25f : 0.75f);
    }
    return values;
}

template <typename T>
std::vector<T> quantize(const std::vector<float>& unit_values, bool truncate = false)
{
    const double max_code = double(std::numeric_limits<T>::max());
    std::vector<T> codes;
    for (float v : unit_values) {
        const double scaled = std::clamp(double(v), 0.0, 1.0) * max_code;
        codes.push_back(T(truncate ? std::floor(scaled) : std::round(scaled)));
    }
    return codes;
}

// The DirectX twin of an OpenGL map: green inverted, as texture tools do it.
template <typename T>
std::vector<T> flip_green_codes(std::vector<T> codes, int channels)
{
    for (size_t i = 1; i < codes.size(); i += size_t(channels))
        codes[i] = std::numeric_limits<T>::max() - codes[i];
    return codes;
}

inline std::vector<float> flip_green_signed(std::vector<float> values, int channels)
{
    for (size_t i = 1; i < values.size(); i += size_t(channels))
        values[i] = -values[i];
    return values;
}

struct Attribute {
    std::string name;
    std::string value;
};

// Writes `data` (interleaved, type T) as an image stored with `file_type` samples.
template <typename T>
void write_image(const std::string& path, int width, int height, int channels,
                 OIIO::TypeDesc file_type, const std::vector<T>& data,
                 const std::vector<Attribute>& attributes = {})
{
    OIIO::ImageSpec spec(width, height, channels, file_type);
    spec.attribute("oiio:UnassociatedAlpha", 1);  // store channel values as given
    for (const Attribute& a : attributes)
        spec.attribute(a.name, a.value);
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out) << OIIO::geterror();
    ASSERT_TRUE(out->open(path, spec)) << out->geterror();
    ASSERT_TRUE(out->write_image(OIIO::TypeDescFromC<T>::value(), data.data())) << out->geterror();
    ASSERT_TRUE(out->close()) << out->geterror();
}

inline float max_difference(const std::vector<Vec3>& a, const std::vector<Vec3>& b)
{
    EXPECT_EQ(a.size(), b.size());
    float worst = 0.0f;
    for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
        for (int c = 0; c < 3; ++c)
            worst = std::max(worst, std::abs(a[i][c] - b[i][c]));
    }
    return worst;
}

inline void expect_identical(const std::vector<Vec3>& a, const std::vector<Vec3>& b)
{
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(a[i].x, b[i].x) << "pixel " << i;
        ASSERT_EQ(a[i].y, b[i].y) << "pixel " << i;
        ASSERT_EQ(a[i].z, b[i].z) << "pixel " << i;
    }
}

inline bool has_assumption(const DecodeResult& result, const std::string& part)
{
    return std::any_of(result.assumptions.begin(), result.assumptions.end(),
                       [&](const std::string& s) { return s.find(part) != std::string::npos; });
}

// `call` must throw an Error with `status` whose message contains every string in `parts`.
template <typename F>
void expect_error(F&& call, Status status, const std::vector<std::string>& parts)
{
    try {
        call();
        ADD_FAILURE() << "no error thrown";
    } catch (const Error& e) {
        EXPECT_EQ(int(e.status()), int(status)) << e.what();
        for (const std::string& part : parts)
            EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
        EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
}

class IoTest : public testing_support::TempDirTest {
protected:
    std::vector<std::string> files_in(const fs::path& dir) const
    {
        std::vector<std::string> names;
        for (const auto& entry : fs::directory_iterator(dir))
            names.push_back(entry.path().filename().string());
        std::sort(names.begin(), names.end());
        return names;
    }

    // The smooth reference field as an 8-bit 3-channel PNG.
    std::string write_reference_png(const std::string& name)
    {
        const std::string file = path(name);
        write_image(file, kWidth, kHeight, 3, OIIO::TypeDesc::UINT8,
                    quantize<uint8_t>(stored_values(smooth_normals(kWidth, kHeight), 3, false)));
        return file;
    }
};

}  // namespace ndfbake::io_fixtures
