// The few file operations whose portable spelling does the wrong thing somewhere, each with one
// implementation per platform (platform/files.cpp), so that no #ifdef appears elsewhere.
//
// Paths: the C API takes and returns UTF-8 (Python passes UTF-8, the OpenEXR core reads UTF-8).
// On Windows, std::filesystem::path(std::string), path::string(), std::ofstream(const char*) and
// ::open() read a char string in the ANSI code page, so a folder like "C:\Users\Zoë\材質" breaks.
// Every path that crosses from a std::string into the file system, or back into a message or a
// returned name, goes through path_from_utf8 / path_to_utf8 (char8_t conversions: exact on every
// platform, a plain copy on POSIX). On Windows, bytes that are not UTF-8 throw
// Error(invalid_argument) saying so.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace ndfbake {

std::filesystem::path path_from_utf8(std::string_view utf8);
std::string path_to_utf8(const std::filesystem::path& path);

// This process's id, for names that must not collide with another process's (temp files).
uint64_t current_process_id();

// What a file operation below did: ok, or why not as one line for a message. `in_use` is set where
// the file is held open by another program (Windows refuses to replace or move such a file).
struct FileResult {
    bool ok = true;
    bool in_use = false;
    std::string reason;
};

// Forces a written file's data onto the disk. Without it, a crash shortly after the rename that
// publishes the file can leave it empty on some filesystems (the rename reaches the disk first).
FileResult flush_file_to_disk(const std::filesystem::path& path);

// Creates `path`, which must not exist yet, and closes it again (the write probe of an output folder).
FileResult create_new_file(const std::filesystem::path& path);

// Whether `path` can be opened for reading (then closed again).
FileResult check_file_opens(const std::filesystem::path& path);

// Renames `from` onto `to` in one step, replacing a file `to` that exists. On Windows a file that
// another program holds open cannot be replaced or moved: sync clients and virus scanners open
// fresh files for a moment, so that case is retried briefly before it fails with in_use set.
FileResult replace_file(const std::filesystem::path& from, const std::filesystem::path& to);

// " (<strerror>)" for an errno a failed write can leave (disk full, quota, read-only, permission),
// else "": a stale errno from an unrelated earlier call is never blamed.
std::string write_errno_reason(int error);

}  // namespace ndfbake
