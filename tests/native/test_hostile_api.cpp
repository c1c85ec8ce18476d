// Misuse of the public C API (issue 6): options out of range, option structs shorter than their
// first layout, null handles and buffers, wrong sizes, a failed call's output handle, a destroyed
// context. Each is an error with a specific status and a one-line message, and writes nothing.

#include <gtest/gtest.h>

#include "hostile_fixtures.h"

namespace ndfbake {
namespace {

using namespace hostile_inputs;

// ---- options ---------------------------------------------------------------------------------

TEST_F(HostileInputs, OptionsOutOfRangeAreInvalidArgumentsAndWriteNothing)
{
    const std::string input = synth_png("in.png", 8);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    struct FitCase {
        const char* name;
        std::function<void(ndfb_fit_options&)> change;
        const char* says;
    };
    const FitCase fit_cases[] = {
        {"J = 0", [](auto& f) { f.max_lobes = 0; }, "max_lobes must be in 1..8, got 0"},
        {"J = 1000", [](auto& f) { f.max_lobes = 1000; }, "max_lobes must be in 1..8, got 1000"},
        {"J = 9", [](auto& f) { f.max_lobes = 9; }, "max_lobes must be in 1..8, got 9"},
        {"negative tolerance", [](auto& f) { f.tolerance = -0.5f; }, "tolerance must be in [0, 1], got -0.5"},
        {"NaN tolerance", [&](auto& f) { f.tolerance = nan; }, "tolerance must be in [0, 1], got nan"},
        {"tolerance 2", [](auto& f) { f.tolerance = 2.0f; }, "tolerance must be in [0, 1], got 2"},
        {"negative alignment", [](auto& f) { f.alignment_strength = -1.0f; }, "alignment_strength must be in [0, 10]"},
        {"NaN alignment", [&](auto& f) { f.alignment_strength = nan; }, "alignment_strength must be in [0, 10]"},
        {"0 iterations", [](auto& f) { f.max_iterations = 0; }, "max_iterations must be in 1..1000, got 0"},
        {"10^6 iterations", [](auto& f) { f.max_iterations = 1000000; }, "max_iterations must be in 1..1000"},
        {"5000 threads", [](auto& f) { f.threads = 5000; }, "threads must be at most 1024"},
        {"unknown BRDF", [](auto& f) { f.brdf = ndfb_brdf(99); }, "unknown BRDF 99"},
        {"GGX roughness 0", [](auto& f) { f.brdf_parameter = 0.0f; }, "GGX roughness must be in [0.01, 1]"},
        {"GGX roughness NaN", [&](auto& f) { f.brdf_parameter = nan; }, "GGX roughness must be in [0.01, 1], got nan"},
        {"Blinn-Phong exponent -3",
         [](auto& f) { f.brdf = NDFB_BRDF_BLINN_PHONG, f.brdf_parameter = -3.0f; },
         "Blinn-Phong exponent must be in [1, 10000]"},
        {"Beckmann slope 5", [](auto& f) { f.brdf = NDFB_BRDF_BECKMANN, f.brdf_parameter = 5.0f; },
         "Beckmann slope must be in [0.0001, 1]"},
        {"unknown wrap", [](auto& f) { f.wrap = ndfb_wrap(7); }, "unknown wrap mode"},
        {"unknown method", [](auto& f) { f.method = ndfb_fit_method(3); }, "unknown fit method"},
        {"struct_size 0", [](auto& f) { f.struct_size = 0; }, "fit options.struct_size is not set"},
        {"struct_size too big", [](auto& f) { f.struct_size = sizeof f + 64; }, "fit options.struct_size is not set"},
    };
    for (const FitCase& c : fit_cases) {
        ndfb_fit_options fit;
        ndfb_fit_options_init(&fit);
        c.change(fit);
        const std::string out = path(std::string("out ") + c.name);
        expect_error(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit, &write_, nullptr, nullptr, nullptr),
                     NDFB_ERROR_INVALID_ARGUMENT, {c.says}, c.name);
        EXPECT_FALSE(fs::exists(out)) << c.name;
    }

    struct DecodeCase {
        const char* name;
        std::function<void(ndfb_decode_options&)> change;
        const char* says;
    };
    const DecodeCase decode_cases[] = {
        {"unknown convention", [](auto& d) { d.convention = ndfb_convention(5); }, "unknown convention"},
        {"unknown sRGB policy", [](auto& d) { d.srgb = ndfb_srgb_policy(9); }, "unknown sRGB policy"},
        {"max_pixels 0", [](auto& d) { d.max_pixels = 0; }, "max_pixels must be positive"},
        {"decode struct_size 0", [](auto& d) { d.struct_size = 0; }, "decode options.struct_size is not set"},
    };
    for (const DecodeCase& c : decode_cases) {
        ndfb_decode_options decode;
        ndfb_decode_options_init(&decode);
        c.change(decode);
        const std::string out = path(std::string("out ") + c.name);
        expect_error(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode, &fit_, &write_, nullptr, nullptr, nullptr),
                     NDFB_ERROR_INVALID_ARGUMENT, {c.says}, c.name);
        EXPECT_FALSE(fs::exists(out)) << c.name;
    }

    ndfb_write_options write;
    ndfb_write_options_init(&write);
    write.precision = ndfb_precision(4);
    expect_error(ndfb_bake(ctx_, input.c_str(), path("out p").c_str(), &decode_, &fit_, &write, nullptr, nullptr, nullptr),
                 NDFB_ERROR_INVALID_ARGUMENT, {"unknown precision"}, "precision");
    ndfb_write_options_init(&write);
    write.struct_size = 2;
    expect_error(ndfb_bake(ctx_, input.c_str(), path("out s").c_str(), &decode_, &fit_, &write, nullptr, nullptr, nullptr),
                 NDFB_ERROR_INVALID_ARGUMENT, {"write options.struct_size is not set"}, "write struct_size");
    // A colour image of another size: refused before anything is written.
    const std::string color = synth_png("color.png", 4);
    ndfb_write_options_init(&write);
    write.color_path = color.c_str();
    expect_error(ndfb_bake(ctx_, input.c_str(), path("out c").c_str(), &decode_, &fit_, &write, nullptr, nullptr, nullptr),
                 NDFB_ERROR_INVALID_ARGUMENT, {"colour image '" + color + "' is 4x4, the normal map is 8x8"}, "colour");
    EXPECT_TRUE(listing(path("out c")).empty());
}

// Memory that ends where an inaccessible page begins: a struct placed at its end with struct_size
// bytes is all the caller has, so a read of any field past struct_size kills the process.
class GuardedMemory {
public:
    GuardedMemory()
    {
        page_ = size_t(::sysconf(_SC_PAGESIZE));
        void* p = ::mmap(nullptr, 2 * page_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (p == MAP_FAILED || ::mprotect(static_cast<char*>(p) + page_, page_, PROT_NONE) != 0) std::abort();
        memory_ = static_cast<char*>(p);
    }
    ~GuardedMemory() { ::munmap(memory_, 2 * page_); }
    GuardedMemory(const GuardedMemory&) = delete;
    GuardedMemory& operator=(const GuardedMemory&) = delete;

    // The first `bytes` bytes of `full` (struct_size set to `bytes`), ending at the guard page but
    // for the padding that aligns the struct as its type needs (any caller's struct is aligned;
    // UBSan rejects a misaligned one): fewer than alignof(Options) bytes, so a read of the field
    // just past struct_size may land there, but reads of the fields beyond it do not.
    template <typename Options>
    const Options* place(Options full, size_t bytes)
    {
        full.struct_size = uint32_t(bytes);
        const size_t span = (bytes + alignof(Options) - 1) / alignof(Options) * alignof(Options);
        char* at = memory_ + page_ - span;
        std::memcpy(at, &full, bytes);
        return reinterpret_cast<const Options*>(at);
    }

private:
    size_t page_ = 0;
    char* memory_ = nullptr;
};

// Ends the (death-test) child with the call's status as exit code, and its message on stderr.
[[noreturn]] void exit_with(ndfb_context ctx, ndfb_status status)
{
    std::fprintf(stderr, "%s: %s\n", ndfb_status_name(status), ndfb_last_error(ctx));
    std::_Exit(int(status));
}

// ndfbake.h: the library "reads only the fields the caller has". A struct shorter than its layout
// in minor version 0 of the ABI holds fields the library must read, so it is refused, naming the struct, before
// any of them is: each call runs in a child (EXPECT_EXIT) with the struct against a guard page,
// where reading past struct_size would end it with SIGSEGV instead of exit code 1.
TEST_F(HostileInputs, OptionStructsShorterThanTheirFirstLayoutAreRefusedUnread)
{
    using ::testing::ExitedWithCode;
    const int inval = NDFB_ERROR_INVALID_ARGUMENT;
    const float pixels[3] = {0.5f, 0.5f, 1.0f};
    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_normal_map_from_pixels(ctx_, pixels, 3, 1, 1, 3, 0, &decode_, &map), NDFB_OK) << error();
    ndfb_pyramid pyramid = nullptr;
    ASSERT_EQ(ndfb_fit(ctx_, map, &fit_, nullptr, nullptr, &pyramid), NDFB_OK) << error();
    ndfb_bench_options bench;
    ndfb_bench_options_init(&bench);
    ndfb_space_options space;
    ndfb_space_options_init(&space);
    const std::string out = path("out");
    GuardedMemory guarded;

    for (size_t bytes : {sizeof(uint32_t), offsetof(ndfb_decode_options, max_pixels)}) {
        const auto* d = guarded.place(decode_, bytes);
        ndfb_normal_map scratch = nullptr;
        EXPECT_EXIT(exit_with(ctx_, ndfb_normal_map_from_pixels(ctx_, pixels, 3, 1, 1, 3, 0, d, &scratch)),
                    ExitedWithCode(inval), "decode options.struct_size is not set: call ndfb_decode_options_init")
            << bytes << " bytes";
    }
    for (size_t bytes : {sizeof(uint32_t), offsetof(ndfb_fit_options, threads), offsetof(ndfb_fit_options, refine)}) {
        const auto* f = guarded.place(fit_, bytes);
        ndfb_pyramid scratch = nullptr;
        EXPECT_EXIT(exit_with(ctx_, ndfb_fit(ctx_, map, f, nullptr, nullptr, &scratch)), ExitedWithCode(inval),
                    "fit options.struct_size is not set: call ndfb_fit_options_init")
            << bytes << " bytes";
    }
    for (size_t bytes : {sizeof(uint32_t), offsetof(ndfb_write_options, mipmap)}) {
        const auto* w = guarded.place(write_, bytes);
        EXPECT_EXIT(exit_with(ctx_, ndfb_pyramid_write(ctx_, pyramid, map, out.c_str(), w, nullptr, nullptr, nullptr)),
                    ExitedWithCode(inval), "write options.struct_size is not set: call ndfb_write_options_init")
            << bytes << " bytes";
    }
    for (size_t bytes : {sizeof(uint32_t), offsetof(ndfb_bench_options, threads)}) {
        const auto* b = guarded.place(bench, bytes);
        EXPECT_EXIT(exit_with(ctx_, ndfb_bench(ctx_, b, out.c_str(), nullptr, nullptr)), ExitedWithCode(inval),
                    "bench options.struct_size is not set: call ndfb_bench_options_init")
            << bytes << " bytes";
    }
    for (size_t bytes : {sizeof(uint32_t), offsetof(ndfb_space_options, frame_normal)}) {
        const auto* o = guarded.place(space, bytes);
        float in[3] = {0, 0, 1}, converted[3];
        EXPECT_EXIT(exit_with(ctx_, ndfb_object_to_tangent(ctx_, nullptr, nullptr, 0, in, 1, 1, 3, o, converted, nullptr)),
                    ExitedWithCode(inval), "space options.struct_size is not set: call ndfb_space_options_init")
            << bytes << " bytes";
    }
    EXPECT_FALSE(fs::exists(out));

    // The layouts of minor version 0 themselves, against the guard: accepted, and nothing past
    // them is read, so this runs in the test's own process.
    const auto* first_fit = guarded.place(fit_, sizeof(ndfb_fit_options));
    ndfb_pyramid refit = nullptr;
    EXPECT_EQ(ndfb_fit(ctx_, map, first_fit, nullptr, nullptr, &refit), NDFB_OK) << error();
    ndfb_pyramid_destroy(refit);
    const auto* first_write = guarded.place(write_, sizeof(ndfb_write_options));
    EXPECT_EQ(ndfb_pyramid_write(ctx_, pyramid, map, out.c_str(), first_write, nullptr, nullptr, nullptr), NDFB_OK) << error();
    ndfb_pyramid_destroy(pyramid);
    ndfb_normal_map_destroy(map);
}

// ---- API misuse ------------------------------------------------------------------------------

TEST_F(HostileInputs, NullHandlesNullBuffersAndWrongSizesAreErrors)
{
    const std::string input = synth_png("in.png", 8);
    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_normal_map_load(ctx_, input.c_str(), &decode_, &map), NDFB_OK);
    ndfb_pyramid pyramid = nullptr;
    ASSERT_EQ(ndfb_fit(ctx_, map, &fit_, nullptr, nullptr, &pyramid), NDFB_OK);
    std::vector<float> buffer(8 * 8 * 4);
    float direction[3] = {0, 0, 1}, value = 0;
    const ndfb_status inval = NDFB_ERROR_INVALID_ARGUMENT;
    // Calls expected to fail write their (null) result here, never over `map`.
    ndfb_normal_map scratch = nullptr;
    ndfb_pyramid scratch_pyramid = nullptr;

    // A null context: refused (there is no context to hold the message).
    EXPECT_EQ(ndfb_normal_map_load(nullptr, input.c_str(), &decode_, &scratch), inval);
    EXPECT_EQ(ndfb_normal_map_from_pixels(nullptr, buffer.data(), 12, 2, 2, 3, 0, nullptr, &scratch), inval);
    EXPECT_EQ(ndfb_fit(nullptr, map, &fit_, nullptr, nullptr, &scratch_pyramid), inval);
    EXPECT_EQ(ndfb_bake(nullptr, input.c_str(), path("o").c_str(), nullptr, &fit_, nullptr, nullptr, nullptr, nullptr), inval);
    EXPECT_EQ(ndfb_pyramid_write(nullptr, pyramid, map, path("o").c_str(), nullptr, nullptr, nullptr, nullptr), inval);
    EXPECT_EQ(ndfb_pyramid_level_stats(nullptr, pyramid, 0, NDFB_BRDF_GGX, 0.5f, 1, nullptr), inval);
    EXPECT_EQ(ndfb_effective_brdf_reference(nullptr, map, NDFB_WRAP_REPEAT, 0, 0, 0, NDFB_BRDF_GGX, 0.5f, direction,
                                            1, &value),
              inval);
    EXPECT_EQ(ndfb_texel_error(nullptr, map, pyramid, NDFB_REPR_TOKSVIG, NDFB_WRAP_REPEAT, 0, 0, 0, NDFB_BRDF_GGX,
                               0.5f, &value),
              inval);
    EXPECT_EQ(ndfb_synthesize(nullptr, "fbm", 4, 4, 0, &scratch), inval);
    EXPECT_EQ(ndfb_normal_map_save(nullptr, map, path("x.png").c_str()), inval);
    EXPECT_EQ(ndfb_describe_image(nullptr, input.c_str(), nullptr, 0, nullptr), inval);
    EXPECT_EQ(ndfb_tangents(nullptr, nullptr, 0, nullptr, 0, nullptr, 0), inval);
    EXPECT_FALSE(fs::exists(path("o")));

    // Null handles, outputs and buffers.
    uint32_t w = 0, h = 0;
    ndfb_repairs repairs;
    ndfb_level_stats stats;
    expect_error(ndfb_normal_map_load(ctx_, input.c_str(), &decode_, nullptr), inval, {"must not be null"}, "out");
    expect_error(ndfb_normal_map_load(ctx_, nullptr, &decode_, &scratch), inval, {"must not be null"}, "path");
    expect_error(ndfb_normal_map_from_pixels(ctx_, nullptr, 12, 2, 2, 3, 0, nullptr, &scratch), inval,
                 {"must not be null"}, "pixels");
    expect_error(ndfb_fit(ctx_, nullptr, &fit_, nullptr, nullptr, &scratch_pyramid), inval, {"must not be null"}, "map");
    expect_error(ndfb_fit(ctx_, map, nullptr, nullptr, nullptr, &scratch_pyramid), inval, {"fit options is null"}, "fit options");
    expect_error(ndfb_bake(ctx_, input.c_str(), path("o").c_str(), &decode_, nullptr, nullptr, nullptr, nullptr, nullptr), inval,
                 {"must not be null"}, "bake fit");
    expect_error(ndfb_bake(ctx_, input.c_str(), nullptr, &decode_, &fit_, nullptr, nullptr, nullptr, nullptr), inval, {"must not be null"},
                 "bake out");
    expect_error(ndfb_pyramid_write(ctx_, nullptr, map, path("o").c_str(), nullptr, nullptr, nullptr, nullptr), inval,
                 {"pyramid is null"}, "write pyramid");
    expect_error(ndfb_pyramid_level_stats(ctx_, pyramid, 0, NDFB_BRDF_GGX, 0.5f, 1, nullptr), inval,
                 {"must not be null"}, "stats out");
    expect_error(ndfb_effective_brdf_reference(ctx_, map, NDFB_WRAP_REPEAT, 0, 0, 0, NDFB_BRDF_GGX, 0.5f, nullptr, 1,
                                               &value),
                 inval, {"null argument"}, "directions");
    expect_error(ndfb_texel_error(ctx_, map, nullptr, NDFB_REPR_VMF_MIXTURE, NDFB_WRAP_REPEAT, 0, 0, 0,
                                  NDFB_BRDF_GGX, 0.5f, &value),
                 inval, {"pyramid is null"}, "texel error pyramid");
    expect_error(ndfb_describe_image(ctx_, input.c_str(), nullptr, 16, nullptr), inval, {"must not be null"},
                 "describe text");
    expect_error(ndfb_synthesize(ctx_, nullptr, 4, 4, 0, &scratch), inval, {"must not be null"}, "pattern");
    EXPECT_EQ(ndfb_normal_map_size(nullptr, &w, &h), inval);
    EXPECT_EQ(ndfb_normal_map_size(map, nullptr, &h), inval);
    EXPECT_EQ(ndfb_normal_map_read(nullptr, buffer.data(), 8 * 8 * 3), inval);
    EXPECT_EQ(ndfb_normal_map_read(map, nullptr, 8 * 8 * 3), inval);
    EXPECT_EQ(ndfb_normal_map_repairs(nullptr, &repairs), inval);
    EXPECT_EQ(ndfb_normal_map_repairs(map, nullptr), inval);
    EXPECT_EQ(ndfb_pyramid_level_size(nullptr, 0, &w, &h), inval);
    EXPECT_EQ(ndfb_pyramid_read_lobe(nullptr, 0, 0, buffer.data(), 8 * 8 * 4), inval);
    EXPECT_EQ(ndfb_pyramid_read_lobe(pyramid, 0, 0, nullptr, 8 * 8 * 4), inval);
    EXPECT_EQ(ndfb_pyramid_level_count(nullptr), 0u);
    EXPECT_EQ(ndfb_pyramid_lobe_slots(nullptr), 0u);
    ndfb_normal_map_destroy(nullptr);
    ndfb_pyramid_destroy(nullptr);
    ndfb_context_destroy(nullptr);
    ndfb_decode_options_init(nullptr);
    ndfb_fit_options_init(nullptr);
    ndfb_write_options_init(nullptr);
    EXPECT_STREQ(ndfb_status_name(ndfb_status(99)), "unknown status");

    // Sizes that do not match.
    EXPECT_EQ(ndfb_normal_map_read(map, buffer.data(), 8 * 8 * 3 - 1), inval);
    EXPECT_EQ(ndfb_normal_map_read(map, buffer.data(), 8 * 8 * 3 + 1), inval);
    EXPECT_EQ(ndfb_pyramid_read_lobe(pyramid, 0, 0, buffer.data(), 8 * 8 * 4 - 4), inval);
    EXPECT_EQ(ndfb_pyramid_read_lobe(pyramid, 1, 0, buffer.data(), 8 * 8 * 4), inval);  // level 1 is 4x4
    EXPECT_EQ(ndfb_pyramid_read_lobe(pyramid, 99, 0, buffer.data(), 4), inval);
    EXPECT_EQ(ndfb_pyramid_read_lobe(pyramid, 0, 2, buffer.data(), 8 * 8 * 4), inval);  // 2 slots
    EXPECT_EQ(ndfb_pyramid_level_size(pyramid, 4, &w, &h), inval);  // 8x8 has levels 0..3
    expect_error(ndfb_normal_map_from_pixels(ctx_, buffer.data(), 11, 2, 2, 3, 0, nullptr, &scratch), inval,
                 {"pixel count 11 does not match 2x2x3"}, "pixel count");
    expect_error(ndfb_normal_map_from_pixels(ctx_, buffer.data(), 0, 0, 2, 3, 0, nullptr, &scratch), inval,
                 {"image size must be 1..65536 per side, got 0x2"}, "zero width");
    expect_error(ndfb_normal_map_from_pixels(ctx_, buffer.data(), 3 * 70000, 70000, 1, 3, 0, nullptr, &scratch), inval,
                 {"image size must be 1..65536 per side, got 70000x1"}, "huge width");
    expect_error(ndfb_pyramid_level_stats(ctx_, pyramid, 9, NDFB_BRDF_GGX, 0.5f, 1, &stats), inval,
                 {"level 9 does not exist (the pyramid has 4)"}, "stats level");
    expect_error(ndfb_texel_error(ctx_, map, pyramid, NDFB_REPR_TOKSVIG, NDFB_WRAP_REPEAT, 1, 4, 0, NDFB_BRDF_GGX,
                                  0.5f, &value),
                 inval, {"texel outside the level"}, "texel");
    expect_error(ndfb_texel_error(ctx_, map, pyramid, ndfb_representation(42), NDFB_WRAP_REPEAT, 0, 0, 0,
                                  NDFB_BRDF_GGX, 0.5f, &value),
                 inval, {"unknown representation"}, "representation");
    // Enum arguments out of range, as a C or ctypes caller can pass them.
    expect_error(ndfb_pyramid_level_stats(ctx_, pyramid, 0, ndfb_brdf(-1), 0.5f, 1, &stats), inval,
                 {"unknown BRDF -1"}, "stats brdf");
    expect_error(ndfb_effective_brdf_reference(ctx_, map, ndfb_wrap(12345), 0, 0, 0, NDFB_BRDF_GGX, 0.5f, direction,
                                               1, &value),
                 inval, {"unknown wrap mode 12345"}, "reference wrap");
    expect_error(ndfb_synthesize(ctx_, "plaid", 4, 4, 0, &scratch), inval, {"unknown pattern 'plaid'"}, "pattern name");
    expect_error(ndfb_synthesize(ctx_, "fbm", 0, 4, 0, &scratch), inval, {"texels per side"}, "pattern size");
    ndfb_normal_map other = nullptr;
    ASSERT_EQ(ndfb_synthesize(ctx_, "fbm", 4, 4, 0, &other), NDFB_OK);
    expect_error(ndfb_pyramid_write(ctx_, pyramid, other, path("o").c_str(), nullptr, nullptr, nullptr, nullptr), inval,
                 {"the pyramid was fitted to a map of another size"}, "write map size");
    expect_error(ndfb_texel_error(ctx_, other, pyramid, NDFB_REPR_VMF_MIXTURE, NDFB_WRAP_REPEAT, 0, 0, 0,
                                  NDFB_BRDF_GGX, 0.5f, &value),
                 inval, {"the pyramid was fitted to a map of another size"}, "texel error map size");
    EXPECT_FALSE(fs::exists(path("o")));

    // A describe buffer too small is truncated and NUL-terminated, never overrun.
    char small[8];
    std::memset(small, 'z', sizeof small);
    size_t length = 0;
    ASSERT_EQ(ndfb_describe_image(ctx_, input.c_str(), small, 5, &length), NDFB_OK);
    EXPECT_EQ(std::string(small), "file");
    EXPECT_EQ(small[5], 'z');
    EXPECT_GT(length, 5u);

    // A success clears the previous message.
    EXPECT_EQ(ndfb_normal_map_size(map, &w, &h), NDFB_OK);
    ASSERT_EQ(ndfb_describe_image(ctx_, input.c_str(), nullptr, 0, &length), NDFB_OK);
    EXPECT_STREQ(ndfb_last_error(ctx_), "");

    ndfb_normal_map_destroy(other);
    ndfb_pyramid_destroy(pyramid);
    ndfb_normal_map_destroy(map);
}

// ndfbake.h: a call that creates an object writes NULL to its output handle on any failure, from
// the first argument check (a null or destroyed context included) to a failure deep in the call,
// so the handle can always be passed to its destroy function afterwards.
TEST_F(HostileInputs, AFailedCallLeavesItsOutputHandleNull)
{
    const std::string input = synth_png("in.png", 8);
    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_normal_map_load(ctx_, input.c_str(), &decode_, &map), NDFB_OK) << error();
    ndfb_context dead = nullptr;
    ASSERT_EQ(ndfb_context_create(&dead), NDFB_OK);
    ndfb_context_destroy(dead);
    const float pixels[3] = {0.5f, 0.5f, 1.0f};
    const ndfb_progress_fn cancel = +[](void*, const char*, float) -> int { return 1; };

    // A value no call returns: a failure must overwrite it.
    const auto stale_map = reinterpret_cast<ndfb_normal_map>(0x1);
    const auto stale_pyramid = reinterpret_cast<ndfb_pyramid>(0x1);
    for (ndfb_context ctx : {ndfb_context(nullptr), dead, ctx_}) {
        const std::string which = ctx == nullptr ? "null context" : ctx == dead ? "destroyed context" : "context";
        ndfb_normal_map m = stale_map;
        EXPECT_NE(ndfb_normal_map_load(ctx, nullptr, &decode_, &m), NDFB_OK);
        EXPECT_EQ(m, nullptr) << "load, " << which;
        m = stale_map;
        EXPECT_NE(ndfb_normal_map_from_pixels(ctx, pixels, 2, 1, 1, 3, 0, &decode_, &m), NDFB_OK);
        EXPECT_EQ(m, nullptr) << "from_pixels, " << which;
        m = stale_map;
        EXPECT_NE(ndfb_synthesize(ctx, "plaid", 4, 4, 0, &m), NDFB_OK);
        EXPECT_EQ(m, nullptr) << "synthesize, " << which;
        ndfb_pyramid p = stale_pyramid;
        EXPECT_NE(ndfb_fit(ctx, nullptr, &fit_, nullptr, nullptr, &p), NDFB_OK);
        EXPECT_EQ(p, nullptr) << "fit, " << which;
    }
    // Failures after the arguments were accepted: a missing file, a cancelled fit.
    ndfb_normal_map m = stale_map;
    EXPECT_EQ(ndfb_normal_map_load(ctx_, path("missing.png").c_str(), &decode_, &m), NDFB_ERROR_FILE_NOT_FOUND);
    EXPECT_EQ(m, nullptr);
    ndfb_pyramid p = stale_pyramid;
    EXPECT_EQ(ndfb_fit(ctx_, map, &fit_, cancel, nullptr, &p), NDFB_ERROR_CANCELLED);
    EXPECT_EQ(p, nullptr);
    ndfb_normal_map_destroy(map);
}

TEST_F(HostileInputs, ADestroyedContextIsRefusedNotUsed)
{
    const std::string input = synth_png("in.png", 8);
    ndfb_context dead = nullptr;
    ASSERT_EQ(ndfb_context_create(&dead), NDFB_OK);
    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_normal_map_load(dead, input.c_str(), &decode_, &map), NDFB_OK);
    ndfb_context_destroy(dead);

    // Every call refuses it without touching it (AddressSanitizer would see any use).
    ndfb_normal_map other = nullptr;
    ndfb_pyramid pyramid = nullptr;
    EXPECT_EQ(ndfb_normal_map_load(dead, input.c_str(), &decode_, &other), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(ndfb_fit(dead, map, &fit_, nullptr, nullptr, &pyramid), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(ndfb_bake(dead, input.c_str(), path("out").c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr),
              NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(ndfb_synthesize(dead, "fbm", 4, 4, 0, &other), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(ndfb_tangents(dead, nullptr, 0, nullptr, 0, nullptr, 0), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(other, nullptr);
    EXPECT_EQ(pyramid, nullptr);
    EXPECT_FALSE(fs::exists(path("out")));
    EXPECT_NE(std::string(ndfb_last_error(dead)).find("the context was destroyed"), std::string::npos);
    ndfb_context_destroy(dead);  // a second destroy is ignored

    // Objects made through it outlive it, and other contexts are unaffected.
    uint32_t w = 0, h = 0;
    EXPECT_EQ(ndfb_normal_map_size(map, &w, &h), NDFB_OK);
    EXPECT_EQ(ndfb_fit(ctx_, map, &fit_, nullptr, nullptr, &pyramid), NDFB_OK) << error();
    ndfb_pyramid_destroy(pyramid);
    ndfb_normal_map_destroy(map);
}

}  // namespace
}  // namespace ndfbake
