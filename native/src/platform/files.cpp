#include "platform/files.h"

#include <cerrno>
#include <cstring>
#include <utility>

#if defined(_WIN32)
#include "platform/windows_api.h"
#else
#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#endif

#include "error.h"

namespace ndfbake {

namespace fs = std::filesystem;

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

// What MoveFileExW reports for a file another program holds open: a sharing violation for the
// file moved, access denied for the one replaced (also for a read-only one).
bool is_held_by_another_program(DWORD error)
{
    return error == ERROR_SHARING_VIOLATION || error == ERROR_ACCESS_DENIED || error == ERROR_LOCK_VIOLATION;
}

}  // namespace

// Converted here rather than by libc++ (path(std::u8string), path::u8string()), which throws a
// bare "locale not supported" for bytes that are not UTF-8: such a path gets a message that says
// what is wrong. A file name that is not valid UTF-16 (an unpaired surrogate) comes back with
// U+FFFD in its place.
fs::path path_from_utf8(std::string_view utf8)
{
    if (utf8.empty()) return {};
    const int length = int(utf8.size());
    const int wide_length = MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, utf8.data(), length, nullptr, 0);
    if (wide_length <= 0)
        throw Error(Status::invalid_argument,
                    "the path '" + std::string(utf8) + "' is not UTF-8 text (ndfbake takes paths as UTF-8)");
    std::wstring wide(size_t(wide_length), L'\0');
    MultiByteToWideChar(CP_UTF8, MB_ERR_INVALID_CHARS, utf8.data(), length, wide.data(), wide_length);
    return fs::path(std::move(wide));
}

std::string path_to_utf8(const fs::path& path)
{
    const std::wstring& wide = path.native();
    return wide.empty() ? std::string() : utf8_from_wide(wide.data(), int(wide.size()));
}

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
                    std::string(error == ERROR_ACCESS_DENIED ? "it is open in another program, or read-only"
                                                             : "it is open in another program") +
                        " (" + windows_error_message(error) + "); close it there and try again"};
        Sleep(kReplaceRetryDelayMs);
    }
}

#else  // POSIX: Linux, macOS

// POSIX paths are bytes, UTF-8 by convention: both are plain copies.
fs::path path_from_utf8(std::string_view utf8)
{
    return fs::path(std::u8string_view(reinterpret_cast<const char8_t*>(utf8.data()), utf8.size()));
}

std::string path_to_utf8(const fs::path& path)
{
    const std::u8string utf8 = path.u8string();
    return std::string(utf8.begin(), utf8.end());
}

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
