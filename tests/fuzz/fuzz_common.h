// Shared by the libFuzzer targets: a context and a private temporary folder per process, and
// the oracle every target applies: the library may refuse an input with any specific status,
// but never with NDFB_ERROR_INTERNAL (an exception it did not classify), never crash, never leave
// a file behind after a failure.
#pragma once

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include <unistd.h>

#include "ndfbake_research.h"  // ndfbake.h and the ground truth, the benchmark

namespace ndfbake_fuzz {

inline ndfb_context context()
{
    static ndfb_context ctx = [] {
        ndfb_context c = nullptr;
        if (ndfb_context_create(&c) != NDFB_OK) std::abort();
        return c;
    }();
    return ctx;
}

// A folder of this process's own (several fuzzing jobs may share a machine), inside
// $NDFBAKE_FUZZ_SCRATCH (scripts/fuzz.sh makes one and removes it afterwards: libFuzzer ends a
// timed run with _Exit, so atexit handlers do not run), else in /dev/shm when it exists, so the
// files written per input cost no disk I/O.
inline const std::string& scratch_dir()
{
    // Never destroyed: the atexit handler that removes the folder runs after static destructors.
    static const std::string* dir = [] {
        const char* scratch = std::getenv("NDFBAKE_FUZZ_SCRATCH");
        const char* base = scratch && *scratch ? scratch
                           : std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : P_tmpdir;
        auto* pattern = new std::string(std::string(base) + "/ndfbake-fuzz-XXXXXX");
        if (!::mkdtemp(pattern->data())) std::abort();
        std::atexit([] {
            std::error_code ec;
            std::filesystem::remove_all(*dir, ec);
        });
        return pattern;
    }();
    return *dir;
}

// Aborts (a finding) on a status no input may cause.
inline void check(ndfb_status status, const char* call)
{
    if (status == NDFB_ERROR_INTERNAL || int(status) < 0 || int(status) > int(NDFB_ERROR_INTERNAL)) {
        std::fprintf(stderr, "%s returned %d (%s): %s\n", call, int(status), ndfb_status_name(status),
                     ndfb_last_error(context()));
        std::abort();
    }
    const char* message = ndfb_last_error(context());
    if ((status == NDFB_OK) != (message[0] == '\0') || std::strchr(message, '\n')) {
        std::fprintf(stderr, "%s: status %d with message '%s'\n", call, int(status), message);
        std::abort();
    }
}

inline void require(bool condition, const char* what)
{
    if (!condition) {
        std::fprintf(stderr, "invariant broken: %s\n", what);
        std::abort();
    }
}

// Stores any int in an enum field, as a C or ctypes caller can (a C++ cast to an enum of a value
// outside its enumerators would be undefined behaviour on our side, not the library's).
template <typename Enum>
void set_raw(Enum& field, uint32_t value)
{
    static_assert(sizeof(Enum) == sizeof(value));
    std::memcpy(&field, &value, sizeof value);
}

// Empties `dir` (keeps the folder).
inline void clear(const std::string& dir)
{
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(dir, ec)) std::filesystem::remove_all(e.path(), ec);
}

inline bool empty_or_missing(const std::string& dir)
{
    std::error_code ec;
    if (!std::filesystem::exists(dir, ec)) return true;
    return std::filesystem::is_empty(dir, ec);
}

}  // namespace ndfbake_fuzz
