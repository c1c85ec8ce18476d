// libFuzzer target: the bake entry points with arbitrary options and a fuzzed map.
//
// Input: the option fields (each either drawn from its valid range or taken raw, so both the
// checks and the work behind them are reached), a map of up to 16 x 16 texels whose samples are
// raw float bits (NaN, Inf, denormals, huge values included), and which path to take:
// ndfb_fit + ndfb_pyramid_write, or the map saved as PNG then ndfb_bake. A progress callback may
// cancel after a fuzzed number of calls. Oracle: no NDFB_ERROR_INTERNAL, finite lobe textures with
// alpha in [0, 1] and |r| <= 1, and after any failure no file in the output folder.
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "fuzz_common.h"

namespace {

struct Cancel {
    int after = -1;  // cancel on this call (-1: never)
    int calls = 0;
};

int progress(void* user, const char* stage, float fraction)
{
    auto* cancel = static_cast<Cancel*>(user);
    ndfbake_fuzz::require(stage && std::strlen(stage) > 0, "progress has a stage name");
    ndfbake_fuzz::require(fraction >= 0.0f && fraction <= 1.0f, "progress fraction in [0, 1]");
    return cancel->calls++ == cancel->after ? 1 : 0;
}

template <typename T>
T pick(FuzzedDataProvider& in, T low, T high)
{
    // Mostly in range; one time in eight any value of the type.
    if (in.ConsumeIntegralInRange<uint8_t>(0, 7) == 0) return in.ConsumeIntegral<T>();
    return in.ConsumeIntegralInRange<T>(low, high);
}

float pick_float(FuzzedDataProvider& in, float low, float high)
{
    switch (in.ConsumeIntegralInRange<uint8_t>(0, 7)) {
    case 0: {
        const uint32_t bits = in.ConsumeIntegral<uint32_t>();
        float f;
        std::memcpy(&f, &bits, sizeof f);
        return f;
    }
    case 1: return low;
    case 2: return high;
    default: return in.ConsumeFloatingPointInRange<float>(low, high);
    }
}

void check_lobes(ndfb_pyramid pyramid)
{
    using ndfbake_fuzz::require;
    const uint32_t levels = ndfb_pyramid_level_count(pyramid), slots = ndfb_pyramid_lobe_slots(pyramid);
    require(levels >= 1 && slots >= 1 && slots <= ndfb_max_lobes(), "pyramid shape");
    for (uint32_t level = 0; level < levels; ++level) {
        uint32_t w = 0, h = 0;
        require(ndfb_pyramid_level_size(pyramid, level, &w, &h) == NDFB_OK, "level size");
        std::vector<float> alpha_sum(size_t(w) * h, 0.0f), rgba(size_t(w) * h * 4);
        for (uint32_t lobe = 0; lobe < slots; ++lobe) {
            require(ndfb_pyramid_read_lobe(pyramid, level, lobe, rgba.data(), rgba.size()) == NDFB_OK, "read lobe");
            for (size_t t = 0; t < alpha_sum.size(); ++t) {
                const float* p = &rgba[t * 4];
                for (int c = 0; c < 4; ++c) require(std::isfinite(p[c]), "lobe texels are finite");
                require(p[0] >= 0.0f && p[0] <= 1.0f + 1e-4f, "alpha in [0, 1]");
                const double r = std::sqrt(double(p[1]) * p[1] + double(p[2]) * p[2] + double(p[3]) * p[3]);
                require(r <= double(p[0]) * (1.0 + 1e-4) + 1e-6, "|alpha r| <= alpha");
                alpha_sum[t] += p[0];
            }
        }
        for (float a : alpha_sum) require(a <= 1.0f + 1e-3f, "alphas of a texel sum to at most 1");
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    using namespace ndfbake_fuzz;
    FuzzedDataProvider in(data, size);
    ndfb_context ctx = context();

    ndfb_decode_options decode;
    ndfb_decode_options_init(&decode);
    set_raw(decode.convention, pick<uint32_t>(in, 0, 1));
    set_raw(decode.srgb, pick<uint32_t>(in, 0, 1));
    decode.max_pixels = pick<uint64_t>(in, 1, 1024);

    Cancel cancel;
    ndfb_fit_options fit;
    ndfb_fit_options_init(&fit);
    fit.max_lobes = pick<uint32_t>(in, 1, ndfb_max_lobes());
    fit.tolerance = in.ConsumeBool() ? 0.0f : pick_float(in, 0.0f, 1.0f);
    const uint32_t brdf = pick<uint32_t>(in, 0, 3);
    set_raw(fit.brdf, brdf);
    const float ranges[4][2] = {{0.01f, 1.0f}, {1.0f, 10000.0f}, {0.0f, 0.0f}, {0.0001f, 1.0f}};
    const auto* range = ranges[brdf < 4 ? brdf : 0];
    fit.brdf_parameter = pick_float(in, range[0], range[1]);
    const uint32_t wrap = pick<uint32_t>(in, 0, 1);
    set_raw(fit.wrap, wrap);
    fit.align = in.ConsumeIntegral<int32_t>();
    fit.alignment_strength = in.ConsumeBool() ? 0.0f : pick_float(in, 0.0f, 10.0f);
    fit.max_iterations = pick<uint32_t>(in, 1, 30);
    set_raw(fit.method, pick<uint32_t>(in, 0, 1));
    fit.threads = pick<uint32_t>(in, 0, 3);
    fit.max_memory_bytes = in.ConsumeBool() ? 0 : in.ConsumeIntegral<uint64_t>();
    ndfb_progress_fn progress_fn = nullptr;
    if (in.ConsumeBool()) {
        cancel.after = in.ConsumeIntegralInRange<int>(0, 64);
        progress_fn = progress;
    }
    fit.refine = in.ConsumeIntegralInRange<uint8_t>(0, 7) == 0;  // slow: one input in eight
    if (in.ConsumeIntegralInRange<uint8_t>(0, 31) == 0) fit.struct_size = in.ConsumeIntegral<uint32_t>();

    ndfb_write_options write;
    ndfb_write_options_init(&write);
    set_raw(write.precision, pick<uint32_t>(in, 0, 1));
    const bool with_color = in.ConsumeIntegralInRange<uint8_t>(0, 3) == 0;
    const bool through_bake = in.ConsumeBool();
    const bool write_files = in.ConsumeIntegralInRange<uint8_t>(0, 3) == 0;

    // The map: size, channels, encoding, then raw float samples (repeated if the input runs out).
    const uint32_t width = in.ConsumeIntegralInRange<uint32_t>(1, 16);
    const uint32_t height = in.ConsumeIntegralInRange<uint32_t>(1, 16);
    const uint32_t channels = pick<uint32_t>(in, 2, 4);
    const int32_t signed_encoding = in.ConsumeBool();
    const std::vector<uint8_t> bytes = in.ConsumeRemainingBytes<uint8_t>();
    if (channels > 8) return 0;  // the count check is exercised by the hostile-input tests
    std::vector<float> pixels(size_t(width) * height * channels, 0.5f);
    if (!bytes.empty())
        for (size_t i = 0; i < pixels.size(); ++i) {
            uint8_t b[4];
            for (int k = 0; k < 4; ++k) b[k] = bytes[(i * 4 + size_t(k)) % bytes.size()];
            std::memcpy(&pixels[i], b, 4);
        }

    ndfb_normal_map map = nullptr;
    ndfb_status status = ndfb_normal_map_from_pixels(ctx, pixels.data(), pixels.size(), width, height, channels,
                                                     signed_encoding, &decode, &map);
    check(status, "ndfb_normal_map_from_pixels");
    if (status != NDFB_OK) return 0;

    const std::string out = scratch_dir() + "/out";
    clear(scratch_dir());
    std::string color;
    if (with_color || through_bake) {
        // The map itself as a PNG: the input of ndfb_bake and a colour image of the right size.
        const std::string png = scratch_dir() + "/map.png";
        check(ndfb_normal_map_save(ctx, map, png.c_str()), "ndfb_normal_map_save");
        color = png;
        if (with_color) write.color_path = color.c_str();
    }

    if (through_bake) {
        status = ndfb_bake(ctx, color.c_str(), out.c_str(), &decode, &fit, &write, progress_fn, &cancel, nullptr);
        check(status, "ndfb_bake");
        if (status != NDFB_OK) require(empty_or_missing(out), "a failed bake leaves no file");
    } else {
        ndfb_pyramid pyramid = nullptr;
        status = ndfb_fit(ctx, map, &fit, progress_fn, &cancel, &pyramid);
        check(status, "ndfb_fit");
        require((status == NDFB_OK) == (pyramid != nullptr), "a pyramid exactly when the fit succeeds");
        if (pyramid) {
            check_lobes(pyramid);
            ndfb_level_stats stats;
            const uint32_t level = ndfb_pyramid_level_count(pyramid) - 1;
            check(ndfb_pyramid_level_stats(ctx, pyramid, level, fit.brdf, fit.brdf_parameter, 4, &stats),
                  "ndfb_pyramid_level_stats");
            float error = 0.0f;
            status = ndfb_texel_error(ctx, map, pyramid, NDFB_REPR_VMF_MIXTURE, fit.wrap, level, 0, 0, fit.brdf,
                                      fit.brdf_parameter, &error);
            check(status, "ndfb_texel_error");
            if (status == NDFB_OK && !(std::isfinite(error) && error >= 0.0f)) {
                std::fprintf(stderr, "texel error %g: %ux%u, %u channels, brdf %u parameter %g, level %u, J %u\n",
                             error, width, height, channels, brdf, fit.brdf_parameter, level, fit.max_lobes);
                std::fprintf(stderr, "tolerance %g align %d strength %g iterations %u method %u wrap %u threads %u refine %d\n",
                             fit.tolerance, fit.align, fit.alignment_strength, fit.max_iterations,
                             unsigned(fit.method), wrap, fit.threads, fit.refine);
                if (const char* dump = std::getenv("NDFB_FUZZ_DUMP")) ndfb_normal_map_save(ctx, map, dump);
                require(false, "texel error finite");
            }
            if (write_files) {
                status = ndfb_pyramid_write(ctx, pyramid, map, out.c_str(), &write, progress_fn, &cancel, nullptr);
                check(status, "ndfb_pyramid_write");
                if (status != NDFB_OK) require(empty_or_missing(out), "a failed write leaves no file");
            }
            ndfb_pyramid_destroy(pyramid);
        }
    }
    ndfb_normal_map_destroy(map);
    return 0;
}
