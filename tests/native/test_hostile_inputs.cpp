// Hostile inputs through the public C API (issue 6): headers that claim huge sizes, empty and
// truncated files, NaN/Inf/huge EXR values, wrong channel counts, unusual paths, read-only and
// full output folders, options out of range and misuse of the API. Each gets a specific status and
// a one-line message naming the problem, and no bake leaves a file behind.
//
// Read-only and full folders are simulated in a forked child so the test process is untouched:
// - read-only: a tmpfs mounted read-only in a private mount namespace (EROFS) where the sandbox
//   allows mount(2), and a folder without write permission (EACCES), as root without
//   CAP_DAC_OVERRIDE (root ignores permission bits);
// - full: RLIMIT_FSIZE makes every write past the limit fail with EFBIG, exactly as a full disk
//   fails a write (portable, needs no privilege); and a small tmpfs (ENOSPC) where mount(2) works.
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
#include "ndfbake.h"
#include "synth/patterns.h"
#include "test_support.h"

namespace ndfbake {
namespace {

namespace fs = std::filesystem;

void write_bytes(const std::string& path, const std::string& bytes)
{
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

std::string read_bytes(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Every entry under `folder`, hidden ones included.
std::set<std::string> entries(const std::string& folder)
{
    std::set<std::string> names;
    if (!fs::exists(folder)) return names;
    for (const auto& e : fs::recursive_directory_iterator(folder)) names.insert(e.path().string());
    return names;
}

// ---- crafted files ---------------------------------------------------------------------------

uint32_t crc32(const std::string& bytes)
{
    uint32_t crc = 0xffffffffu;
    for (unsigned char b : bytes) {
        crc ^= b;
        for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

std::string be32(uint32_t v)
{
    return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
}

std::string png_chunk(const std::string& type, const std::string& data)
{
    return be32(uint32_t(data.size())) + type + data + be32(crc32(type + data));
}

// A valid PNG header (8-bit RGB) claiming width x height, then an IDAT holding a tiny zlib stream
// (one stored block of 4 zero bytes) and IEND: a reader learns the size, then finds no pixels.
std::string png_claiming(uint32_t width, uint32_t height)
{
    const std::string ihdr = be32(width) + be32(height) + std::string("\x08\x02\x00\x00\x00", 5);
    const std::string zlib_stream("\x78\x01\x01\x04\x00\xfb\xff\x00\x00\x00\x00\x00\x04\x00\x01", 15);
    return std::string("\x89PNG\r\n\x1a\n", 8) + png_chunk("IHDR", ihdr) + png_chunk("IDAT", zlib_stream) +
           png_chunk("IEND", "");
}

std::string le32(int32_t v)
{
    const auto u = uint32_t(v);
    return {char(u), char(u >> 8), char(u >> 16), char(u >> 24)};
}

std::string exr_attribute(const std::string& name, const std::string& type, const std::string& value)
{
    return name + '\0' + type + '\0' + le32(int32_t(value.size())) + value;
}

// An uncompressed scanline EXR header (half RGB) claiming width x height, with its line offset
// table all zeros and no pixel data.
std::string exr_claiming(int32_t width, int32_t height)
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
void write_image(const std::string& path, int width, int height, int channels, OIIO::TypeDesc type,
                 const std::vector<float>& values)
{
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out) << OIIO::geterror();
    const OIIO::ImageSpec spec(width, height, channels, type);
    ASSERT_TRUE(out->open(path, spec)) << out->geterror();
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, values.data())) << out->geterror();
    ASSERT_TRUE(out->close());
}

// ---- child processes -------------------------------------------------------------------------

// What a child reports: a status (or kSkipped) and a message.
struct ChildReport {
    int status = -1;
    std::string message;
};
constexpr int kSkipped = -2;

// A bake run in a child process, in the conditions `setup` creates there (rlimits, a mount
// namespace, another user). The child is this test binary started afresh (fork, setup, exec), so
// it inherits no threads: a forked copy of a process whose OpenEXR thread pool is running would
// hang on its first EXR. It bakes `earlier` (if any) into `out` first, then `input`, and reports
// the second bake's status and message, flagging any change the failed bake made to the folder.
// `setup` runs between fork and exec, so it allocates nothing: it returns null, or the name of the
// step that failed (errno tells why), which makes the child report kSkipped.
ChildReport bake_in_child(const std::function<const char*()>& setup, const std::string& input,
                          const std::string& out, const std::string& earlier = {})
{
    int fds[2];
    if (::pipe(fds) != 0) return {-1, "pipe failed"};
    // Everything the child needs, built before fork: after it only system calls are made.
    std::vector<std::string> env_strings = {"NDFB_CHILD_FD=" + std::to_string(fds[1]), "NDFB_CHILD_INPUT=" + input,
                                            "NDFB_CHILD_OUT=" + out, "NDFB_CHILD_EARLIER=" + earlier};
    for (char** e = environ; *e; ++e) env_strings.emplace_back(*e);
    std::vector<char*> envp;
    for (std::string& e : env_strings) envp.push_back(e.data());
    envp.push_back(nullptr);
    std::string exe = "/proc/self/exe", filter = "--gtest_filter=HostileChild.DISABLED_Bake",
                disabled = "--gtest_also_run_disabled_tests";
    char* argv[] = {exe.data(), filter.data(), disabled.data(), nullptr};

    const pid_t pid = ::fork();
    if (pid == 0) {
        ::close(fds[0]);
        if (const char* failed = setup()) {
            char payload[256];
            const int n = std::snprintf(payload, sizeof payload, "%d\n%s: %s", kSkipped, failed, std::strerror(errno));
            ssize_t written = ::write(fds[1], payload, size_t(std::max(0, std::min(n, int(sizeof payload) - 1))));
            (void)written;
            ::_exit(0);
        }
        const int null = ::open("/dev/null", O_WRONLY);
        if (null >= 0) ::dup2(null, STDOUT_FILENO);
        ::execve(argv[0], argv, envp.data());
        ::_exit(127);
    }
    ::close(fds[1]);
    std::string payload;
    char buffer[512];
    for (ssize_t n; (n = ::read(fds[0], buffer, sizeof buffer)) > 0;) payload.append(buffer, size_t(n));
    ::close(fds[0]);
    int wait_status = 0;
    ::waitpid(pid, &wait_status, 0);
    const size_t newline = payload.find('\n');
    if (!WIFEXITED(wait_status) || WEXITSTATUS(wait_status) != 0 || newline == std::string::npos)
        return {-1, "child failed (wait status " + std::to_string(wait_status) + "): " + payload};
    return {std::stoi(payload.substr(0, newline)), payload.substr(newline + 1)};
}

// The child's side: does nothing unless started by bake_in_child.
TEST(HostileChild, DISABLED_Bake)
{
    const char* fd = std::getenv("NDFB_CHILD_FD");
    if (!fd) GTEST_SKIP() << "run by the hostile-input tests in a child process";
    const std::string input = std::getenv("NDFB_CHILD_INPUT"), out = std::getenv("NDFB_CHILD_OUT"),
                      earlier = std::getenv("NDFB_CHILD_EARLIER");
    ndfb_context ctx = nullptr;
    ASSERT_EQ(ndfb_context_create(&ctx), NDFB_OK);
    ndfb_fit_options fit;
    ndfb_fit_options_init(&fit);
    fit.max_lobes = 2;
    fit.threads = 2;
    std::string problems;
    std::set<std::string> before;
    std::string report;
    if (!earlier.empty()) {
        if (ndfb_bake(ctx, earlier.c_str(), out.c_str(), nullptr, &fit, nullptr) != NDFB_OK)
            problems += std::string(" [the earlier bake failed: ") + ndfb_last_error(ctx) + "]";
        before = entries(out);
        report = read_bytes(out + "/report.json");
    }
    const ndfb_status status = ndfb_bake(ctx, input.c_str(), out.c_str(), nullptr, &fit, nullptr);
    std::string message = ndfb_last_error(ctx);
    if (entries(out) != before) message += " [the folder's files changed]";
    if (!earlier.empty() && read_bytes(out + "/report.json") != report) message += " [the earlier report changed]";
    const std::string payload = std::to_string(int(status)) + "\n" + message + problems;
    ssize_t written = ::write(std::atoi(fd), payload.data(), payload.size());
    (void)written;
    ndfb_context_destroy(ctx);
}

// In the child: a private mount namespace with a tmpfs at `dir`; the failed step where mount is
// not allowed (no CAP_SYS_ADMIN, a container that forbids it).
const char* mount_private_tmpfs(const std::string& dir, const char* options, unsigned long flags)
{
    if (::unshare(CLONE_NEWNS) != 0) return "unshare(CLONE_NEWNS)";
    if (::mount("none", "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0) return "mount --make-rprivate /";
    if (::mount("ndfbake-test", dir.c_str(), "tmpfs", flags, options) != 0) return "mount tmpfs";
    return nullptr;
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
        expect_error(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit_, &write_), expected, parts,
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

// ---- sizes and memory ------------------------------------------------------------------------

TEST_F(HostileInputs, HeadersClaimingHugeImagesAreRefusedBeforeAnyPixelIsRead)
{
    // 10^10 pixels: over max_pixels (2^28 by default), refused from the header alone; reading
    // would instead find the pixel data missing (corrupt file).
    write_bytes(path("huge.png"), png_claiming(100000, 100000));
    write_bytes(path("huge.exr"), exr_claiming(100000, 100000));
    for (const char* name : {"huge.png", "huge.exr"}) {
        const std::string file = path(name);
        expect_load_error(file, NDFB_ERROR_OUT_OF_MEMORY,
                          {file, "100000 x 100000 = 10000000000 pixels", "over the limit of 268435456"}, name);
        expect_bake_error(file, NDFB_ERROR_OUT_OF_MEMORY, {file, "100000 x 100000"}, name);
    }
    // TGA headers stop at 65535.
    const unsigned char tga[18] = {0, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0xff, 0xff, 0xff, 24, 0x20};
    write_bytes(path("huge.tga"), std::string(reinterpret_cast<const char*>(tga), 18));
    expect_bake_error(path("huge.tga"), NDFB_ERROR_OUT_OF_MEMORY, {"65535 x 65535"}, "huge.tga");

    // The caller's own pixel limit.
    decode_.max_pixels = 1000;
    const std::string small = synth_png("small.png", 64);
    expect_bake_error(small, NDFB_ERROR_OUT_OF_MEMORY, {"64 x 64 = 4096 pixels", "over the limit of 1000"},
                      "max_pixels");
}

TEST_F(HostileInputs, ABakeOverTheMemoryLimitIsRefusedUpFrontWithTheEstimate)
{
    // A header alone (no pixel data) claiming 4096 x 4096: refused for memory, not found
    // truncated, so the check ran before decoding.
    write_bytes(path("big.png"), png_claiming(4096, 4096));
    fit_.max_memory_bytes = 64ull << 20;
    fit_.max_lobes = 4;
    expect_bake_error(path("big.png"), NDFB_ERROR_OUT_OF_MEMORY,
                      {path("big.png"), "4096 x 4096 map with 4 lobe slots needs an estimated",
                       "over the memory limit of 67108864 bytes (64.0 MiB)", "max_memory_bytes"},
                      "memory limit");

    // ndfb_fit checks the same budget for a map already in memory.
    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_synthesize(ctx_, "bumps", 512, 512, 1, &map), NDFB_OK);
    fit_.max_memory_bytes = 1ull << 20;
    ndfb_pyramid pyramid = reinterpret_cast<ndfb_pyramid>(0x1);
    expect_error(ndfb_fit(ctx_, map, &fit_, &pyramid), NDFB_ERROR_OUT_OF_MEMORY,
                 {"cannot fit the map", "512 x 512", "over the memory limit of 1048576 bytes"}, "fit limit");
    EXPECT_EQ(pyramid, nullptr);
    ndfb_normal_map_destroy(map);

    // Within the limit: the bake runs and its report gives the estimate and the measured peak.
    fit_.max_memory_bytes = 1ull << 30;
    const std::string input = synth_png("ok.png", 32);
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), path("ok").c_str(), &decode_, &fit_, &write_), NDFB_OK) << error();
    const std::string report = read_bytes(path("ok/report.json"));
    for (const char* key : {"\"peak_memory_bytes\": ", "\"estimated_memory_bytes\": ", "\"memory_limit_bytes\": 1073741824"})
        EXPECT_NE(report.find(key), std::string::npos) << key;
    EXPECT_EQ(report.find("\"peak_memory_bytes\": 0,"), std::string::npos);
}

// ---- damaged files ---------------------------------------------------------------------------

TEST_F(HostileInputs, ZeroLengthFilesAreCorrupt)
{
    for (const char* name : {"empty.png", "empty.exr", "empty.tga", "empty.tif", "empty.jpg", "empty"}) {
        write_bytes(path(name), "");
        expect_load_error(path(name), NDFB_ERROR_CORRUPT_FILE, {path(name), "file is empty (0 bytes)"}, name);
        expect_bake_error(path(name), NDFB_ERROR_CORRUPT_FILE, {path(name), "file is empty (0 bytes)"}, name);
    }
}

TEST_F(HostileInputs, TruncatedFilesAreCorrupt)
{
    const NormalMap map = synthesize(Pattern::bumps, 64, 64);
    std::vector<float> rgb(map.normals.size() * 3);
    for (size_t i = 0; i < map.normals.size(); ++i)
        for (int c = 0; c < 3; ++c) rgb[i * 3 + size_t(c)] = 0.5f + 0.5f * map.normals[i][c];
    write_image(path("full.png"), 64, 64, 3, OIIO::TypeDesc::UINT8, rgb);
    write_image(path("full.tga"), 64, 64, 3, OIIO::TypeDesc::UINT8, rgb);
    write_image(path("full.tif"), 64, 64, 3, OIIO::TypeDesc::UINT16, rgb);
    write_image(path("full.jpg"), 64, 64, 3, OIIO::TypeDesc::UINT8, rgb);
    write_image(path("full.exr"), 64, 64, 3, OIIO::TypeDesc::HALF, rgb);
    for (const std::string ext : {"png", "tga", "tif", "jpg", "exr"}) {
        const std::string bytes = read_bytes(path("full." + ext));
        // Cut inside the pixel data: the header reads, the pixels do not.
        const std::string half = path("half." + ext);
        write_bytes(half, bytes.substr(0, bytes.size() / 2));
        expect_load_error(half, NDFB_ERROR_CORRUPT_FILE, {half, "truncated"}, "half " + ext);
        expect_bake_error(half, NDFB_ERROR_CORRUPT_FILE, {half, "truncated"}, "half " + ext);
        // Cut inside the header: the file does not open as its format.
        const std::string stub = path("stub." + ext);
        write_bytes(stub, bytes.substr(0, 12));
        expect_load_error(stub, NDFB_ERROR_CORRUPT_FILE, {stub, "damaged, or not really a ." + ext + " file"},
                          "stub " + ext);
        expect_bake_error(stub, NDFB_ERROR_CORRUPT_FILE, {stub}, "stub " + ext);
    }
}

TEST_F(HostileInputs, ExrWithNanInfNegativeAndHugeValuesIsRepairedAndCounted)
{
    // Such values are a documented input, not an error: each texel is repaired (docs/lobe-format.md: NaN/Inf
    // or too short -> +Z, z < 0 -> -z, then normalized), counted, and the bake's output is finite.
    const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
    std::vector<float> rgb(8 * 8 * 3);
    for (size_t i = 0; i < rgb.size(); i += 3) rgb[i] = 0.0f, rgb[i + 1] = 0.0f, rgb[i + 2] = 1.0f;
    const std::vector<std::vector<float>> special = {
        {nan, 0.0f, 1.0f},          // non-finite
        {inf, 0.0f, 1.0f},          // non-finite
        {0.0f, -inf, 1.0f},         // non-finite
        {0.6f, 0.0f, -0.8f},        // below the horizon (unit length)
        {1e30f, 0.0f, 1e30f},       // huge: renormalized
        {-FLT_MAX, FLT_MAX, FLT_MAX},  // huge and negative: renormalized
        {1e-30f, 1e-30f, 1e-30f},   // too short: +Z
        {3.0f, 0.0f, 4.0f},         // length 5: renormalized
    };
    for (size_t k = 0; k < special.size(); ++k)
        for (int c = 0; c < 3; ++c) rgb[k * 3 + size_t(c)] = special[k][size_t(c)];
    write_image(path("float.exr"), 8, 8, 3, OIIO::TypeDesc::FLOAT, rgb);

    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_normal_map_load(ctx_, path("float.exr").c_str(), &decode_, &map), NDFB_OK) << error();
    ndfb_repairs repairs{};
    ASSERT_EQ(ndfb_normal_map_repairs(map, &repairs), NDFB_OK);
    EXPECT_EQ(repairs.non_finite, 3u);
    EXPECT_EQ(repairs.zero_length, 1u);
    EXPECT_EQ(repairs.below_horizon, 1u);
    EXPECT_EQ(repairs.renormalized, 3u);
    std::vector<float> normals(8 * 8 * 3);
    ASSERT_EQ(ndfb_normal_map_read(map, normals.data(), normals.size()), NDFB_OK);
    for (size_t i = 0; i < normals.size(); i += 3) {
        const float len = std::sqrt(normals[i] * normals[i] + normals[i + 1] * normals[i + 1] +
                                    normals[i + 2] * normals[i + 2]);
        EXPECT_TRUE(std::isfinite(len) && std::abs(len - 1.0f) < 1e-5f && normals[i + 2] >= 0.0f) << i / 3;
    }
    ndfb_normal_map_destroy(map);

    // Half EXR: Inf, the largest half, NaN; and a 2-channel float file whose z is rebuilt.
    std::vector<float> half(4 * 4 * 3, 0.5f);
    half[0] = inf, half[4] = 65504.0f, half[8] = nan, half[9] = -65504.0f;
    write_image(path("half.exr"), 4, 4, 3, OIIO::TypeDesc::HALF, half);
    std::vector<float> xy(4 * 4 * 2, 0.0f);
    xy[0] = nan, xy[3] = 1e30f, xy[4] = -inf;
    write_image(path("xy.exr"), 4, 4, 2, OIIO::TypeDesc::FLOAT, xy);

    for (const char* name : {"float.exr", "half.exr", "xy.exr"}) {
        const std::string out = path(std::string("out-") + name);
        ASSERT_EQ(ndfb_bake(ctx_, path(name).c_str(), out.c_str(), &decode_, &fit_, &write_), NDFB_OK)
            << name << ": " << error();
        const std::string report = read_bytes(out + "/report.json");
        EXPECT_EQ(report.find("\"non_finite\": 0,"), std::string::npos) << name << ": repairs not reported";
        for (const auto& entry : fs::directory_iterator(out)) {
            if (entry.path().extension() != ".exr") continue;
            auto in = OIIO::ImageInput::open(entry.path().string());
            ASSERT_TRUE(in);
            std::vector<float> pixels(size_t(in->spec().image_pixels()) * size_t(in->spec().nchannels));
            ASSERT_TRUE(in->read_image(0, 0, 0, in->spec().nchannels, OIIO::TypeDesc::FLOAT, pixels.data()));
            for (float v : pixels) ASSERT_TRUE(std::isfinite(v)) << entry.path();
        }
    }
}

TEST_F(HostileInputs, HorizonNormalsGiveFiniteErrorsUnderEveryBrdf)
{
    // Found by fuzz_bake (corpus/bake/beckmann_horizon_nan): a 13 x 16 map of +Z with texels on
    // the horizon (as the repair leaves x = +-1 texels) gave lobes whose Beckmann-convolved
    // distribution was evaluated just above the horizon, where exp() and c^4 both underflow:
    // 0/0 = NaN in the texel errors, the lobe budget and report.json.
    std::vector<float> pixels(13 * 16 * 3, 0.0f);
    for (size_t i = 2; i < pixels.size(); i += 3) pixels[i] = 1.0f;
    const struct {
        int texel;
        float x, y;
    } horizon[] = {{15, 1, 0},   {29, 6.47306442e-05f, 1}, {37, 0, -1},  {44, 1, 0},   {52, 0, -1},  {59, 1, 0},
                   {60, 0, -1},  {66, 1, 0},   {67, -1, 0},  {74, 0, 1},   {81, 1, 0},   {82, -1, 0},  {104, 1, 0},
                   {118, 6.47306442e-05f, 1}, {126, 0, -1}, {133, 1, 0},  {141, 0, -1}, {148, 1, 0},  {149, 0, -1},
                   {155, 1, 0},  {156, -1, 0}, {163, 0, 1},  {170, 1, 0},  {171, -1, 0}, {193, 1, 0},
                   {207, 6.47306442e-05f, 1}};
    for (const auto& h : horizon) {
        pixels[size_t(h.texel) * 3 + 0] = h.x;
        pixels[size_t(h.texel) * 3 + 1] = h.y;
        pixels[size_t(h.texel) * 3 + 2] = 0.0f;
    }
    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_normal_map_from_pixels(ctx_, pixels.data(), pixels.size(), 13, 16, 3, 1, &decode_, &map), NDFB_OK);
    const struct {
        ndfb_brdf brdf;
        float parameter;
    } brdfs[] = {{NDFB_BRDF_BECKMANN, 1.0f}, {NDFB_BRDF_BECKMANN, 0.0001f}, {NDFB_BRDF_GGX, 1.0f},
                 {NDFB_BRDF_GGX, 0.01f}, {NDFB_BRDF_BLINN_PHONG, 1.0f}, {NDFB_BRDF_BLINN_PHONG, 10000.0f},
                 {NDFB_BRDF_LAMBERT, 0.0f}};
    for (const auto& b : brdfs) {
        fit_.brdf = b.brdf;
        fit_.brdf_parameter = b.parameter;
        fit_.max_lobes = 8;
        fit_.max_iterations = 16;
        ndfb_pyramid pyramid = nullptr;
        ASSERT_EQ(ndfb_fit(ctx_, map, &fit_, &pyramid), NDFB_OK) << error();
        for (uint32_t level = 1; level < ndfb_pyramid_level_count(pyramid); ++level) {
            float value = -1.0f;
            ASSERT_EQ(ndfb_texel_error(ctx_, map, pyramid, NDFB_REPR_VMF_MIXTURE, NDFB_WRAP_REPEAT, level, 0, 0,
                                       b.brdf, b.parameter, &value),
                      NDFB_OK);
            EXPECT_TRUE(std::isfinite(value) && value >= 0.0f) << int(b.brdf) << " " << b.parameter << " level "
                                                               << level << ": " << value;
            ndfb_level_stats stats;
            ASSERT_EQ(ndfb_pyramid_level_stats(ctx_, pyramid, level, b.brdf, b.parameter, 0, &stats), NDFB_OK);
            EXPECT_TRUE(std::isfinite(stats.mean_error) && std::isfinite(stats.p95_error)) << level;
        }
        ndfb_pyramid_destroy(pyramid);
    }
    ndfb_normal_map_destroy(map);
}

TEST_F(HostileInputs, OneOrFiveAndMoreChannelsAreUnsupported)
{
    write_image(path("grey.png"), 8, 8, 1, OIIO::TypeDesc::UINT8, std::vector<float>(64, 0.5f));
    write_image(path("grey.exr"), 8, 8, 1, OIIO::TypeDesc::HALF, std::vector<float>(64, 0.5f));
    write_image(path("five.tif"), 8, 8, 5, OIIO::TypeDesc::UINT8, std::vector<float>(8 * 8 * 5, 0.5f));
    write_image(path("six.exr"), 8, 8, 6, OIIO::TypeDesc::FLOAT, std::vector<float>(8 * 8 * 6, 0.5f));
    const struct {
        const char* name;
        const char* says;
    } cases[] = {{"grey.png", "1 channel;"}, {"grey.exr", "1 channel;"}, {"five.tif", "5 channels;"},
                 {"six.exr", "6 channels;"}};
    for (const auto& c : cases) {
        const std::string file = path(c.name);
        expect_load_error(file, NDFB_ERROR_UNSUPPORTED_FORMAT,
                          {file, c.says, "a normal map needs 2 (XY), 3 (XYZ) or 4 (XYZ + alpha)"}, c.name);
        expect_bake_error(file, NDFB_ERROR_UNSUPPORTED_FORMAT, {file, c.says}, c.name);
    }
    // The same from memory, and no channels at all.
    const std::vector<float> pixels(4 * 4 * 5, 0.5f);
    for (uint32_t channels : {0u, 1u, 5u}) {
        ndfb_normal_map map = nullptr;
        expect_error(ndfb_normal_map_from_pixels(ctx_, pixels.data(), 16 * size_t(channels), 4, 4, channels, 0,
                                                 &decode_, &map),
                     NDFB_ERROR_UNSUPPORTED_FORMAT,
                     {"in-memory pixels", std::to_string(channels) + (channels == 1 ? " channel;" : " channels;")},
                     std::to_string(channels) + " channels in memory");
        EXPECT_EQ(map, nullptr);
    }
}

// ---- paths -----------------------------------------------------------------------------------

TEST_F(HostileInputs, PathsWithSpacesAndNonAsciiCharactersWork)
{
    const std::string folder = path("maps with spaces/Ñandú 法线 😀");
    fs::create_directories(folder);
    const std::string input = folder + "/normal map é ü.png";
    write_normal_map(input, synthesize(Pattern::bumps, 16, 16));
    const std::string out = path("out folder/résultat 出力");
    ASSERT_EQ(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit_, &write_), NDFB_OK) << error();
    EXPECT_TRUE(fs::exists(out + "/level00_lobe0.exr"));
    EXPECT_NE(read_bytes(out + "/report.json").find("normal map é ü.png"), std::string::npos);
    char text[4096];
    size_t length = 0;
    ASSERT_EQ(ndfb_describe_image(ctx_, (out + "/level01_lobe1.exr").c_str(), text, sizeof text, &length), NDFB_OK);
    EXPECT_NE(std::string(text).find("résultat 出力"), std::string::npos);

    // Errors name the path exactly as given.
    const std::string missing = folder + "/n’existe pas.png";
    expect_bake_error(missing, NDFB_ERROR_FILE_NOT_FOUND, {"cannot read '" + missing + "': no such file"}, "missing");
    const std::string damaged = folder + "/abîmé 壊れた.png";
    write_bytes(damaged, std::string(100, 'x'));
    expect_bake_error(damaged, NDFB_ERROR_CORRUPT_FILE, {"cannot read '" + damaged + "'"}, "damaged");

    // And the same for saving a map.
    ndfb_normal_map map = nullptr;
    ASSERT_EQ(ndfb_synthesize(ctx_, "weave", 8, 8, 0, &map), NDFB_OK);
    EXPECT_EQ(ndfb_normal_map_save(ctx_, map, (folder + "/tissé 織物.tga").c_str()), NDFB_OK) << error();
    EXPECT_TRUE(fs::exists(folder + "/tissé 織物.tga"));
    ndfb_normal_map_destroy(map);

    // A name that is not UTF-8 (Latin-1 "é"): the bake works and report.json stays UTF-8, the
    // byte replaced by U+FFFD.
    const std::string latin1 = path("carte \xe9.png");
    write_normal_map(latin1, synthesize(Pattern::bumps, 8, 8));
    ASSERT_EQ(ndfb_bake(ctx_, latin1.c_str(), path("latin1").c_str(), &decode_, &fit_, &write_), NDFB_OK) << error();
    const std::string report = read_bytes(path("latin1") + "/report.json");
    EXPECT_NE(report.find("carte \\ufffd.png"), std::string::npos);
    EXPECT_EQ(report.find('\xe9'), std::string::npos);
}

// ---- output folders --------------------------------------------------------------------------

TEST_F(HostileInputs, AnOutputPathThatCannotBeAFolderIsAnIoError)
{
    const std::string input = synth_png("in.png", 16);
    const std::string under_file = input + "/out";
    expect_error(ndfb_bake(ctx_, input.c_str(), under_file.c_str(), &decode_, &fit_, &write_), NDFB_ERROR_IO,
                 {"output folder '" + under_file + "' is not writable"}, "folder under a file");
    expect_error(ndfb_bake(ctx_, input.c_str(), input.c_str(), &decode_, &fit_, &write_), NDFB_ERROR_IO,
                 {"output folder '" + input + "' is not writable"}, "folder is a file");
    EXPECT_EQ(read_bytes(input).substr(1, 3), "PNG");  // untouched
}

TEST_F(HostileInputs, AReadOnlyOutputFolderIsAnIoErrorAndNothingIsWritten)
{
    const std::string input = synth_png("in.png", 16);
    const std::string locked = path("locked");
    fs::create_directories(locked);

    // Permission bits (EACCES). Root passes them through CAP_DAC_OVERRIDE, so as root the child
    // drops that capability from its bounding set (kept across exec, and the test binary stays
    // reachable whatever the permissions of the folders above it); without CAP_SETPCAP it becomes
    // user nobody instead.
    ::chmod(locked.c_str(), 0555);
    const bool root = ::geteuid() == 0;
    ChildReport r = bake_in_child(
        [root]() -> const char* {
            if (!root) return nullptr;
            if (::prctl(PR_CAPBSET_DROP, CAP_DAC_OVERRIDE, 0, 0, 0) == 0 &&
                ::prctl(PR_CAPBSET_DROP, CAP_DAC_READ_SEARCH, 0, 0, 0) == 0 &&
                ::prctl(PR_CAPBSET_DROP, CAP_FOWNER, 0, 0, 0) == 0)
                return nullptr;
            if (::setgid(testing_support::kNobodyGid) != 0 || ::setuid(testing_support::kNobodyUid) != 0)
                return "drop CAP_DAC_OVERRIDE or become user nobody";
            return nullptr;
        },
        input, locked + "/out");
    ::chmod(locked.c_str(), 0755);
    EXPECT_EQ(r.status, NDFB_ERROR_IO) << r.message;
    EXPECT_NE(r.message.find("output folder '" + locked + "/out' is not writable: Permission denied"),
              std::string::npos)
        << r.message;
    EXPECT_EQ(r.message.find(" [the"), std::string::npos) << r.message;
    EXPECT_TRUE(listing(locked).empty());

    // A read-only file system (EROFS), where this sandbox allows mount(2).
    const std::string ro = path("ro");
    fs::create_directories(ro);
    r = bake_in_child([&] { return mount_private_tmpfs(ro, "size=1m", MS_RDONLY); }, input, ro);
    if (r.status == kSkipped) {
        std::printf("read-only tmpfs not tested here: %s\n", r.message.c_str());
    } else {
        EXPECT_EQ(r.status, NDFB_ERROR_IO) << r.message;
        EXPECT_NE(r.message.find("output folder '" + ro + "' is not writable: Read-only file system"),
                  std::string::npos)
            << r.message;
        EXPECT_EQ(r.message.find(" [the"), std::string::npos) << r.message;
    }
}

TEST_F(HostileInputs, AFullOutputFolderIsAnIoErrorAndKeepsTheEarlierBake)
{
    // An earlier bake of a 2 x 2 map fits; the 128 x 128 bake after it does not.
    const std::string small = synth_png("small.png", 2), large = synth_png("large.png", 128);

    // Every write past 16 KiB fails with EFBIG, as on a full disk (SIGXFSZ ignored, so the write
    // returns the error instead of killing the process).
    const std::string out = path("out");
    ChildReport r = bake_in_child(
        []() -> const char* {
            ::signal(SIGXFSZ, SIG_IGN);
            const struct rlimit limit {16 * 1024, 16 * 1024};
            return ::setrlimit(RLIMIT_FSIZE, &limit) != 0 ? "setrlimit(RLIMIT_FSIZE)" : nullptr;
        },
        large, out, small);
    EXPECT_EQ(r.status, NDFB_ERROR_IO) << r.message;
    EXPECT_NE(r.message.find("cannot write '" + out), std::string::npos) << r.message;
    EXPECT_NE(r.message.find("File too large"), std::string::npos) << r.message;
    EXPECT_EQ(r.message.find(" [the"), std::string::npos) << r.message;

    // A real ENOSPC: a 64 KiB tmpfs, where this sandbox allows mount(2).
    const std::string tiny = path("tiny");
    fs::create_directories(tiny);
    r = bake_in_child([&] { return mount_private_tmpfs(tiny, "size=64k", 0); }, large, tiny + "/out", small);
    if (r.status == kSkipped) {
        std::printf("full tmpfs not tested here: %s\n", r.message.c_str());
    } else {
        EXPECT_EQ(r.status, NDFB_ERROR_IO) << r.message;
        EXPECT_NE(r.message.find("cannot write '" + tiny + "/out"), std::string::npos) << r.message;
        EXPECT_NE(r.message.find("No space left on device"), std::string::npos) << r.message;
        EXPECT_EQ(r.message.find(" [the"), std::string::npos) << r.message;
    }
}

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
        expect_error(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode_, &fit, &write_),
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
        expect_error(ndfb_bake(ctx_, input.c_str(), out.c_str(), &decode, &fit_, &write_),
                     NDFB_ERROR_INVALID_ARGUMENT, {c.says}, c.name);
        EXPECT_FALSE(fs::exists(out)) << c.name;
    }

    ndfb_write_options write;
    ndfb_write_options_init(&write);
    write.precision = ndfb_precision(4);
    expect_error(ndfb_bake(ctx_, input.c_str(), path("out p").c_str(), &decode_, &fit_, &write),
                 NDFB_ERROR_INVALID_ARGUMENT, {"unknown precision"}, "precision");
    ndfb_write_options_init(&write);
    write.struct_size = 2;
    expect_error(ndfb_bake(ctx_, input.c_str(), path("out s").c_str(), &decode_, &fit_, &write),
                 NDFB_ERROR_INVALID_ARGUMENT, {"write options.struct_size is not set"}, "write struct_size");
    // A colour image of another size: refused before anything is written.
    const std::string color = synth_png("color.png", 4);
    ndfb_write_options_init(&write);
    write.color_path = color.c_str();
    expect_error(ndfb_bake(ctx_, input.c_str(), path("out c").c_str(), &decode_, &fit_, &write),
                 NDFB_ERROR_INVALID_ARGUMENT, {"colour image '" + color + "' is 4x4, the normal map is 8x8"}, "colour");
    EXPECT_TRUE(listing(path("out c")).empty());

    // A caller built before max_memory_bytes existed passes a shorter struct: the field's bytes
    // (here a 1-byte limit that would refuse any bake) are not read.
    ndfb_fit_options old;
    ndfb_fit_options_init(&old);
    old.struct_size = uint32_t(offsetof(ndfb_fit_options, max_memory_bytes));
    old.max_memory_bytes = 1;
    EXPECT_EQ(ndfb_bake(ctx_, input.c_str(), path("out old").c_str(), &decode_, &old, &write_), NDFB_OK) << error();
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

// ndfbake.h: the library "reads only the fields the caller has". A struct shorter than its first
// ABI-1 layout holds fields the library must read, so it is refused, naming the struct, before
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
    ASSERT_EQ(ndfb_fit(ctx_, map, &fit_, &pyramid), NDFB_OK) << error();
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
    for (size_t bytes : {sizeof(uint32_t), offsetof(ndfb_fit_options, threads), offsetof(ndfb_fit_options, progress_user)}) {
        const auto* f = guarded.place(fit_, bytes);
        ndfb_pyramid scratch = nullptr;
        EXPECT_EXIT(exit_with(ctx_, ndfb_fit(ctx_, map, f, &scratch)), ExitedWithCode(inval),
                    "fit options.struct_size is not set: call ndfb_fit_options_init")
            << bytes << " bytes";
    }
    for (size_t bytes : {sizeof(uint32_t), offsetof(ndfb_write_options, source_name)}) {
        const auto* w = guarded.place(write_, bytes);
        EXPECT_EXIT(exit_with(ctx_, ndfb_pyramid_write(ctx_, pyramid, map, out.c_str(), &fit_, w)),
                    ExitedWithCode(inval), "write options.struct_size is not set: call ndfb_write_options_init")
            << bytes << " bytes";
    }
    for (size_t bytes : {sizeof(uint32_t), offsetof(ndfb_bench_options, progress_user)}) {
        const auto* b = guarded.place(bench, bytes);
        EXPECT_EXIT(exit_with(ctx_, ndfb_bench(ctx_, b, out.c_str())), ExitedWithCode(inval),
                    "bench options.struct_size is not set: call ndfb_bench_options_init")
            << bytes << " bytes";
    }
    for (size_t bytes : {sizeof(uint32_t), offsetof(ndfb_space_options, threads)}) {
        const auto* o = guarded.place(space, bytes);
        float in[3] = {0, 0, 1}, converted[3];
        EXPECT_EXIT(exit_with(ctx_, ndfb_object_to_tangent(ctx_, nullptr, nullptr, 0, in, 1, 1, 3, o, converted, nullptr)),
                    ExitedWithCode(inval), "space options.struct_size is not set: call ndfb_space_options_init")
            << bytes << " bytes";
    }
    EXPECT_FALSE(fs::exists(out));

    // The first layouts themselves, against the guard: accepted, and the fields added since
    // (max_memory_bytes..refine, atlas) are not read, so this runs in the test's own process.
    const auto* first_fit = guarded.place(fit_, offsetof(ndfb_fit_options, max_memory_bytes));
    ndfb_pyramid refit = nullptr;
    EXPECT_EQ(ndfb_fit(ctx_, map, first_fit, &refit), NDFB_OK) << error();
    ndfb_pyramid_destroy(refit);
    const auto* first_write = guarded.place(write_, offsetof(ndfb_write_options, atlas));
    EXPECT_EQ(ndfb_pyramid_write(ctx_, pyramid, map, out.c_str(), &fit_, first_write), NDFB_OK) << error();
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
    ASSERT_EQ(ndfb_fit(ctx_, map, &fit_, &pyramid), NDFB_OK);
    std::vector<float> buffer(8 * 8 * 4);
    float direction[3] = {0, 0, 1}, value = 0;
    const ndfb_status inval = NDFB_ERROR_INVALID_ARGUMENT;
    // Calls expected to fail write their (null) result here, never over `map`.
    ndfb_normal_map scratch = nullptr;
    ndfb_pyramid scratch_pyramid = nullptr;

    // A null context: refused (there is no context to hold the message).
    EXPECT_EQ(ndfb_normal_map_load(nullptr, input.c_str(), &decode_, &scratch), inval);
    EXPECT_EQ(ndfb_normal_map_from_pixels(nullptr, buffer.data(), 12, 2, 2, 3, 0, nullptr, &scratch), inval);
    EXPECT_EQ(ndfb_fit(nullptr, map, &fit_, &scratch_pyramid), inval);
    EXPECT_EQ(ndfb_bake(nullptr, input.c_str(), path("o").c_str(), nullptr, &fit_, nullptr), inval);
    EXPECT_EQ(ndfb_pyramid_write(nullptr, pyramid, map, path("o").c_str(), &fit_, nullptr), inval);
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
    expect_error(ndfb_fit(ctx_, nullptr, &fit_, &scratch_pyramid), inval, {"must not be null"}, "map");
    expect_error(ndfb_fit(ctx_, map, nullptr, &scratch_pyramid), inval, {"fit options is null"}, "fit options");
    expect_error(ndfb_bake(ctx_, input.c_str(), path("o").c_str(), &decode_, nullptr, nullptr), inval,
                 {"must not be null"}, "bake fit");
    expect_error(ndfb_bake(ctx_, input.c_str(), nullptr, &decode_, &fit_, nullptr), inval, {"must not be null"},
                 "bake out");
    expect_error(ndfb_pyramid_write(ctx_, nullptr, map, path("o").c_str(), &fit_, nullptr), inval,
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
    expect_error(ndfb_pyramid_write(ctx_, pyramid, other, path("o").c_str(), &fit_, nullptr), inval,
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
    ndfb_fit_options cancelling = fit_;
    cancelling.progress = +[](void*, const char*, float) -> int { return 1; };

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
        EXPECT_NE(ndfb_fit(ctx, nullptr, &fit_, &p), NDFB_OK);
        EXPECT_EQ(p, nullptr) << "fit, " << which;
    }
    // Failures after the arguments were accepted: a missing file, a cancelled fit.
    ndfb_normal_map m = stale_map;
    EXPECT_EQ(ndfb_normal_map_load(ctx_, path("missing.png").c_str(), &decode_, &m), NDFB_ERROR_FILE_NOT_FOUND);
    EXPECT_EQ(m, nullptr);
    ndfb_pyramid p = stale_pyramid;
    EXPECT_EQ(ndfb_fit(ctx_, map, &cancelling, &p), NDFB_ERROR_CANCELLED);
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
    EXPECT_EQ(ndfb_fit(dead, map, &fit_, &pyramid), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(ndfb_bake(dead, input.c_str(), path("out").c_str(), &decode_, &fit_, &write_),
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
    EXPECT_EQ(ndfb_fit(ctx_, map, &fit_, &pyramid), NDFB_OK) << error();
    ndfb_pyramid_destroy(pyramid);
    ndfb_normal_map_destroy(map);
}

}  // namespace
}  // namespace ndfbake
