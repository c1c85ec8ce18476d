// commit_files (io/atomic_file.h): a bake's files move into the output folder as one change. When
// one move fails mid-way (on Windows: a file open in another program; here: a staged file that is
// missing), every step already made is undone, so the folder holds its earlier files again.
// Portable C++ only, so that it runs under wine as well.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#include "error.h"
#include "io/atomic_file.h"
#include "platform/files.h"

namespace ndfbake {
namespace {

namespace fs = std::filesystem;

std::map<std::string, std::string> contents(const fs::path& folder)
{
    std::map<std::string, std::string> files;
    for (const auto& entry : fs::directory_iterator(folder)) {
        std::ifstream in(entry.path(), std::ios::binary);
        files[path_to_utf8(entry.path().filename())] =
            entry.is_regular_file() ? std::string(std::istreambuf_iterator<char>(in), {}) : "<folder>";
    }
    return files;
}

void write(const fs::path& file, const std::string& text) { std::ofstream(file, std::ios::binary) << text; }

class AtomicFileCommit : public ::testing::Test {
protected:
    void SetUp() override
    {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
        root_ = fs::temp_directory_path() / ("ndfbake-" + std::string(info->name()) + "-" + std::to_string(stamp));
        folder_ = root_ / path_from_utf8("Zo\xc3\xab");  // "Zoë"
        staging_ = folder_ / ".staging";
        fs::create_directories(staging_);
        write(folder_ / "a.exr", "old a");
        write(folder_ / "b.exr", "old b");
        write(folder_ / "stale.exr", "old stale");
        write(staging_ / "a.exr", "new a");
        write(staging_ / "b.exr", "new b");
        write(staging_ / "c.exr", "new c");
    }
    void TearDown() override
    {
        std::error_code ec;
        fs::remove_all(root_, ec);
    }
    fs::path root_, folder_, staging_;
};

TEST_F(AtomicFileCommit, ReplacesAddsAndRetiresFiles)
{
    commit_files(path_to_utf8(staging_), path_to_utf8(folder_), {"a.exr", "b.exr", "c.exr"}, {"stale.exr"});
    const std::map<std::string, std::string> expected = {
        {".staging", "<folder>"}, {"a.exr", "new a"}, {"b.exr", "new b"}, {"c.exr", "new c"}};
    EXPECT_EQ(contents(folder_), expected);
    EXPECT_TRUE(fs::is_empty(staging_));
}

TEST_F(AtomicFileCommit, AFailedMoveRestoresTheEarlierFiles)
{
    const auto earlier = contents(folder_);
    // a.exr is moved in and the earlier ones aside before the missing file fails.
    try {
        commit_files(path_to_utf8(staging_), path_to_utf8(folder_), {"a.exr", "missing.exr", "c.exr"},
                     {"stale.exr", "b.exr"});
        FAIL() << "the commit should fail";
    } catch (const Error& e) {
        EXPECT_EQ(e.status(), Status::io_error);
        EXPECT_NE(std::string(e.what()).find(path_to_utf8(folder_ / "missing.exr")), std::string::npos) << e.what();
    }
    EXPECT_EQ(contents(folder_), earlier);
    EXPECT_EQ(contents(staging_).at("a.exr"), "new a");
}

TEST_F(AtomicFileCommit, AWrittenFileReplacesTheOldOneUnderANonAsciiName)
{
    const std::string file = path_to_utf8(folder_ / path_from_utf8("\xe6\x9d\x90\xe8\xb3\xaa.json"));  // "材質.json"
    write_text_atomic(file, "first");
    write_text_atomic(file, "second");
    std::ifstream in(path_from_utf8(file), std::ios::binary);
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "second");
    for (const auto& [name, bytes] : contents(folder_))
        EXPECT_TRUE(name[0] != '.' || name == ".staging") << "left behind: " << name;
}

}  // namespace
}  // namespace ndfbake
