#include "io/atomic_file.h"

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fcntl.h>
#include <unistd.h>

#include "error.h"

namespace ndfbake {

namespace fs = std::filesystem;

namespace {

// Unique per process (pid) and per call (counter), so concurrent writers never share a temp file.
std::string temp_path_for(const std::string& final_path)
{
    static std::atomic<uint64_t> counter{0};
    const fs::path final_file(final_path);
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "." + std::string&&.
    std::string name = ".";
    name += final_file.stem().string();
    name += ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
    name += final_file.extension().string();
    return (final_file.parent_path() / name).string();
}

// Without this, a crash shortly after the rename can leave final_path empty on some filesystems
// (the rename reaches the disk before the data does).
void flush_to_disk(const std::string& path, const std::string& final_path)
{
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0 || ::fsync(fd) != 0) {
        const std::string reason = std::strerror(errno);
        if (fd >= 0)
            ::close(fd);
        throw Error(Status::io_error, "cannot write '" + final_path + "': " + reason);
    }
    ::close(fd);
}

[[noreturn]] void throw_not_writable(const std::string& dir, const std::string& reason)
{
    throw Error(Status::io_error, "output folder '" + dir + "' is not writable: " + reason);
}

}  // namespace

void write_file_atomic(const std::string& final_path,
                       const std::function<void(const std::string& temp_path)>& writer)
{
    const std::string temp_path = temp_path_for(final_path);
    const auto remove_temp = [&] {
        std::error_code ignored;
        fs::remove(temp_path, ignored);
    };
    try {
        writer(temp_path);
        flush_to_disk(temp_path, final_path);
        std::error_code ec;
        fs::rename(temp_path, final_path, ec);
        if (ec)
            throw Error(Status::io_error, "cannot write '" + final_path + "': " + ec.message());
    } catch (const Error& e) {
        remove_temp();
        // Writers' libraries name the file they were given: the user asked for final_path.
        std::string message = e.what();
        for (size_t at = message.find(temp_path); at != std::string::npos;
             at = message.find(temp_path, at + final_path.size()))
            message.replace(at, temp_path.size(), final_path);
        throw Error(e.status(), message);
    } catch (...) {
        remove_temp();
        throw;
    }
}

void write_text_atomic(const std::string& path, const std::string& text)
{
    write_file_atomic(path, [&](const std::string& temp_path) {
        std::ofstream file(temp_path, std::ios::binary | std::ios::trunc);
        if (file)
            file.write(text.data(), std::streamsize(text.size()));
        if (file)
            file.close();
        if (!file)
            throw Error(Status::io_error, "cannot write '" + path + "': " + std::strerror(errno));
    });
}

void ensure_writable_directory(const std::string& dir)
{
    // An empty folder is the current directory, as in a bare output file name.
    const fs::path folder = dir.empty() ? fs::path(".") : fs::path(dir);
    std::error_code ec;
    fs::create_directories(folder, ec);
    if (ec)
        throw_not_writable(dir, ec.message());
    if (!fs::is_directory(folder, ec))
        throw_not_writable(dir, "not a directory");

    // Permission bits alone do not answer this (ACLs, read-only mounts, root): try it. The name
    // is unique per call, so two bakes into one folder from two threads do not collide on it.
    static std::atomic<uint64_t> probes{0};
    const fs::path probe = folder / (".ndfbake-write-probe-" + std::to_string(::getpid()) + "-" +
                                     std::to_string(probes++));
    const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd < 0)
        throw_not_writable(dir, std::strerror(errno));
    ::close(fd);
    fs::remove(probe, ec);
}

std::vector<std::string> missing_folders(const std::string& dir)
{
    std::vector<std::string> missing;
    std::error_code ec;
    fs::path folder = fs::path(dir).lexically_normal();
    if (!folder.has_filename()) folder = folder.parent_path();  // a trailing separator
    for (; !folder.empty() && !fs::exists(folder, ec); folder = folder.parent_path()) {
        missing.push_back(folder.string());
        if (folder == folder.parent_path()) break;
    }
    return missing;
}

void remove_empty_folders(const std::vector<std::string>& folders)
{
    std::error_code ec;
    for (const std::string& folder : folders) fs::remove(folder, ec);  // removes only an empty folder
}

}  // namespace ndfbake
