#include "platform/files.h"

#include <cerrno>
#include <cstring>

#if defined(_WIN32)
#ifndef WIN32_LEAN_AND_MEAN
#define WIN32_LEAN_AND_MEAN
#endif
#ifndef NOMINMAX
#define NOMINMAX
#endif
#include <windows.h>
#else
#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#endif

namespace ndfbake {

namespace fs = std::filesystem;

fs::path path_from_utf8(std::string_view utf8)
{
    return fs::path(std::u8string_view(reinterpret_cast<const char8_t*>(utf8.data()), utf8.size()));
}

std::string path_to_utf8(const fs::path& path)
{
    const std::u8string utf8 = path.u8string();
    return std::string(utf8.begin(), utf8.end());
}

std::string write_errno_reason(int error)
{
    switch (error) {
    case ENOSPC: case EFBIG: case EIO: case EROFS: case EACCES: case EPERM:
#ifdef EDQUOT  // POSIX: a full disk quota; the Windows C runtime has no such errno
    case EDQUOT:
#endif
        return std::string(" (") + std::strerror(error) + ")";
    default: return {};
    }
}

#if defined(_WIN32)

namespace {

// How long a rename waits for another program to let go of a file. Sync clients (OneDrive,
// Dropbox) and virus scanners open a freshly written or replaced file for a few to a few hundred
// milliseconds; a file held longer (an image viewer, another Blender) is open for good, and the
// bake should say so rather than hang. 20 tries 50 ms apart wait one second at most.
constexpr int kReplaceAttempts = 20;
constexpr DWORD kReplaceRetryDelayMs = 50;

std::string utf8_from_wide(const wchar_t* text, int length)
{
    const int bytes = WideCharToMultiByte(CP_UTF8, 0, text, length, nullptr, 0, nullptr, nullptr);
    std::string utf8(size_t(bytes > 0 ? bytes : 0), '\0');
    if (bytes > 0) WideCharToMultiByte(CP_UTF8, 0, text, length, utf8.data(), bytes, nullptr, nullptr);
    return utf8;
}

// The system's one-line text for a GetLastError() code, in UTF-8, without the trailing period.
std::string windows_error_message(DWORD error)
{
    wchar_t* text = nullptr;
    const DWORD length = FormatMessageW(
        FORMAT_MESSAGE_ALLOCATE_BUFFER | FORMAT_MESSAGE_FROM_SYSTEM | FORMAT_MESSAGE_IGNORE_INSERTS, nullptr, error,
        0, reinterpret_cast<LPWSTR>(&text), 0, nullptr);
    std::string message = length && text ? utf8_from_wide(text, int(length)) : std::string();
    if (text) LocalFree(text);
    while (!message.empty() && (message.back() == '\n' || message.back() == '\r' || message.back() == ' ' ||
                                message.back() == '.'))
        message.pop_back();
    return message.empty() ? "Windows error " + std::to_string(error) : message;
}

FileResult failure(DWORD error) { return {false, false, windows_error_message(error)}; }

bool is_held_by_another_program(DWORD error)
{
    return error == ERROR_SHARING_VIOLATION || error == ERROR_ACCESS_DENIED || error == ERROR_LOCK_VIOLATION;
}

}  // namespace

uint64_t current_process_id() { return GetCurrentProcessId(); }

FileResult flush_file_to_disk(const fs::path& path)
{
    // FlushFileBuffers needs a handle with write access; sharing everything lets it open a file
    // that a scanner is already reading.
    const HANDLE file = CreateFileW(path.c_str(), GENERIC_WRITE, FILE_SHARE_READ | FILE_SHARE_WRITE | FILE_SHARE_DELETE,
                                    nullptr, OPEN_EXISTING, FILE_ATTRIBUTE_NORMAL, nullptr);
    if (file == INVALID_HANDLE_VALUE) return failure(GetLastError());
    const bool flushed = FlushFileBuffers(file) != 0;
    const DWORD error = GetLastError();
    CloseHandle(file);
    return flushed ? FileResult{} : failure(error);
}

FileResult create_new_file(const fs::path& path)
{
    const HANDLE file =
        CreateFileW(path.c_str(), GENERIC_WRITE, 0, nullptr, CREATE_NEW, FILE_ATTRIBUTE_TEMPORARY, nullptr);
    if (file == INVALID_HANDLE_VALUE) return failure(GetLastError());
    CloseHandle(file);
    return {};
}

FileResult check_file_opens(const fs::path& path)
{
    const HANDLE file = CreateFileW(path.c_str(), GENERIC_READ, FILE_SHARE_READ | FILE_SHARE_WRITE | FILE_SHARE_DELETE,
                                    nullptr, OPEN_EXISTING, FILE_ATTRIBUTE_NORMAL, nullptr);
    if (file == INVALID_HANDLE_VALUE) return failure(GetLastError());
    CloseHandle(file);
    return {};
}

FileResult replace_file(const fs::path& from, const fs::path& to)
{
    for (int attempt = 1;; ++attempt) {
        // WRITE_THROUGH: returns once the rename is on the disk, as the flushed data already is.
        if (MoveFileExW(from.c_str(), to.c_str(), MOVEFILE_REPLACE_EXISTING | MOVEFILE_WRITE_THROUGH)) return {};
        const DWORD error = GetLastError();
        if (!is_held_by_another_program(error)) return failure(error);
        if (attempt == kReplaceAttempts)
            return {false, true,
                    "it is open in another program (" + windows_error_message(error) +
                        "); close it there and try again"};
        Sleep(kReplaceRetryDelayMs);
    }
}

#else  // POSIX: Linux, macOS

namespace {

FileResult failure(int error) { return {false, false, std::strerror(error)}; }

}  // namespace

uint64_t current_process_id() { return uint64_t(::getpid()); }

FileResult flush_file_to_disk(const fs::path& path)
{
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return failure(errno);
#if defined(__APPLE__)
    // macOS's fsync only hands the data to the drive, whose cache may still lose it;
    // F_FULLFSYNC asks the drive to write it. Filesystems without it (network shares) get fsync.
    const bool flushed = ::fcntl(fd, F_FULLFSYNC) == 0 || ::fsync(fd) == 0;
#else
    const bool flushed = ::fsync(fd) == 0;
#endif
    const int error = errno;
    ::close(fd);
    return flushed ? FileResult{} : failure(error);
}

FileResult create_new_file(const fs::path& path)
{
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
    if (fd < 0) return failure(errno);
    ::close(fd);
    return {};
}

FileResult check_file_opens(const fs::path& path)
{
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return failure(errno);
    ::close(fd);
    return {};
}

FileResult replace_file(const fs::path& from, const fs::path& to)
{
    if (std::rename(from.c_str(), to.c_str()) != 0) return failure(errno);
    return {};
}

#endif

}  // namespace ndfbake
