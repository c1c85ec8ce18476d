// What the C API's translation units share: the context behind ndfb_context and the wrapper that
// turns every exception into a status code plus the context's last-error text.
#pragma once

#include <exception>
#include <new>
#include <string>

#include "error.h"
#include "ndfbake.h"

struct ndfb_context_s {
    std::string last_error;
};

namespace ndfbake {

// Runs `body`, mapping every failure to a status and ctx's last-error text.
template <typename Body>
ndfb_status guarded(ndfb_context ctx, Body&& body)
{
    std::string message;
    ndfb_status status = NDFB_OK;
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
