// libFuzzer target: normal-map decoding of arbitrary bytes (ndfb_normal_map_load, the first step
// of every bake, and ndfb_describe_image).
//
// Input: byte 0 picks the file extension (OpenImageIO picks its reader by extension first) and the
// decode options; the rest is the file, written to a scratch folder (the decoder takes a path).
// A decoded map must hold finite unit normals with z >= 0; a small one is also fitted.
#include <cmath>
#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "fuzz_common.h"

namespace {

// The formats normal maps come in (and the readers a user's file reaches through the add-on).
const char* const kExtensions[] = {"png", "exr", "tga", "tif", "jpg", "bmp", "hdr", "psd"};
constexpr size_t kExtensionCount = sizeof kExtensions / sizeof kExtensions[0];

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    using namespace ndfbake_fuzz;
    if (size < 1) return 0;
    const uint8_t selector = data[0];
    const std::string file = scratch_dir() + "/input." + kExtensions[selector % kExtensionCount];
    {
        std::ofstream out(file, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data + 1), std::streamsize(size - 1));
    }

    ndfb_context ctx = context();
    ndfb_decode_options decode;
    ndfb_decode_options_init(&decode);
    decode.convention = (selector & 0x10) ? NDFB_CONVENTION_DIRECTX : NDFB_CONVENTION_OPENGL;
    decode.srgb = (selector & 0x20) ? NDFB_SRGB_LINEARIZE : NDFB_SRGB_AS_DATA;
    // Keeps a header's claimed size within what a fuzzing process may allocate; the pixel limit
    // itself is what is tested when a header claims more.
    decode.max_pixels = (selector & 0x40) ? 4096 : (uint64_t(1) << 20);

    char text[256];
    size_t length = 0;
    check(ndfb_describe_image(ctx, file.c_str(), text, sizeof text, &length), "ndfb_describe_image");

    ndfb_normal_map map = nullptr;
    const ndfb_status status = ndfb_normal_map_load(ctx, file.c_str(), &decode, &map);
    check(status, "ndfb_normal_map_load");
    require((status == NDFB_OK) == (map != nullptr), "a map exactly when the load succeeds");
    if (!map) return 0;

    uint32_t width = 0, height = 0;
    require(ndfb_normal_map_size(map, &width, &height) == NDFB_OK, "size of a loaded map");
    require(width >= 1 && height >= 1 && uint64_t(width) * height <= decode.max_pixels, "size within max_pixels");
    std::vector<float> normals(size_t(width) * height * 3);
    require(ndfb_normal_map_read(map, normals.data(), normals.size()) == NDFB_OK, "read a loaded map");
    for (size_t i = 0; i < normals.size(); i += 3) {
        const double x = normals[i], y = normals[i + 1], z = normals[i + 2];
        require(std::isfinite(x) && std::isfinite(y) && std::isfinite(z), "decoded normals are finite");
        require(std::abs(std::sqrt(x * x + y * y + z * z) - 1.0) < 1e-4, "decoded normals are unit");
        require(z >= 0.0, "decoded normals point out of the surface");
    }
    ndfb_repairs repairs{};
    require(ndfb_normal_map_repairs(map, &repairs) == NDFB_OK, "repairs of a loaded map");

    // What the bake does next, on maps small enough to fit quickly.
    if (uint64_t(width) * height <= 256) {
        ndfb_fit_options fit;
        ndfb_fit_options_init(&fit);
        fit.max_lobes = 1 + (selector >> 6);
        fit.threads = 1;
        fit.max_iterations = 5;
        ndfb_pyramid pyramid = nullptr;
        check(ndfb_fit(ctx, map, &fit, nullptr, nullptr, &pyramid), "ndfb_fit");
        ndfb_pyramid_destroy(pyramid);
    }
    ndfb_normal_map_destroy(map);
    return 0;
}
