// What the hostile-input tests share: crafted files (headers that claim huge sizes), listings, and
// the HostileInputs fixture, whose checks hold every failure to a specific status and a one-line
// message naming the problem.
#pragma once

#include <gtest/gtest.h>
#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <linux/capability.h>
#include <sys/mman.h>
#include <sys/mount.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <cfloat>
#include <cstdlib>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <limits>
#include <set>
#include <string>
#include <vector>
#include <OpenImageIO/imageio.h>
#include "io/normal_encode.h"
#include "ndfbake_research.h"  // ndfbake.h and the ground truth, the benchmark
#include "synth/patterns.h"
#include "test_support.h"

namespace ndfbake::hostile_inputs {

namespace fs = std::filesystem;
using testing_support::read_bytes;
using testing_support::write_bytes;

// Every entry under `folder`, hidden ones included.
inline std::set<std::string> entries(const std::string& folder)
{
    std::set<std::string> names;
    if (!fs::exists(folder)) return names;
    for (const auto& e : fs::recursive_directory_iterator(folder)) names.insert(e.path().string());
    return names;
}

// ---- crafted files ---------------------------------------------------------------------------

inline uint32_t crc32(const std::string& bytes)
{
    uint32_t crc = 0xffffffffu;
    for (unsigned char b : bytes) {
        crc ^= b;
        for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

inline std::string be32(uint32_t v)
{
    return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
}

inline std::string png_chunk(const std::string& type, const std::string& data)
{
    return be32(uint32_t(data.size())) + type + data + be32(crc32(type + data));
}

// A valid PNG header (8-bit RGB) claiming width x height, then an IDAT holding a tiny zlib stream
// (one stored block of 4 zero bytes) and IEND: a reader learns the size, then finds no pixels.
inline std::string png_claiming(uint32_t width, uint32_t height)
{
    const std::string ihdr = be32(width) + be32(height) + std::string("\x08\x02\x00\x00\x00", 5);
    const std::string zlib_stream("\x78\x01\x01\x04\x00\xfb\xff\x00\x00\x00\x00\x00\x04\x00\x01", 15);
    return std::string("\x89PNG\r\n\x1a\n", 8) + png_chunk("IHDR", ihdr) + png_chunk("IDAT", zlib_stream) +
           png_chunk("IEND", "");
}

inline std::string le32(int32_t v)
{
    const auto u = uint32_t(v);
    return {char(u), char(u >> 8), char(u >> 16), char(u >> 24)};
}

inline std::string exr_attribute(const std::string& name, const std::string& type, const std::string& value)
{
    return name + '\0' + type + '\0' + le32(int32_t(value.size())) + value;
}

// An uncompressed scanline EXR header (half RGB) claiming width x height, with its line offset
// table all zeros and no pixel data.
inline std::string exr_claiming(int32_t width, int32_t height)
{
    std::string channels;
    for (const char* c : {"B", "G", "R"})
        channels += std::string(c) + '\0' + le32(1) + std::string(4, '\0') + le32(1) + le32(1);
    channels += '\0';
    const std::string window = le32(0) + le32(0) + le32(width - 1) + le32(height - 1);
    const float one = 1.0f;
    std::string one_bytes(4, '\0');
    std::memcpy(one_bytes.data(), &one, 4);
    return std::string("\x76\x2f\x31\x01", 4) + le32(2) + exr_attribute("channels", "chlist", channels) +
           exr_attribute("compression", "compression", std::string(1, '\0')) +
           exr_attribute("dataWindow", "box2i", window) + exr_attribute("displayWindow", "box2i", window) +
           exr_attribute("lineOrder", "lineOrder", std::string(1, '\0')) +
           exr_attribute("pixelAspectRatio", "float", one_bytes) +
           exr_attribute("screenWindowCenter", "v2f", std::string(8, '\0')) +
           exr_attribute("screenWindowWidth", "float", one_bytes) + '\0' + std::string(size_t(height) * 8, '\0');
}

// Any image through OpenImageIO: `values` are floats converted to `type` on write.
inline void write_image(const std::string& path, int width, int height, int channels, OIIO::TypeDesc type,
                 const std::vector<float>& values)
{
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out) << OIIO::geterror();
    const OIIO::ImageSpec spec(width, height, channels, type);
    ASSERT_TRUE(out->open(path, spec)) << out->geterror();
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, values.data())) << out->geterror();
    ASSERT_TRUE(out->close());
}

// ---- the fixture -----------------------------------------------------------------------------

class HostileInputs : public testing_support::CApiTest {
protected:
    void SetUp() override
    {
        CApiTest::SetUp();
        fit_.max_lobes = 2;
        fit_.threads = 2;
    }

    std::string synth_png(const std::string& name, int size, Pattern pattern = Pattern::fbm)
    {
        return synth_file(pattern, size, size, name);
    }

    std::string error() const { return ndfb_last_error(ctx_); }

    // The status and message of the last call are what `expected` and `parts` say, in one line.
    void expect_error(ndfb_status status, ndfb_status expected, std::initializer_list<std::string> parts,
                      const std::string& what)
    {
        EXPECT_EQ(status, expected) << what << ": " << ndfb_status_name(status) << ": " << error();
        const std::string message = error();
        EXPECT_EQ(message.find('\n'), std::string::npos) << what << ": " << message;
        for (const std::string& part : parts)
            EXPECT_NE(message.find(part), std::string::npos) << what << ": '" << part << "' not in: " << message;
    }

    // Bakes `input` into out_dir and checks the failure; the folder must hold nothing afterwards.
    void expect_bake_error(const std::string& input, ndfb_status expected, std::initializer_list<std::string> parts,
                           const std::string& what)
    {
        const std::string out = path("out-" + std::to_string(bakes_++));
        expect_error(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), expected, parts,
                     what + " (bake)");
        EXPECT_TRUE(listing(out).empty()) << what << ": the bake left files in " << out;
    }

    // Loads `input` and checks the failure.
    void expect_load_error(const std::string& input, ndfb_status expected, std::initializer_list<std::string> parts,
                           const std::string& what)
    {
        ndfb_normal_map map = reinterpret_cast<ndfb_normal_map>(0x1);
        expect_error(ndfb_normal_map_load(ctx_, input.c_str(), &decode_, &map), expected, parts, what + " (load)");
        EXPECT_EQ(map, nullptr) << what;
    }

    int bakes_ = 0;
};

}  // namespace ndfbake::hostile_inputs
