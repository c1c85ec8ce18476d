// The C API: a thin skin that checks arguments, calls the C++ core and turns exceptions into
// status codes plus last-error text. No exception crosses its functions. This file owns the entry
// points about the library and its contexts (version, ABI, contexts, last error, status names);
// the others, by object: capi/options.cpp, capi/map_exports.cpp, capi/pyramid_exports.cpp,
// capi/bake_exports.cpp, capi/bake_result_exports.cpp, capi/tangent_exports.cpp,
// capi/research_exports.cpp. Calls capi/context.h, io/image_files.h and ndf/spherical_em.h (the lobe limit).
#include "ndfbake.h"

#include <new>
#include <string>

#include "capi/context.h"
#include "io/image_files.h"
#include "ndf/spherical_em.h"

namespace {

using namespace ndfbake;

thread_local std::string g_create_error;

}  // namespace

extern "C" {

NDFB_API const char* ndfb_version(void) { return NDFBAKE_VERSION_STRING; }
NDFB_API uint32_t ndfb_abi_version(void) { return NDFB_ABI_MAJOR; }
NDFB_API uint32_t ndfb_abi_minor(void) { return NDFB_ABI_MINOR; }
NDFB_API uint32_t ndfb_max_lobes(void) { return uint32_t(kMaxLobes); }

NDFB_API int32_t ndfb_has_image_files(void) { return reads_image_files() ? 1 : 0; }

NDFB_API ndfb_status ndfb_context_create(ndfb_context* out)
{
    if (!out) {
        g_create_error = "ndfb_context_create: out is null";
        return NDFB_ERROR_INVALID_ARGUMENT;
    }
    *out = new (std::nothrow) ndfb_context_s;
    if (!*out) {
        g_create_error = "out of memory";
        return NDFB_ERROR_OUT_OF_MEMORY;
    }
    try {
        ContextRegistry::instance().add(*out);
    } catch (...) {
        delete *out;
        *out = nullptr;
        g_create_error = "out of memory";
        return NDFB_ERROR_OUT_OF_MEMORY;
    }
    return NDFB_OK;
}

// A second destroy, or a handle that was never a context, is ignored rather than freed twice.
NDFB_API void ndfb_context_destroy(ndfb_context ctx)
{
    if (ctx && ContextRegistry::instance().remove(ctx)) delete ctx;
}

NDFB_API const char* ndfb_last_error(ndfb_context ctx)
{
    if (!ctx) return g_create_error.c_str();
    if (!ContextRegistry::instance().live(ctx)) return kDeadContextMessage;
    return ctx->last_error.c_str();
}

NDFB_API const char* ndfb_status_name(ndfb_status status)
{
    switch (raw(status)) {
    case NDFB_OK: return "ok";
    case NDFB_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case NDFB_ERROR_FILE_NOT_FOUND: return "file not found";
    case NDFB_ERROR_UNSUPPORTED_FORMAT: return "unsupported format";
    case NDFB_ERROR_CORRUPT_FILE: return "corrupt file";
    case NDFB_ERROR_IO: return "i/o error";
    case NDFB_ERROR_OUT_OF_MEMORY: return "out of memory";
    case NDFB_ERROR_CANCELLED: return "cancelled";
    case NDFB_ERROR_INTERNAL: return "internal error";
    }
    return "unknown status";
}

}  // extern "C"
