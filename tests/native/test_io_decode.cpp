// Tests for io/ reading: normal-map decoding from every supported format and bit depth, the
// conventions (DirectX / OpenGL green, sRGB tags, float encodings), the repair rule, in-memory
// pixels, and the errors for bad files. Fixture images are written at test time with OpenImageIO
// into a fresh folder per test (io_fixtures.h).

#include <gtest/gtest.h>

#include "io_fixtures.h"

namespace ndfbake {
namespace {

using namespace io_fixtures;

// ---- formats, depths, channel counts ---------------------------------------------------------

struct FormatCase {
    std::string extension;
    OIIO::TypeDesc file_type;
    int channels;
    std::string format_name;
    int bits;
    bool float_data;
    float tolerance;  // max component error against the reference normals
};

// Names the case in test output (ctest lists it) instead of dumping its bytes.
void PrintTo(const FormatCase& c, std::ostream* os)
{
    *os << c.extension << " " << c.file_type.c_str() << " " << c.channels << "ch";
}

class DecodeFormatTest : public IoTest, public ::testing::WithParamInterface<FormatCase> {};

TEST_P(DecodeFormatTest, DecodesToTheReferenceNormals)
{
    const FormatCase& c = GetParam();
    const std::vector<Vec3> reference = smooth_normals(kWidth, kHeight);
    const std::string file = path("normals." + c.extension);
    const bool lossy = c.format_name == "jpeg";
    // Float files are written signed, except TIFF, which exercises automatic unsigned detection.
    const bool signed_floats = c.float_data && c.extension != "tif";
    const std::vector<float> values = stored_values(reference, c.channels, signed_floats);
    const std::vector<Attribute> jpeg_quality = {{"CompressionQuality", "100"},
                                                 {"jpeg:subsampling", "4:4:4"}};
    switch (c.file_type.basetype) {
    case OIIO::TypeDesc::UINT8:
        write_image(file, kWidth, kHeight, c.channels, c.file_type, quantize<uint8_t>(values),
                    lossy ? jpeg_quality : std::vector<Attribute>{});
        break;
    case OIIO::TypeDesc::UINT16:
        write_image(file, kWidth, kHeight, c.channels, c.file_type, quantize<uint16_t>(values));
        break;
    case OIIO::TypeDesc::UINT32:
        write_image(file, kWidth, kHeight, c.channels, c.file_type, quantize<uint32_t>(values));
        break;
    default:
        write_image(file, kWidth, kHeight, c.channels, c.file_type, values);
    }

    const DecodeResult result = decode_normal_map(file, DecodeOptions{});
    EXPECT_EQ(result.format, c.format_name);
    EXPECT_EQ(result.channels, c.channels);
    EXPECT_EQ(result.bits_per_channel, c.bits);
    EXPECT_EQ(result.float_data, c.float_data);
    EXPECT_EQ(result.signed_encoding, signed_floats);
    EXPECT_EQ(result.map.width, kWidth);
    EXPECT_EQ(result.map.height, kHeight);
    EXPECT_LE(max_difference(result.map.normals, reference), c.tolerance);
    if (!lossy) {
        EXPECT_EQ(result.repairs.total(), 0u);
    }
    EXPECT_EQ(has_assumption(result, "alpha"), c.channels == 4);
    EXPECT_EQ(has_assumption(result, "Z reconstructed"), c.channels == 2);
    EXPECT_TRUE(has_assumption(result, "OpenGL"));
    for (const Vec3& n : result.map.normals)
        EXPECT_NEAR(length(n), 1.0f, 1e-6f);
}

// 8-bit: rounding error 1/255 per component, a little more after Z is rebuilt from X and Y.
INSTANTIATE_TEST_SUITE_P(
    AllFormats, DecodeFormatTest,
    ::testing::Values(FormatCase{"png", OIIO::TypeDesc::UINT8, 3, "png", 8, false, 0.01f},
                      FormatCase{"png", OIIO::TypeDesc::UINT8, 4, "png", 8, false, 0.01f},
                      FormatCase{"png", OIIO::TypeDesc::UINT8, 2, "png", 8, false, 0.01f},
                      FormatCase{"png", OIIO::TypeDesc::UINT16, 3, "png", 16, false, 1e-4f},
                      FormatCase{"tga", OIIO::TypeDesc::UINT8, 3, "targa", 8, false, 0.01f},
                      FormatCase{"tga", OIIO::TypeDesc::UINT8, 4, "targa", 8, false, 0.01f},
                      FormatCase{"jpg", OIIO::TypeDesc::UINT8, 3, "jpeg", 8, false, 0.04f},
                      FormatCase{"tif", OIIO::TypeDesc::UINT8, 3, "tiff", 8, false, 0.01f},
                      FormatCase{"tif", OIIO::TypeDesc::UINT16, 4, "tiff", 16, false, 1e-4f},
                      FormatCase{"tif", OIIO::TypeDesc::UINT32, 3, "tiff", 32, false, 1e-6f},
                      FormatCase{"tif", OIIO::TypeDesc::FLOAT, 3, "tiff", 32, true, 1e-6f},
                      FormatCase{"exr", OIIO::TypeDesc::HALF, 3, "openexr", 16, true, 2e-3f},
                      FormatCase{"exr", OIIO::TypeDesc::HALF, 4, "openexr", 16, true, 2e-3f},
                      FormatCase{"exr", OIIO::TypeDesc::HALF, 2, "openexr", 16, true, 2e-3f},
                      FormatCase{"exr", OIIO::TypeDesc::FLOAT, 3, "openexr", 32, true, 1e-6f},
                      FormatCase{"exr", OIIO::TypeDesc::FLOAT, 2, "openexr", 32, true, 1e-6f}),
    [](const ::testing::TestParamInfo<FormatCase>& info) {
        return info.param.extension + "_" + info.param.file_type.c_str() + "_" +
               std::to_string(info.param.channels) + "ch";
    });

TEST_F(IoTest, EightBitQuantizationIsNotCountedAsRepair)
{
    const int size = 64;
    const std::vector<float> values = stored_values(hemisphere_normals(size, size), 3, false);
    for (bool truncate : {false, true}) {
        SCOPED_TRACE(truncate ? "truncating encoder" : "rounding encoder");
        const std::vector<uint8_t> codes = quantize<uint8_t>(values, truncate);
        // The stored vectors really are off unit length by more than float noise.
        float worst = 0.0f;
        for (size_t i = 0; i < codes.size(); i += 3) {
            const Vec3 n{codes[i] / 127.5f - 1.0f, codes[i + 1] / 127.5f - 1.0f,
                         codes[i + 2] / 127.5f - 1.0f};
            worst = std::max(worst, std::abs(length(n) - 1.0f));
        }
        EXPECT_GT(worst, 0.004f);
        EXPECT_LT(worst, kUnitLengthTolerance);

        for (const std::string ext : {"png", "tga"}) {
            const std::string file = path("hemisphere." + ext);
            write_image(file, size, size, 3, OIIO::TypeDesc::UINT8, codes);
            const DecodeResult result = decode_normal_map(file, DecodeOptions{});
            EXPECT_EQ(result.repairs.total(), 0u) << ext;
        }
    }
}

TEST_F(IoTest, SixteenBitAndTwoChannelMapsMatchTheEightBitOriginal)
{
    const std::vector<Vec3> reference = smooth_normals(kWidth, kHeight);
    const DecodeResult original = decode_normal_map(write_reference_png("n8.png"), DecodeOptions{});

    write_image(path("n16.png"), kWidth, kHeight, 3, OIIO::TypeDesc::UINT16,
                quantize<uint16_t>(stored_values(reference, 3, false)));
    write_image(path("n2.png"), kWidth, kHeight, 2, OIIO::TypeDesc::UINT8,
                quantize<uint8_t>(stored_values(reference, 2, false)));
    write_image(path("n2.exr"), kWidth, kHeight, 2, OIIO::TypeDesc::FLOAT,
                stored_values(reference, 2, true));
    for (const std::string name : {"n16.png", "n2.png", "n2.exr"}) {
        const DecodeResult result = decode_normal_map(path(name), DecodeOptions{});
        EXPECT_LE(max_difference(result.map.normals, original.map.normals), 0.012f) << name;
        EXPECT_EQ(result.repairs.total(), 0u) << name;
    }
}

// ---- conventions and colour tags -------------------------------------------------------------

TEST_F(IoTest, DirectXMapDecodesExactlyLikeItsOpenGLTwin)
{
    const std::vector<Vec3> reference = hemisphere_normals(kWidth, kHeight);
    DecodeOptions directx;
    directx.convention = Convention::directx;

    const auto check = [&](const std::string& gl_name, const std::string& dx_name) {
        SCOPED_TRACE(gl_name);
        const DecodeResult gl = decode_normal_map(path(gl_name), DecodeOptions{});
        const DecodeResult dx = decode_normal_map(path(dx_name), directx);
        expect_identical(gl.map.normals, dx.map.normals);
        EXPECT_TRUE(has_assumption(dx, "DirectX"));
    };

    const std::vector<uint8_t> codes8 = quantize<uint8_t>(stored_values(reference, 3, false));
    write_image(path("gl8.png"), kWidth, kHeight, 3, OIIO::TypeDesc::UINT8, codes8);
    write_image(path("dx8.png"), kWidth, kHeight, 3, OIIO::TypeDesc::UINT8,
                flip_green_codes(codes8, 3));
    check("gl8.png", "dx8.png");

    const std::vector<uint16_t> codes16 = quantize<uint16_t>(stored_values(reference, 4, false));
    write_image(path("gl16.tif"), kWidth, kHeight, 4, OIIO::TypeDesc::UINT16, codes16);
    write_image(path("dx16.tif"), kWidth, kHeight, 4, OIIO::TypeDesc::UINT16,
                flip_green_codes(codes16, 4));
    check("gl16.tif", "dx16.tif");

    const std::vector<uint8_t> codes2 = quantize<uint8_t>(stored_values(reference, 2, false));
    write_image(path("gl2.png"), kWidth, kHeight, 2, OIIO::TypeDesc::UINT8, codes2);
    write_image(path("dx2.png"), kWidth, kHeight, 2, OIIO::TypeDesc::UINT8,
                flip_green_codes(codes2, 2));
    check("gl2.png", "dx2.png");

    const std::vector<float> values = stored_values(reference, 3, true);
    write_image(path("gl.exr"), kWidth, kHeight, 3, OIIO::TypeDesc::FLOAT, values);
    write_image(path("dx.exr"), kWidth, kHeight, 3, OIIO::TypeDesc::FLOAT,
                flip_green_signed(values, 3));
    check("gl.exr", "dx.exr");
}

double srgb_eotf(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }

TEST_F(IoTest, SrgbTaggedPngIsRawDataUnlessLinearizeIsAsked)
{
    const std::vector<uint8_t> codes =
        quantize<uint8_t>(stored_values(smooth_normals(kWidth, kHeight), 3, false));
    write_image(path("srgb.png"), kWidth, kHeight, 3, OIIO::TypeDesc::UINT8, codes,
                {{"oiio:ColorSpace", "sRGB"}});
    write_image(path("linear.png"), kWidth, kHeight, 3, OIIO::TypeDesc::UINT8, codes,
                {{"oiio:ColorSpace", "Linear"}});  // OpenImageIO writes gAMA 1.0
    {
        std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path("srgb.png"));
        ASSERT_TRUE(in);
        if (in->spec().get_string_attribute("oiio:ColorSpace") != "sRGB")
            GTEST_SKIP() << "this OpenImageIO does not read back a PNG's sRGB tag";
    }

    const DecodeResult srgb = decode_normal_map(path("srgb.png"), DecodeOptions{});
    const DecodeResult linear = decode_normal_map(path("linear.png"), DecodeOptions{});
    EXPECT_TRUE(srgb.srgb_tagged);
    EXPECT_FALSE(linear.srgb_tagged);
    expect_identical(srgb.map.normals, linear.map.normals);
    EXPECT_TRUE(
        has_assumption(srgb, "8-bit sRGB-tagged PNG: values taken as raw data, not linearized"));
    EXPECT_FALSE(has_assumption(linear, "sRGB"));

    DecodeOptions linearize;
    linearize.srgb = SrgbPolicy::linearize;
    const DecodeResult linearized = decode_normal_map(path("srgb.png"), linearize);
    EXPECT_TRUE(has_assumption(linearized, "sRGB transfer function removed"));
    for (size_t i = 0; i < linearized.map.normals.size(); ++i) {
        const Vec3 raw{float(2 * srgb_eotf(codes[3 * i] / 255.0) - 1),
                       float(2 * srgb_eotf(codes[3 * i + 1] / 255.0) - 1),
                       float(2 * srgb_eotf(codes[3 * i + 2] / 255.0) - 1)};
        const Vec3 expected = normalize_or(raw, {0, 0, 1});
        ASSERT_NEAR(linearized.map.normals[i].x, expected.x, 1e-5f) << "pixel " << i;
        ASSERT_NEAR(linearized.map.normals[i].y, expected.y, 1e-5f) << "pixel " << i;
        ASSERT_NEAR(std::abs(linearized.map.normals[i].z), std::abs(expected.z), 1e-5f);
    }
    // Linearizing the file of a linear-tagged map changes nothing: there is no tag to undo.
    expect_identical(decode_normal_map(path("linear.png"), linearize).map.normals,
                     linear.map.normals);
}

TEST_F(IoTest, FloatEncodingIsDetectedAndRecorded)
{
    const std::vector<Vec3> reference = smooth_normals(kWidth, kHeight);
    std::vector<float> unsigned_values = stored_values(reference, 3, false);
    unsigned_values[5] = -0.005f;  // a lossy dip below zero is not a sign of signed data
    write_image(path("unsigned.exr"), kWidth, kHeight, 3, OIIO::TypeDesc::FLOAT, unsigned_values);
    write_image(path("signed.exr"), kWidth, kHeight, 3, OIIO::TypeDesc::FLOAT,
                stored_values(reference, 3, true));

    const DecodeResult u = decode_normal_map(path("unsigned.exr"), DecodeOptions{});
    EXPECT_FALSE(u.signed_encoding);
    EXPECT_TRUE(has_assumption(u, "taken as unsigned [0, 1]"));
    const DecodeResult s = decode_normal_map(path("signed.exr"), DecodeOptions{});
    EXPECT_TRUE(s.signed_encoding);
    EXPECT_TRUE(has_assumption(s, "taken as signed [-1, 1]"));
    EXPECT_LE(max_difference(s.map.normals, reference), 1e-6f);

    DecodeOptions forced;
    forced.float_encoding = FloatEncoding::signed_unit;
    const DecodeResult forced_signed = decode_normal_map(path("unsigned.exr"), forced);
    EXPECT_TRUE(forced_signed.signed_encoding);
    EXPECT_FALSE(has_assumption(forced_signed, "taken as signed"));
    EXPECT_GT(max_difference(forced_signed.map.normals, reference), 0.1f);
}

// ---- repairs ---------------------------------------------------------------------------------

TEST_F(IoTest, BrokenPixelsAreRepairedAndCountedExactly)
{
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    const std::vector<float> pixels = {
        nan,  0.0f, 1.0f,   // non-finite -> +Z
        0.0f, 0.0f, inf,    // non-finite -> +Z
        0.0f, 0.0f, 0.0f,   // zero -> +Z
        0.6f, 0.0f, -0.8f,  // below the horizon -> reflected
        0.0f, 0.0f, 2.0f,   // non-unit -> normalized
        1.0f, 0.0f, 0.0f,   // exactly on the horizon: kept
        0.0f, -1.0f, 0.0f,  // exactly on the horizon: kept
        0.0f, 0.6f, 0.8f,   // fine
    };
    write_image(path("broken.exr"), 4, 2, 3, OIIO::TypeDesc::FLOAT, pixels);
    DecodeOptions options;
    options.float_encoding = FloatEncoding::signed_unit;
    const DecodeResult result = decode_normal_map(path("broken.exr"), options);

    EXPECT_EQ(result.repairs.non_finite, 2u);
    EXPECT_EQ(result.repairs.zero_length, 1u);
    EXPECT_EQ(result.repairs.below_horizon, 1u);
    EXPECT_EQ(result.repairs.renormalized, 1u);
    EXPECT_EQ(result.repairs.total(), 5u);
    const std::vector<Vec3> expected = {{0, 0, 1},   {0, 0, 1},  {0, 0, 1}, {0.6f, 0, 0.8f},
                                        {0, 0, 1},   {1, 0, 0},  {0, -1, 0}, {0, 0.6f, 0.8f}};
    for (size_t i = 0; i < expected.size(); ++i) {
        EXPECT_NEAR(result.map.normals[i].x, expected[i].x, 1e-6f) << "pixel " << i;
        EXPECT_NEAR(result.map.normals[i].y, expected[i].y, 1e-6f) << "pixel " << i;
        EXPECT_NEAR(result.map.normals[i].z, expected[i].z, 1e-6f) << "pixel " << i;
    }
}

TEST(RepairNormals, NormalizesWithinToleranceWithoutCounting)
{
    NormalMap map;
    map.width = 5;
    map.height = 1;
    map.normals = {{0, 0, 0.999f},         // within tolerance: normalized, not counted
                   {1, 0, -0.0f},          // on the horizon, -0 z: kept with z = +0
                   {0, 0, 0.005f},         // shorter than kMinNormalLength: +Z
                   {3e30f, 0, 4e30f},      // huge but finite: normalized without overflow
                   {0.3f, 0.4f, -1.2f}};   // below the horizon and not unit: both rules apply
    RepairCounts counts;
    repair_normals(map, counts);

    EXPECT_EQ(counts.renormalized, 2u);
    EXPECT_EQ(counts.below_horizon, 1u);
    EXPECT_EQ(counts.zero_length, 1u);
    EXPECT_EQ(counts.non_finite, 0u);
    EXPECT_FLOAT_EQ(map.normals[0].z, 1.0f);
    EXPECT_EQ(map.normals[1].x, 1.0f);
    EXPECT_FALSE(std::signbit(map.normals[1].z));
    EXPECT_EQ(map.normals[2].z, 1.0f);
    EXPECT_FLOAT_EQ(map.normals[3].x, 0.6f);
    EXPECT_FLOAT_EQ(map.normals[3].z, 0.8f);
    EXPECT_FLOAT_EQ(map.normals[4].z, 1.2f / 1.3f);
}

// ---- in-memory pixels ------------------------------------------------------------------------

TEST(DecodeNormalPixels, DecodesUnsignedSignedAndTwoChannelPixels)
{
    const std::vector<float> unsigned_pixels = {0.5f, 0.5f, 1.0f, 0.8f, 0.5f, 0.9f};
    const DecodeResult u = decode_normal_pixels(unsigned_pixels.data(), 2, 1, 3, false, {});
    EXPECT_EQ(u.format, "memory");
    EXPECT_FALSE(u.signed_encoding);
    EXPECT_FLOAT_EQ(u.map.normals[0].z, 1.0f);
    EXPECT_FLOAT_EQ(u.map.normals[1].x, 0.6f);
    EXPECT_FLOAT_EQ(u.map.normals[1].z, 0.8f);
    EXPECT_EQ(u.repairs.total(), 0u);

    const std::vector<float> signed_xy = {0.6f, 0.0f, 0.0f, -0.8f};
    DecodeOptions directx;
    directx.convention = Convention::directx;
    const DecodeResult s = decode_normal_pixels(signed_xy.data(), 1, 2, 2, true, directx);
    EXPECT_TRUE(s.signed_encoding);
    EXPECT_FLOAT_EQ(s.map.at(0, 0).z, 0.8f);
    EXPECT_FLOAT_EQ(s.map.at(0, 1).y, 0.8f);
    EXPECT_FLOAT_EQ(s.map.at(0, 1).z, 0.6f);
    EXPECT_TRUE(has_assumption(s, "Z reconstructed"));

    EXPECT_NE(decode_normal_pixels(signed_xy.data(), 1, 2, 2, true, {}).source_hash,
              decode_normal_pixels(unsigned_pixels.data(), 1, 2, 2, true, {}).source_hash);
}

TEST(DecodeNormalPixels, RejectsBadArguments)
{
    const std::vector<float> pixels(64, 0.5f);
    expect_error([&] { decode_normal_pixels(nullptr, 2, 2, 3, false, {}); },
                 Status::invalid_argument, {"in-memory", "null"});
    expect_error([&] { decode_normal_pixels(pixels.data(), 0, 2, 3, false, {}); },
                 Status::invalid_argument, {"in-memory", "0 x 2"});
    expect_error([&] { decode_normal_pixels(pixels.data(), 2, 2, 1, false, {}); },
                 Status::unsupported_format, {"1 channel"});
    expect_error([&] { decode_normal_pixels(pixels.data(), 2, 2, 5, false, {}); },
                 Status::unsupported_format, {"5 channels"});
    DecodeOptions small;
    small.max_pixels = 3;
    expect_error([&] { decode_normal_pixels(pixels.data(), 2, 2, 3, false, small); },
                 Status::out_of_memory, {"2 x 2", "limit of 3"});
}

// ---- bad files -------------------------------------------------------------------------------

TEST_F(IoTest, MissingEmptyAndForeignFilesGetTheirOwnStatus)
{
    const DecodeOptions options;
    expect_error([&] { decode_normal_map(path("missing.png"), options); }, Status::file_not_found,
                 {path("missing.png"), "no such file"});

    write_bytes(path("empty.png"), "");
    expect_error([&] { decode_normal_map(path("empty.png"), options); }, Status::corrupt_file,
                 {path("empty.png"), "file is empty (0 bytes)"});

    write_bytes(path("notes.txt"), "these are notes, not pixels\n");
    expect_error([&] { decode_normal_map(path("notes.txt"), options); },
                 Status::unsupported_format, {path("notes.txt")});

    write_bytes(path("garbage.png"), std::string(200, '\x5a'));
    expect_error([&] { decode_normal_map(path("garbage.png"), options); }, Status::corrupt_file,
                 {path("garbage.png"), "Not a PNG file"});

    expect_error([&] { decode_normal_map(dir_.string(), options); }, Status::invalid_argument,
                 {dir_.string(), "not a regular file"});
}

TEST_F(IoTest, TruncatedFilesAreCorrupt)
{
    const std::vector<Vec3> reference = hemisphere_normals(128, 128);
    const std::vector<uint8_t> codes = quantize<uint8_t>(stored_values(reference, 3, false));
    write_image(path("full.png"), 128, 128, 3, OIIO::TypeDesc::UINT8, codes);
    write_image(path("full.tif"), 128, 128, 3, OIIO::TypeDesc::UINT8, codes);
    write_image(path("full.jpg"), 128, 128, 3, OIIO::TypeDesc::UINT8, codes);
    write_image(path("full.tga"), 128, 128, 3, OIIO::TypeDesc::UINT8, codes);
    write_image(path("full.exr"), 128, 128, 3, OIIO::TypeDesc::HALF,
                stored_values(reference, 3, true));

    for (const std::string ext : {"png", "tif", "jpg", "tga", "exr"}) {
        const std::string bytes = read_bytes(path("full." + ext));
        const std::string cut = path("cut." + ext);
        write_bytes(cut, bytes.substr(0, bytes.size() / 2));
        expect_error([&] { decode_normal_map(cut, DecodeOptions{}); }, Status::corrupt_file,
                     {cut, "truncated"});
    }
    const std::vector<float> rgba(128 * 128 * 4, 0.5f);
    write_rgba_exr(path("lobe.exr"), 128, 128, rgba.data(), PixelPrecision::half, {});
    const std::string exr = read_bytes(path("lobe.exr"));
    write_bytes(path("cut_lobe.exr"), exr.substr(0, exr.size() / 2));
    int width = 0, height = 0;
    expect_error([&] { read_rgba_exr(path("cut_lobe.exr"), width, height); },
                 Status::corrupt_file, {path("cut_lobe.exr")});
}

TEST_F(IoTest, WrongChannelCountsAreUnsupported)
{
    write_image(path("grey.png"), 8, 8, 1, OIIO::TypeDesc::UINT8, std::vector<uint8_t>(64, 128));
    expect_error([&] { decode_normal_map(path("grey.png"), DecodeOptions{}); },
                 Status::unsupported_format, {path("grey.png"), "1 channel;"});

    write_image(path("five.tif"), 8, 8, 5, OIIO::TypeDesc::UINT8, std::vector<uint8_t>(320, 128));
    expect_error([&] { decode_normal_map(path("five.tif"), DecodeOptions{}); },
                 Status::unsupported_format, {path("five.tif"), "5 channels"});

    write_image(path("five.exr"), 8, 8, 5, OIIO::TypeDesc::HALF, std::vector<float>(320, 0.5f));
    expect_error([&] { decode_normal_map(path("five.exr"), DecodeOptions{}); },
                 Status::unsupported_format, {path("five.exr"), "5 channels"});
}

TEST_F(IoTest, OversizedImagesFailFromTheHeaderBeforeReadingPixels)
{
    DecodeOptions small;
    small.max_pixels = 100;
    const std::string file = write_reference_png("normals.png");
    expect_error([&] { decode_normal_map(file, small); }, Status::out_of_memory,
                 {file, "32 x 16 = 512 pixels", "limit of 100"});

    // An 18-byte TGA header claiming 65535 x 65535 pixels and no pixel data: only a check made
    // on the header, before allocating, can answer out_of_memory rather than corrupt_file.
    const unsigned char header[18] = {0, 0, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0xff, 0xff, 0xff,
                                      24, 0x20};
    write_bytes(path("huge.tga"), std::string(reinterpret_cast<const char*>(header), 18));
    expect_error([&] { decode_normal_map(path("huge.tga"), DecodeOptions{}); },
                 Status::out_of_memory, {path("huge.tga"), "65535 x 65535"});
}

TEST_F(IoTest, SourceHashIsFnv1aOfTheFileBytes)
{
    const std::string file = write_reference_png("normals.png");
    uint64_t expected = 14695981039346656037ull;
    for (unsigned char byte : read_bytes(file))
        expected = (expected ^ byte) * 1099511628211ull;
    EXPECT_EQ(decode_normal_map(file, DecodeOptions{}).source_hash, expected);

    DecodeOptions directx;
    directx.convention = Convention::directx;
    EXPECT_EQ(decode_normal_map(file, directx).source_hash, expected);
}

}  // namespace
}  // namespace ndfbake
