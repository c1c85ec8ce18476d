// Shared helpers for the native tests: a fresh temporary folder per test and file listings.
#pragma once

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>

#include "io/normal_encode.h"
#include "ndfbake.h"
#include "synth/patterns.h"

namespace ndfbake::testing_support {

// Debian's user and group nobody: the ids a test running as root takes where permission bits must
// bind (root ignores them).
inline constexpr uid_t kNobodyUid = 65534;
inline constexpr gid_t kNobodyGid = 65534;

// A file's bytes, and a file of exactly these bytes (no newline translation).
inline std::string read_bytes(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

inline void write_bytes(const std::string& path, const std::string& bytes)
{
    std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

class TempDirTest : public ::testing::Test {
protected:
    void SetUp() override
    {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        std::string name = std::string(info->test_suite_name()) + "-" + info->name();
        std::replace(name.begin(), name.end(), '/', '_');  // parameterized names contain '/'
        dir_ = std::filesystem::path(::testing::TempDir()) / ("ndfbake-" + name + "-" + std::to_string(::getpid()));
        std::filesystem::remove_all(dir_);
        std::filesystem::create_directories(dir_);
    }
    // Gives the owner back every permission first: a test may have locked a folder.
    void TearDown() override
    {
        namespace fs = std::filesystem;
        std::error_code ec;
        fs::permissions(dir_, fs::perms::owner_all, fs::perm_options::add, ec);
        for (const auto& entry : fs::recursive_directory_iterator(dir_, ec))
            fs::permissions(entry.path(), fs::perms::owner_all, fs::perm_options::add, ec);
        fs::remove_all(dir_, ec);
    }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }

    // Every entry under `folder`, hidden ones included.
    static std::set<std::string> listing(const std::string& folder)
    {
        std::set<std::string> names;
        if (!std::filesystem::exists(folder)) return names;
        for (const auto& e : std::filesystem::recursive_directory_iterator(folder)) names.insert(e.path().string());
        return names;
    }

    std::filesystem::path dir_;
};

// A C API context and default option structs, in a fresh temporary folder.
class CApiTest : public TempDirTest {
protected:
    void SetUp() override
    {
        TempDirTest::SetUp();
        ASSERT_EQ(ndfb_context_create(&ctx_), NDFB_OK);
        ndfb_decode_options_init(&decode_);
        ndfb_fit_options_init(&fit_);
        ndfb_write_options_init(&write_);
    }
    void TearDown() override
    {
        ndfb_context_destroy(ctx_);
        TempDirTest::TearDown();
    }
    // A synthetic normal map written as an image file in the folder.
    std::string synth_file(Pattern pattern, int w, int h, const std::string& name)
    {
        write_normal_map(path(name), synthesize(pattern, w, h));
        return path(name);
    }

    ndfb_context ctx_ = nullptr;
    ndfb_decode_options decode_;
    ndfb_fit_options fit_;
    ndfb_write_options write_;
};

}  // namespace ndfbake::testing_support
