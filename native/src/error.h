// The library's internal error type. Thrown inside the library, caught at the C API boundary and
// turned into a status code plus last-error text; never crosses into C callers.
#pragma once

#include <stdexcept>
#include <string>

namespace ndfbake {

// Mirrors ndfb_status in ndfbake.h; values must stay equal.
enum class Status : int {
    ok = 0,
    invalid_argument = 1,
    file_not_found = 2,
    unsupported_format = 3,
    corrupt_file = 4,
    io_error = 5,
    out_of_memory = 6,
    cancelled = 7,
    internal = 8,
};

class Error : public std::runtime_error {
public:
    Error(Status status, const std::string& message) : std::runtime_error(message), status_(status) {}
    Status status() const { return status_; }

private:
    Status status_;
};

}  // namespace ndfbake
