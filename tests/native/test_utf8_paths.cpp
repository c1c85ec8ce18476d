// Paths cross the C API as UTF-8 (Python passes UTF-8): a bake into a folder whose names are not
// ASCII must write the same files as one into a plain folder, and every message must name the path
// in UTF-8. On Windows this is where a char path read in the ANSI code page breaks (libc++'s
// std::filesystem::path(std::string), std::ofstream(const char*), ::open), so this file uses only
// the C API, the C++ library and GoogleTest: it also runs against the add-on's DLL under wine.
//
// It also holds the re-bake over a lobe file another program has open: on Windows the bake fails
// saying so and the earlier bake stays whole; elsewhere the files are replaced.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "ndfbake.h"

namespace {

namespace fs = std::filesystem;

std::string utf8(const fs::path& path)
{
    const std::u8string text = path.u8string();
    return std::string(text.begin(), text.end());
}

fs::path from_utf8(const char8_t* text) { return fs::path(std::u8string(text)); }

std::string chars(const char8_t* text)
{
    const std::u8string utf8_text(text);
    return std::string(utf8_text.begin(), utf8_text.end());
}

std::string read_bytes(const fs::path& file)
{
    std::ifstream in(file, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Every file directly in `folder` (hidden ones included), by UTF-8 name, with its bytes.
std::map<std::string, std::string> folder_contents(const fs::path& folder)
{
    std::map<std::string, std::string> files;
    for (const auto& entry : fs::directory_iterator(folder))
        files[utf8(entry.path().filename())] = entry.is_regular_file() ? read_bytes(entry.path()) : "<folder>";
    return files;
}

class Utf8Paths : public ::testing::Test {
protected:
    void SetUp() override
    {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
        root_ = fs::temp_directory_path() / ("ndfbake-" + std::string(info->name()) + "-" + std::to_string(stamp));
        fs::create_directories(root_);
        ASSERT_EQ(ndfb_context_create(&ctx_), NDFB_OK);
        ndfb_decode_options_init(&decode_);
        ndfb_fit_options_init(&fit_);
        ndfb_write_options_init(&write_);
        fit_.max_lobes = 2;
        fit_.threads = 2;
        write_.source_name = "bumps";
        write_.atlas = 1;

        // A 32 x 32 map of bumps, [0, 1]-encoded RGB as Blender's image pixels are.
        const uint32_t size = 32;
        std::vector<float> pixels(size * size * 3);
        for (uint32_t y = 0; y < size; ++y)
            for (uint32_t x = 0; x < size; ++x) {
                const float u = 0.5f * std::sin(float(x) * 0.7f), v = 0.5f * std::cos(float(y) * 0.5f);
                float* p = &pixels[(y * size + x) * 3];
                p[0] = 0.5f * u + 0.5f, p[1] = 0.5f * v + 0.5f, p[2] = 0.5f * std::sqrt(1.0f - u * u - v * v) + 0.5f;
            }
        ASSERT_EQ(ndfb_normal_map_from_pixels(ctx_, pixels.data(), pixels.size(), size, size, 3, 0, &decode_, &map_),
                  NDFB_OK)
            << ndfb_last_error(ctx_);
    }
    void TearDown() override
    {
        ndfb_normal_map_destroy(map_);
        ndfb_context_destroy(ctx_);
        std::error_code ec;
        fs::remove_all(root_, ec);
    }

    ndfb_status bake_into(const fs::path& folder)
    {
        return ndfb_bake_map(ctx_, map_, utf8(folder).c_str(), &fit_, &write_, nullptr, nullptr, nullptr);
    }

    fs::path root_;
    ndfb_context ctx_ = nullptr;
    ndfb_normal_map map_ = nullptr;
    ndfb_decode_options decode_;
    ndfb_fit_options fit_;
    ndfb_write_options write_;
};

TEST_F(Utf8Paths, ABakeIntoANonAsciiFolderWritesWhatAPlainFolderGets)
{
    const fs::path plain = root_ / "plain" / "out", named = root_ / from_utf8(u8"Zoë") / from_utf8(u8"材質.ndfbake");
    ASSERT_EQ(bake_into(plain), NDFB_OK) << ndfb_last_error(ctx_);
    ASSERT_EQ(bake_into(named), NDFB_OK) << ndfb_last_error(ctx_);

    // Read back through the file system's own (wide, on Windows) names.
    ASSERT_TRUE(fs::is_directory(root_ / from_utf8(u8"Zoë") / from_utf8(u8"材質.ndfbake")));
    const auto expected = folder_contents(plain), written = folder_contents(named);
    ASSERT_EQ(written.size(), expected.size());
    for (const auto& [name, bytes] : expected) {
        ASSERT_TRUE(written.count(name)) << name;
        EXPECT_NE(name[0], '.') << "left behind: " << name;
        if (name == "report.json") continue;  // its timings and peak memory differ
        EXPECT_EQ(written.at(name), bytes) << name;
    }
    const std::string& lobe = written.at("level00_lobe0.exr");
    ASSERT_GE(lobe.size(), 4u);
    EXPECT_EQ(lobe.substr(0, 4), std::string("\x76\x2f\x31\x01", 4)) << "an OpenEXR file";
    EXPECT_NE(written.at("report.json").find("\"level00_lobe1.exr\""), std::string::npos);
}

TEST_F(Utf8Paths, ARebakeReplacesAndRetiresFilesInANonAsciiFolder)
{
    const fs::path folder = root_ / from_utf8(u8"Zoë") / from_utf8(u8"材質.ndfbake");
    ASSERT_EQ(bake_into(folder), NDFB_OK) << ndfb_last_error(ctx_);
    ASSERT_TRUE(fs::exists(folder / "level00_lobe1.exr"));
    fit_.max_lobes = 1;
    write_.atlas = 0;
    ASSERT_EQ(bake_into(folder), NDFB_OK) << ndfb_last_error(ctx_);
    std::vector<std::string> names;
    for (const auto& [name, bytes] : folder_contents(folder)) names.push_back(name);
    for (const std::string& name : names) {
        EXPECT_NE(name[0], '.') << "left behind: " << name;
        EXPECT_EQ(name.find("lobe1"), std::string::npos) << "not retired: " << name;
        EXPECT_EQ(name.find("atlas"), std::string::npos) << "not retired: " << name;
    }
    EXPECT_TRUE(fs::exists(folder / "level00_lobe0.exr"));
    EXPECT_TRUE(fs::exists(folder / "report.json"));
}

TEST_F(Utf8Paths, AFailureNamesTheFolderInUtf8)
{
    const fs::path file = root_ / from_utf8(u8"Zoë-Datei");
    std::ofstream(file) << "not a folder";
    const fs::path folder = file / from_utf8(u8"材質.ndfbake");
    ASSERT_EQ(bake_into(folder), NDFB_ERROR_IO);
    const std::string message = ndfb_last_error(ctx_);
    EXPECT_NE(message.find(utf8(folder)), std::string::npos) << message;
    EXPECT_EQ(read_bytes(file), "not a folder");
}

// A path in another encoding (here "Zoë" in Windows-1252, as a program's char argv arrives
// there) cannot name a file on Windows: the message says what is wrong. POSIX names are bytes.
TEST_F(Utf8Paths, APathThatIsNotUtf8IsRefusedOnWindows)
{
#if defined(_WIN32)
    const std::string folder = utf8(root_) + "\\Zo\xeb";
    ASSERT_EQ(ndfb_bake_map(ctx_, map_, folder.c_str(), &fit_, &write_, nullptr, nullptr, nullptr), NDFB_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(ndfb_last_error(ctx_)).find("is not UTF-8"), std::string::npos) << ndfb_last_error(ctx_);
    EXPECT_TRUE(fs::is_empty(root_));
#else
    GTEST_SKIP() << "POSIX file names are bytes";
#endif
}

TEST_F(Utf8Paths, ImageFilesWithNonAsciiNamesAreReadAndWritten)
{
    if (!ndfb_has_image_files()) GTEST_SKIP() << "this library reads and writes no image files";
    const fs::path image = root_ / from_utf8(u8"Zoë") / from_utf8(u8"材質.png");
    fs::create_directories(image.parent_path());
    ASSERT_EQ(ndfb_normal_map_save(ctx_, map_, utf8(image).c_str()), NDFB_OK) << ndfb_last_error(ctx_);
    ASSERT_TRUE(fs::is_regular_file(image));
    const fs::path folder = root_ / from_utf8(u8"Zoë") / from_utf8(u8"出力");
    write_.source_name = nullptr;  // the file's name
    ASSERT_EQ(ndfb_bake(ctx_, utf8(image).c_str(), utf8(folder).c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr), NDFB_OK)
        << ndfb_last_error(ctx_);
    EXPECT_NE(read_bytes(folder / "report.json").find(chars(u8"材質.png")), std::string::npos);

    // A missing input is named in UTF-8 too.
    const fs::path missing = root_ / from_utf8(u8"Zoë") / from_utf8(u8"fehlt-ü.png");
    ASSERT_EQ(ndfb_bake(ctx_, utf8(missing).c_str(), utf8(folder).c_str(), &decode_, &fit_, &write_, nullptr, nullptr, nullptr),
              NDFB_ERROR_FILE_NOT_FOUND);
    EXPECT_NE(std::string(ndfb_last_error(ctx_)).find(utf8(missing)), std::string::npos) << ndfb_last_error(ctx_);
}

// Windows does not rename over, or move, a file another program holds open without
// FILE_SHARE_DELETE (the C runtime's fopen, and so std::ifstream, does not share it).
TEST_F(Utf8Paths, ARebakeWhileALobeFileIsOpenElsewhere)
{
    const fs::path folder = root_ / from_utf8(u8"Zoë") / from_utf8(u8"材質.ndfbake");
    ASSERT_EQ(bake_into(folder), NDFB_OK) << ndfb_last_error(ctx_);
    const auto earlier = folder_contents(folder);
    std::ifstream held(folder / "level00_lobe1.exr", std::ios::binary);
    ASSERT_TRUE(held.is_open());
    fit_.max_lobes = 1;  // retires level*_lobe1.exr, replaces level*_lobe0.exr
    const ndfb_status status = bake_into(folder);
#if defined(_WIN32)
    ASSERT_EQ(status, NDFB_ERROR_IO);
    const std::string message = ndfb_last_error(ctx_);
    EXPECT_NE(message.find(utf8(folder / "level00_lobe1.exr")), std::string::npos) << message;
    EXPECT_NE(message.find("open in another program"), std::string::npos) << message;
    EXPECT_EQ(folder_contents(folder), earlier) << "the earlier bake must stay whole";
    held.close();
    ASSERT_EQ(bake_into(folder), NDFB_OK) << ndfb_last_error(ctx_);
#else
    ASSERT_EQ(status, NDFB_OK) << ndfb_last_error(ctx_);
#endif
    EXPECT_FALSE(fs::exists(folder / "level00_lobe1.exr"));
    for (const auto& [name, bytes] : folder_contents(folder)) EXPECT_NE(name[0], '.') << "left behind: " << name;
}

}  // namespace
