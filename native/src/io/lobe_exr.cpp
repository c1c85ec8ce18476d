#include "io/lobe_exr.h"

#include <cerrno>
#include <algorithm>
#include <cstring>
#include <type_traits>

#include <Imath/half.h>
#include <OpenEXR/openexr.h>

#include "error.h"
#include "io/atomic_file.h"
#include "platform/files.h"

// Written with OpenEXR's C core (OpenEXRCore), not OpenImageIO: it needs nothing but zlib and the
// C library, so the Blender add-on's library can carry it (see native/CMakeLists.txt).

namespace ndfbake {

namespace {

// zlib at its fastest level: lossless like the default level, files about 6% larger, written
// 1.5× faster (compressing the lobe textures is most of a bake's write time).
constexpr int kZlibLevel = 1;

// OpenEXRCore reports an error through a callback before returning its code; the message is kept
// per thread, since the lobe textures of a bake are written on every core at once.
thread_local std::string t_exr_message;

void remember_exr_message(exr_const_context_t, exr_result_t, const char* message)
{
    t_exr_message = message ? message : "";
}

[[noreturn]] void throw_write_error(const std::string& path, const std::string& detail)
{
    throw Error(Status::io_error, "cannot write '" + path + "': " + detail);
}

// Calls an OpenEXRCore function; a failure throws with the library's message (or its code's name).
void check(exr_result_t result, const std::string& path)
{
    if (result == EXR_ERR_SUCCESS) return;
    // OpenEXR reports a failed write without the reason; the errno of the write is still set
    // when it returns (write_errno_reason names only errors a write can raise).
    const int error = errno;
    const std::string message = t_exr_message.empty() ? exr_get_default_error_message(result) : t_exr_message;
    throw_write_error(path, message + write_errno_reason(error));
}

// A write context that is always finished: exr_finish also releases a context whose write failed.
class ExrWriter {
public:
    ExrWriter(const std::string& temp_path, const std::string& path) : path_(path)
    {
        exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
        init.error_handler_fn = &remember_exr_message;
        t_exr_message.clear();
        errno = 0;
        check(exr_start_write(&context_, temp_path.c_str(), EXR_WRITE_FILE_DIRECTLY, &init), path_);
    }
    ExrWriter(const ExrWriter&) = delete;
    ExrWriter& operator=(const ExrWriter&) = delete;
    ~ExrWriter()
    {
        if (context_) exr_finish(&context_);
    }
    exr_context_t get() const { return context_; }
    // Writes the offset table and closes the file.
    void finish() { check(exr_finish(&context_), path_); }

private:
    exr_context_t context_ = nullptr;
    std::string path_;
};

void set_attribute(exr_context_t context, int part, const ExrAttribute& attribute, const std::string& path)
{
    const char* name = attribute.name.c_str();
    std::visit(
        [&](const auto& value) {
            using T = std::decay_t<decltype(value)>;
            if constexpr (std::is_same_v<T, int>) check(exr_attr_set_int(context, part, name, value), path);
            else if constexpr (std::is_same_v<T, float>) check(exr_attr_set_float(context, part, name, value), path);
            else check(exr_attr_set_string(context, part, name, value.c_str()), path);
        },
        attribute.value);
}

// The header: one part, R, G, B, A of one sample type, the given compression and attributes;
// scanlines, or (tiled) MIP-mapped tiles of kMipTileSize², levels rounded up.
int write_header(exr_context_t context, int width, int height, exr_pixel_type_t type,
                 const std::vector<ExrAttribute>& attributes, ExrCompression compression, const std::string& path,
                 bool tiled = false)
{
    int part = 0;
    check(exr_add_part(context, nullptr, tiled ? EXR_STORAGE_TILED : EXR_STORAGE_SCANLINE, &part), path);
    const bool rle = compression == ExrCompression::run_length;
    check(exr_initialize_required_attr_simple(context, part, width, height,
                                              rle ? EXR_COMPRESSION_RLE : EXR_COMPRESSION_ZIP),
          path);
    if (tiled)
        check(exr_set_tile_descriptor(context, part, kMipTileSize, kMipTileSize, EXR_TILE_MIPMAP_LEVELS,
                                      EXR_TILE_ROUND_UP),
              path);
    if (!rle) check(exr_set_zip_compression_level(context, part, kZlibLevel), path);
    for (const char* channel : {"R", "G", "B", "A"})
        check(exr_add_channel(context, part, channel, type, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1), path);
    for (const ExrAttribute& attribute : attributes) set_attribute(context, part, attribute, path);
    check(exr_write_header(context), path);
    return part;
}

// One encoder for every chunk of a part: initialized on the first, updated for the next, and
// always destroyed.
class ChunkEncoder {
public:
    ChunkEncoder(exr_context_t context, int part, const std::string& path)
        : context_(context), part_(part), path_(path) {}
    ChunkEncoder(const ChunkEncoder&) = delete;
    ChunkEncoder& operator=(const ChunkEncoder&) = delete;
    ~ChunkEncoder()
    {
        if (started_) exr_encoding_destroy(context_, &encoder_);
    }

    // Encodes and writes `chunk`, whose top-left texel is `origin` in an interleaved RGBA image of
    // type T with `line_samples` samples per row.
    template <typename T>
    void run(const exr_chunk_info_t& chunk, exr_pixel_type_t type, const T* origin, size_t line_samples)
    {
        if (started_) {
            check(exr_encoding_update(context_, part_, &chunk, &encoder_), path_);
        } else {
            check(exr_encoding_initialize(context_, part_, &chunk, &encoder_), path_);
            started_ = true;
        }
        // The file stores the channels sorted by name (A, B, G, R): each reads its own offset.
        for (int c = 0; c < encoder_.channel_count; ++c) {
            exr_coding_channel_info_t& channel = encoder_.channels[c];
            static constexpr char kInterleaved[] = "RGBA";
            const auto offset = std::strchr(kInterleaved, channel.channel_name[0]) - kInterleaved;
            channel.encode_from_ptr = reinterpret_cast<const uint8_t*>(origin + offset);
            channel.user_pixel_stride = int32_t(4 * sizeof(T));
            channel.user_line_stride = int32_t(line_samples * sizeof(T));
            channel.user_bytes_per_element = int16_t(sizeof(T));
            channel.user_data_type = uint16_t(type);
        }
        if (!routines_chosen_) {
            check(exr_encoding_choose_default_routines(context_, part_, &encoder_), path_);
            routines_chosen_ = true;
        }
        check(exr_encoding_run(context_, part_, &encoder_), path_);
    }

private:
    exr_context_t context_;
    int part_;
    const std::string& path_;
    exr_encode_pipeline_t encoder_{};
    bool started_ = false;
    bool routines_chosen_ = false;
};

// Encodes interleaved RGBA samples of type T (width * 4 per row, top row first), chunk by chunk.
template <typename T>
void write_scanlines(exr_context_t context, int part, int width, int height, exr_pixel_type_t type,
                     const T* rgba, const std::string& path)
{
    int32_t lines_per_chunk = 0;
    check(exr_get_scanlines_per_chunk(context, part, &lines_per_chunk), path);
    ChunkEncoder encoder(context, part, path);
    for (int y = 0; y < height; y += lines_per_chunk) {
        exr_chunk_info_t chunk{};
        check(exr_write_scanline_chunk_info(context, part, y, &chunk), path);
        encoder.run(chunk, type, rgba + size_t(chunk.start_y) * size_t(width) * 4, size_t(width) * 4);
    }
}

// Encodes level `level` (interleaved RGBA samples of type T, top row first) tile by tile.
template <typename T>
void write_level_tiles(exr_context_t context, int part, int level, int width, int height, exr_pixel_type_t type,
                       const T* rgba, ChunkEncoder& encoder, const std::string& path)
{
    const int tiles_x = (width + kMipTileSize - 1) / kMipTileSize, tiles_y = (height + kMipTileSize - 1) / kMipTileSize;
    for (int ty = 0; ty < tiles_y; ++ty)
        for (int tx = 0; tx < tiles_x; ++tx) {
            exr_chunk_info_t chunk{};
            check(exr_write_tile_chunk_info(context, part, tx, ty, level, level, &chunk), path);
            // OpenEXRCore 3.1 clips a level's last tiles against level 0's size, not the level's
            // (a 100-texel level 1 of a 200-texel map would get a second tile 64 wide, not 36):
            // the tile's size and bytes are set here from the level's own size.
            chunk.width = std::min(kMipTileSize, width - tx * kMipTileSize);
            chunk.height = std::min(kMipTileSize, height - ty * kMipTileSize);
            chunk.unpacked_size = uint64_t(chunk.width) * uint64_t(chunk.height) * 4 * sizeof(T);
            const size_t x0 = size_t(tx) * kMipTileSize, y0 = size_t(ty) * kMipTileSize;
            encoder.run(chunk, type, rgba + (y0 * size_t(width) + x0) * 4, size_t(width) * 4);
        }
}

}  // namespace

void write_rgba_exr(const std::string& path, int width, int height, const float* rgba,
                    PixelPrecision precision, const std::vector<ExrAttribute>& attributes,
                    ExrCompression compression)
{
    if (width <= 0 || height <= 0 || !rgba)
        throw Error(Status::invalid_argument,
                    "cannot write '" + path + "': no pixels (" + std::to_string(width) + " x " +
                        std::to_string(height) + ")");
    // Half samples are rounded here (to nearest, as OpenImageIO and Imath do) and stored as they are.
    std::vector<Imath::half> halves;
    if (precision == PixelPrecision::half)
        halves.assign(rgba, rgba + size_t(width) * size_t(height) * 4);
    const exr_pixel_type_t type = precision == PixelPrecision::half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
    write_file_atomic(path, [&](const std::string& temp_path) {
        ExrWriter writer(temp_path, path);
        const int part = write_header(writer.get(), width, height, type, attributes, compression, path);
        if (precision == PixelPrecision::half)
            write_scanlines(writer.get(), part, width, height, type, halves.data(), path);
        else
            write_scanlines(writer.get(), part, width, height, type, rgba, path);
        writer.finish();
    });
}

void write_mip_rgba_exr(const std::string& path, std::span<const RgbaLevel> levels, PixelPrecision precision,
                        const std::vector<ExrAttribute>& attributes, ExrCompression compression)
{
    const auto refuse = [&](const std::string& why) {
        throw Error(Status::invalid_argument, "cannot write '" + path + "': " + why);
    };
    if (levels.empty() || levels[0].width <= 0 || levels[0].height <= 0) refuse("no pixels");
    for (size_t level = 0; level < levels.size(); ++level)
        if (!levels[level].rgba) refuse("level " + std::to_string(level) + " has no pixels");
    const int width = levels[0].width, height = levels[0].height;
    const exr_pixel_type_t type = precision == PixelPrecision::half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
    write_file_atomic(path, [&](const std::string& temp_path) {
        ExrWriter writer(temp_path, path);
        const int part = write_header(writer.get(), width, height, type, attributes, compression, path, true);
        // The chain must be the one OpenEXR lays out for this header (its level count and sizes),
        // checked before any tile is written.
        int32_t levels_x = 0, levels_y = 0;
        check(exr_get_tile_levels(writer.get(), part, &levels_x, &levels_y), path);
        if (levels_x != int(levels.size()) || levels_y != int(levels.size()))
            refuse(std::to_string(levels.size()) + " levels, a " + std::to_string(width) + " x " +
                   std::to_string(height) + " MIP chain has " + std::to_string(levels_x));
        for (size_t level = 0; level < levels.size(); ++level) {
            int32_t w = 0, h = 0;
            check(exr_get_level_sizes(writer.get(), part, int(level), int(level), &w, &h), path);
            if (levels[level].width != w || levels[level].height != h)
                refuse("level " + std::to_string(level) + " is " + std::to_string(levels[level].width) + " x " +
                       std::to_string(levels[level].height) + ", expected " + std::to_string(w) + " x " +
                       std::to_string(h));
        }
        {
            // Destroyed before finish(), which releases the context the encoder refers to.
            ChunkEncoder encoder(writer.get(), part, path);
            std::vector<Imath::half> halves;
            for (size_t level = 0; level < levels.size(); ++level) {
                const RgbaLevel& l = levels[level];
                if (precision == PixelPrecision::half) {
                    // Rounded here (to nearest, as OpenImageIO and Imath do) and stored as they are.
                    halves.assign(l.rgba, l.rgba + size_t(l.width) * size_t(l.height) * 4);
                    write_level_tiles(writer.get(), part, int(level), l.width, l.height, type, halves.data(), encoder, path);
                } else {
                    write_level_tiles(writer.get(), part, int(level), l.width, l.height, type, l.rgba, encoder, path);
                }
            }
        }
        writer.finish();
    });
}

}  // namespace ndfbake
