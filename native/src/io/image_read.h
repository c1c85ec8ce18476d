// Opening and reading image files through OpenImageIO with every failure sorted into an ndfbake
// Status, so the normal-map decoder and the EXR reader report bad files the same way.
#pragma once

#include <memory>
#include <string>

#include <OpenImageIO/imageio.h>

#include "error.h"

namespace ndfbake {

// Throws Error(status, "cannot read '<path>': <problem>"), with OpenImageIO's own text (if any)
// appended after the problem on the same line.
[[noreturn]] void throw_read_error(Status status, const std::string& path,
                                   const std::string& problem, const std::string& oiio_detail = {});

// Opens subimage 0, MIP level 0 of `path`. Missing -> file_not_found; empty or damaged file of a
// format OpenImageIO knows -> corrupt_file; anything else it cannot open -> unsupported_format.
std::unique_ptr<OIIO::ImageInput> open_image(const std::string& path);

// Reads every channel of the opened image, converted to `type`, into `data`. Some readers finish a
// truncated file and only leave an error behind (TIFF, JPEG), so a pending error fails too.
void read_all_pixels(OIIO::ImageInput& in, const std::string& path, OIIO::TypeDesc type,
                     void* data);

}  // namespace ndfbake
