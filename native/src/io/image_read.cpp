#include "io/image_read.h"

#include <filesystem>
#include <set>
#include <vector>

#include <OpenImageIO/strutil.h>

#include "platform/files.h"

namespace ndfbake {

namespace {

// OpenImageIO's messages can span several lines; an Error message is one line.
std::string one_line(const std::string& text)
{
    std::vector<std::string> lines;
    for (const std::string& line : OIIO::Strutil::splits(text, "\n")) {
        if (!OIIO::Strutil::strip(line).empty())
            lines.push_back(line);
    }
    return OIIO::Strutil::join(lines, "; ");
}

// Extensions of every format this OpenImageIO build reads ("png:png;tiff:tif,tiff;...").
// A file with one of them that still fails to open is a damaged file, not a foreign format.
const std::set<std::string>& known_extensions()
{
    static const std::set<std::string> extensions = [] {
        std::set<std::string> result;
        const std::string list = OIIO::get_string_attribute("extension_list");
        for (const std::string& format : OIIO::Strutil::splits(list, ";")) {
            const std::vector<std::string> name_and_list = OIIO::Strutil::splits(format, ":");
            if (name_and_list.size() == 2) {
                for (const std::string& ext : OIIO::Strutil::splits(name_and_list[1], ","))
                    result.insert(ext);
            }
        }
        return result;
    }();
    return extensions;
}

bool has_known_image_extension(const std::string& path)
{
    const std::string ext = path_to_utf8(path_from_utf8(path).extension());
    return !ext.empty() && known_extensions().count(OIIO::Strutil::lower(ext.substr(1))) > 0;
}

// Catches what OpenImageIO would report vaguely ("could not open file") with a precise status.
void check_readable_file(const std::string& path)
{
    namespace fs = std::filesystem;
    const fs::path file = path_from_utf8(path);
    std::error_code ec;
    const fs::file_status status = fs::status(file, ec);
    if (!fs::exists(status))
        throw_read_error(Status::file_not_found, path, "no such file");
    if (!fs::is_regular_file(status))
        throw_read_error(Status::invalid_argument, path, "not a regular file");
    if (fs::file_size(file, ec) == 0 && !ec)
        throw_read_error(Status::corrupt_file, path, "file is empty (0 bytes)");

    const FileResult opened = check_file_opens(file);
    if (!opened.ok)
        throw_read_error(Status::io_error, path, opened.reason);
}

}  // namespace

void throw_read_error(Status status, const std::string& path, const std::string& problem,
                      const std::string& oiio_detail)
{
    std::string message = "cannot read '" + path + "': " + problem;
    const std::string detail = one_line(oiio_detail);
    if (!detail.empty())
        message += ": " + detail;
    throw Error(status, message);
}

std::unique_ptr<OIIO::ImageInput> open_image(const std::string& path)
{
    check_readable_file(path);
    // Readers of formats with alpha (PNG, TGA, TIFF) premultiply colour by it unless told not to.
    // A fourth channel in our inputs is not coverage, and a 2-channel PNG's Y would be taken as
    // alpha and multiplied into X.
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path, &config);
    if (in)
        return in;
    const std::string detail = OIIO::geterror();
    if (has_known_image_extension(path))
        throw_read_error(Status::corrupt_file, path,
                         "damaged, or not really a " +
                             path_to_utf8(path_from_utf8(path).extension()) + " file",
                         detail);
    throw_read_error(Status::unsupported_format, path, "not an image format OpenImageIO can read",
                     detail);
}

void read_all_pixels(OIIO::ImageInput& in, const std::string& path, OIIO::TypeDesc type, void* data)
{
    const bool ok = in.read_image(0, 0, 0, in.spec().nchannels, type, data);
    if (!ok || in.has_error())
        throw_read_error(Status::corrupt_file, path, "pixel data is truncated or damaged",
                         in.geterror());
}

}  // namespace ndfbake
