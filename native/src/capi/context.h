// What the C API's translation units share: the context behind ndfb_context and the wrapper that
// turns every exception into a status code plus the context's last-error text.
#pragma once

#include <cstddef>
#include <cstring>
#include <exception>
#include <mutex>
#include <new>
#include <string>
#include <unordered_set>

#include "error.h"
#include "ndfbake.h"

struct ndfb_context_s {
    std::string last_error;
};

namespace ndfbake {

// Every live context, so that a call with a destroyed (or never created) context is refused with
// NDFB_ERROR_INVALID_ARGUMENT instead of touching freed memory inside the host process. A freed
// address handed out again by a later ndfb_context_create becomes valid again: the check catches
// use after destroy, not every stale handle.
class ContextRegistry {
public:
    static ContextRegistry& instance()
    {
        static ContextRegistry* registry = new ContextRegistry;  // never destroyed: safe at exit
        return *registry;
    }
    void add(ndfb_context ctx)
    {
        std::lock_guard lock(mutex_);
        live_.insert(ctx);
    }
    // True if ctx was live (and is now removed).
    bool remove(ndfb_context ctx)
    {
        std::lock_guard lock(mutex_);
        return live_.erase(ctx) > 0;
    }
    bool live(ndfb_context ctx)
    {
        std::lock_guard lock(mutex_);
        return live_.count(ctx) > 0;
    }

private:
    std::mutex mutex_;
    std::unordered_set<ndfb_context> live_;
};

inline constexpr const char* kDeadContextMessage =
    "the context was destroyed or was never created by ndfb_context_create";

// An enum argument or field as the int a C (or ctypes) caller stored in it. A value outside the
// enumerators cannot be read through the C++ enum type (undefined behaviour, which UBSan reports
// and the optimizer may exploit in a switch), so the bytes are read as int and checked as such.
template <typename Enum>
int raw(const Enum& value)
{
    static_assert(sizeof(Enum) == sizeof(int));
    int v;
    std::memcpy(&v, &value, sizeof v);
    return v;
}

// An argument check: where `condition` is false the call fails with NDFB_ERROR_INVALID_ARGUMENT,
// `message` its last-error text.
inline void require(bool condition, const std::string& message)
{
    if (!condition) throw Error(Status::invalid_argument, message);
}

// Option structs only ever grow at their end, and `first_size` is the size of the struct as ABI 1
// first shipped it: those fields every caller has, so they are read without looking at
// struct_size; fields added since are read only where struct_size covers them. A struct_size
// below first_size (or above the struct this library knows) comes from no header: the struct is
// refused before any field past struct_size is touched, since the caller's memory may end there.
template <typename Options>
void require_struct_size(const Options* options, const char* name, size_t first_size, const char* init)
{
    require(options, std::string(name) + " is null");
    const uint32_t size = options->struct_size;
    require(size >= first_size && size <= sizeof(Options),
            std::string(name) + ".struct_size is not set: call " + init + " first (struct_size is " +
                std::to_string(size) + "; this library reads " + std::to_string(first_size) + " to " +
                std::to_string(sizeof(Options)) + " bytes)");
}

// The size of a struct up to and including `field`: the first_size of a struct whose later
// fields begin after it.
#define NDFB_SIZE_THROUGH(type, field) (offsetof(type, field) + sizeof(type::field))

// Runs `body`, mapping every failure to a status and ctx's last-error text.
template <typename Body>
ndfb_status guarded(ndfb_context ctx, Body&& body)
{
    std::string message;
    ndfb_status status = NDFB_OK;
    if (ctx && !ContextRegistry::instance().live(ctx)) return NDFB_ERROR_INVALID_ARGUMENT;
    try {
        body();
    } catch (const Error& e) {
        status = ndfb_status(int(e.status()));
        message = e.what();
    } catch (const std::bad_alloc&) {
        status = NDFB_ERROR_OUT_OF_MEMORY;
        message = "out of memory";
    } catch (const std::exception& e) {
        status = NDFB_ERROR_INTERNAL;
        message = std::string("internal error: ") + e.what();
    } catch (...) {
        status = NDFB_ERROR_INTERNAL;
        message = "internal error";
    }
    if (ctx) ctx->last_error = status == NDFB_OK ? std::string() : message;
    return status;
}

}  // namespace ndfbake
