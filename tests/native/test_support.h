// Shared helpers for the native tests: a fresh temporary folder per test and file listings.
#pragma once

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <set>
#include <string>

namespace ndfbake::testing_support {

class TempDirTest : public ::testing::Test {
protected:
    void SetUp() override
    {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = std::filesystem::path(::testing::TempDir()) /
               ("ndfbake-" + std::string(info->test_suite_name()) + "-" + info->name() + "-" + std::to_string(::getpid()));
        std::filesystem::remove_all(dir_);
        std::filesystem::create_directories(dir_);
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }
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

}  // namespace ndfbake::testing_support
