// Tests for io/ writing: the self-describing EXR round trip (pixels, typed attributes, run-length
// and half files), atomic writes and output folders, and report.json's writer.

#include <gtest/gtest.h>

#include "io_fixtures.h"

namespace ndfbake {
namespace {

using namespace io_fixtures;

// ---- EXR writing and reading -----------------------------------------------------------------

std::vector<float> test_rgba(int width, int height)
{
    std::vector<float> rgba;
    for (int i = 0; i < width * height * 4; ++i)
        rgba.push_back(std::sin(0.37f * float(i)) * (i % 7 == 0 ? 3.0f : 1.0f));
    return rgba;
}

TEST_F(IoTest, ExrRoundTripKeepsPixelsAndTypedAttributes)
{
    const std::vector<float> rgba = test_rgba(8, 4);
    const std::vector<ExrAttribute> attributes = {
        {"ndfbake:level", 3},
        {"ndfbake:lobe", 1},
        {"ndfbake:fit_error", 0.125f},
        {"ndfbake:source", std::string("rock_normal.png")}};
    const std::string file = path("lobe.exr");
    write_rgba_exr(file, 8, 4, rgba.data(), PixelPrecision::single, attributes);
    EXPECT_EQ(files_in(dir_), std::vector<std::string>{"lobe.exr"});

    int width = 0, height = 0;
    EXPECT_EQ(read_rgba_exr(file, width, height), rgba);
    EXPECT_EQ(width, 8);
    EXPECT_EQ(height, 4);

    const ImageInfo info = read_image_info(file);
    EXPECT_EQ(info.format, "openexr");
    EXPECT_EQ(info.width, 8);
    EXPECT_EQ(info.height, 4);
    EXPECT_EQ(info.channels, 4);
    EXPECT_EQ(info.pixel_type, "float");
    const auto has = [&](const std::string& name, const std::string& value) {
        return std::find(info.attributes.begin(), info.attributes.end(),
                         std::pair<std::string, std::string>(name, value)) != info.attributes.end();
    };
    EXPECT_TRUE(has("ndfbake:level", "3"));
    EXPECT_TRUE(has("ndfbake:lobe", "1"));
    EXPECT_TRUE(has("ndfbake:fit_error", "0.125"));
    EXPECT_TRUE(has("ndfbake:source", "rock_normal.png"));
    EXPECT_TRUE(has("compression", "zip"));

    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(file);
    ASSERT_TRUE(in);
    const OIIO::ImageSpec& spec = in->spec();
    ASSERT_TRUE(spec.find_attribute("ndfbake:level"));
    EXPECT_EQ(spec.find_attribute("ndfbake:level")->type(), OIIO::TypeInt);
    EXPECT_EQ(spec.find_attribute("ndfbake:lobe")->type(), OIIO::TypeInt);
    EXPECT_EQ(spec.get_int_attribute("ndfbake:level"), 3);
    EXPECT_EQ(spec.find_attribute("ndfbake:fit_error")->type(), OIIO::TypeFloat);
    EXPECT_EQ(spec.find_attribute("ndfbake:source")->type(), OIIO::TypeString);
}

TEST_F(IoTest, RunLengthFilesRoundTripExactly)
{
    // A level-0 lobe slot: zero wherever the texel's lobe sits in another slot.
    std::vector<float> rgba = test_rgba(16, 8);
    for (size_t i = 0; i < rgba.size(); i += 12) std::fill_n(&rgba[i], 8, 0.0f);
    const std::string file = path("level0.exr");
    write_rgba_exr(file, 16, 8, rgba.data(), PixelPrecision::single, {}, ExrCompression::run_length);
    int width = 0, height = 0;
    EXPECT_EQ(read_rgba_exr(file, width, height), rgba);
    const ImageInfo info = read_image_info(file);
    EXPECT_NE(std::find(info.attributes.begin(), info.attributes.end(),
                        std::pair<std::string, std::string>("compression", "rle")),
              info.attributes.end());
}

TEST_F(IoTest, HalfPrecisionRoundTripIsWithinHalfTolerance)
{
    const std::vector<float> rgba = test_rgba(16, 8);
    const std::string file = path("lobe_half.exr");
    write_rgba_exr(file, 16, 8, rgba.data(), PixelPrecision::half, {{"ndfbake:level", 0}});
    int width = 0, height = 0;
    const std::vector<float> back = read_rgba_exr(file, width, height);
    ASSERT_EQ(back.size(), rgba.size());
    for (size_t i = 0; i < rgba.size(); ++i) {
        // Half keeps 11 significant bits: relative error 2^-11, plus subnormal spacing near 0.
        EXPECT_NEAR(back[i], rgba[i], std::abs(rgba[i]) * 4.9e-4f + 6e-8f) << "sample " << i;
    }
    EXPECT_EQ(read_image_info(file).pixel_type, "half");
}

TEST_F(IoTest, ExrReadersReportBadFilesLikeTheDecoder)
{
    int width = 0, height = 0;
    expect_error([&] { read_rgba_exr(path("missing.exr"), width, height); },
                 Status::file_not_found, {path("missing.exr")});
    expect_error([&] { read_image_info(path("missing.exr")); }, Status::file_not_found,
                 {path("missing.exr")});
    write_bytes(path("garbage.exr"), std::string(100, 'x'));
    expect_error([&] { read_image_info(path("garbage.exr")); }, Status::corrupt_file,
                 {path("garbage.exr")});
    const std::string png = write_reference_png("three.png");
    expect_error([&] { read_rgba_exr(png, width, height); }, Status::unsupported_format,
                 {png, "3 channels, expected 4"});
}

// ---- atomic writes and output folders --------------------------------------------------------

TEST_F(IoTest, AtomicTextWriteLeavesOnlyTheFinalFile)
{
    const std::string file = path("report.json");
    write_text_atomic(file, "{\"first\": 1}\n");
    write_text_atomic(file, "{\"second\": 2}\n");
    EXPECT_EQ(read_bytes(file), "{\"second\": 2}\n");
    EXPECT_EQ(files_in(dir_), std::vector<std::string>{"report.json"});
}

TEST_F(IoTest, AtomicWriteUsesAHiddenSiblingWithTheSameExtension)
{
    std::string seen;
    write_file_atomic(path("lobe.exr"), [&](const std::string& temp_path) {
        seen = temp_path;
        write_bytes(temp_path, "data");
    });
    const fs::path temp(seen);
    EXPECT_EQ(temp.parent_path(), dir_);
    EXPECT_EQ(temp.extension(), ".exr");
    EXPECT_EQ(temp.filename().string().rfind(".lobe.tmp-", 0), 0u) << seen;
    EXPECT_EQ(files_in(dir_), std::vector<std::string>{"lobe.exr"});
}

TEST_F(IoTest, FailedAtomicWriteRemovesTheTempFileAndKeepsTheOldOne)
{
    const std::string file = path("lobe.exr");
    write_bytes(file, "old contents");
    const auto failing_writer = [](const std::string& temp_path) {
        write_bytes(temp_path, "half of the new con");
        throw std::runtime_error("disk on fire");
    };
    EXPECT_THROW(write_file_atomic(file, failing_writer), std::runtime_error);
    EXPECT_EQ(read_bytes(file), "old contents");
    EXPECT_EQ(files_in(dir_), std::vector<std::string>{"lobe.exr"});
}

TEST_F(IoTest, AFailedWriteNamesTheFileAskedForNotItsTemporary)
{
    // OpenImageIO names the file it was given, the temporary: the error says the user's file.
    const std::string file = path("missing") + "/normal.png";
    try {
        write_normal_map(file, synthesize(Pattern::bumps, 4, 4));
        FAIL() << "wrote into a missing folder";
    } catch (const Error& e) {
        const std::string message = e.what();
        EXPECT_EQ(message.find(".tmp-"), std::string::npos) << message;
        EXPECT_NE(message.find("cannot write '" + file + "'"), std::string::npos) << message;
    }
}

TEST_F(IoTest, EnsureWritableDirectoryCreatesMissingFolders)
{
    const fs::path nested = dir_ / "a" / "b" / "c";
    ensure_writable_directory(nested.string());
    EXPECT_TRUE(fs::is_directory(nested));
    EXPECT_TRUE(files_in(nested).empty());  // the probe file is gone
    ensure_writable_directory(nested.string());  // existing folder: fine
}

// A regular file used as a folder blocks writes even for root, unlike permission bits.
TEST_F(IoTest, FolderUnderARegularFileIsNotWritable)
{
    write_bytes(path("file.txt"), "a file, not a folder");
    const std::string folder = path("file.txt") + "/sub";
    expect_error([&] { ensure_writable_directory(folder); }, Status::io_error,
                 {"output folder '" + folder + "' is not writable: "});

    const std::vector<float> rgba = test_rgba(2, 2);
    expect_error(
        [&] { write_rgba_exr(folder + "/lobe.exr", 2, 2, rgba.data(), PixelPrecision::half, {}); },
        Status::io_error, {folder + "/lobe.exr"});
    EXPECT_EQ(files_in(dir_), std::vector<std::string>{"file.txt"});
}

// Permission bits do not bind root: a test running as root (CI, containers) takes nobody's
// effective ids for the block, as tests/blender/test_addon_bad_inputs.py does, and gives them back
// after. The saved set-user-ID stays 0, which is what allows the way back.
class UnprivilegedScope {
public:
    UnprivilegedScope() : dropped_(::geteuid() == 0)
    {
        if (dropped_ && (::setegid(testing_support::kNobodyGid) != 0 || ::seteuid(testing_support::kNobodyUid) != 0))
            throw std::runtime_error("cannot take nobody's effective ids");
    }
    ~UnprivilegedScope()
    {
        if (dropped_ && (::seteuid(0) != 0 || ::setegid(0) != 0)) std::abort();
    }
    UnprivilegedScope(const UnprivilegedScope&) = delete;
    UnprivilegedScope& operator=(const UnprivilegedScope&) = delete;

private:
    bool dropped_;
};

TEST_F(IoTest, ReadOnlyFolderIsNotWritable)
{
    const fs::path locked = dir_ / "locked";
    fs::create_directory(locked);
    fs::permissions(locked, fs::perms::owner_read | fs::perms::owner_exec | fs::perms::group_read |
                                fs::perms::group_exec | fs::perms::others_read | fs::perms::others_exec);
    const UnprivilegedScope unprivileged;
    expect_error([&] { ensure_writable_directory(locked.string()); }, Status::io_error,
                 {locked.string(), "not writable", "Permission denied"});
    const std::vector<float> rgba = test_rgba(2, 2);
    expect_error([&] {
        write_rgba_exr((locked / "lobe.exr").string(), 2, 2, rgba.data(), PixelPrecision::half, {});
    }, Status::io_error, {(locked / "lobe.exr").string()});
    EXPECT_TRUE(files_in(locked).empty());
}

// ---- report.json -----------------------------------------------------------------------------

// The string value `s` as JsonWriter writes it, without the quotes.
std::string json_string(const std::string& s)
{
    JsonWriter json;
    json.begin_array().value(nullptr, s).end_array();
    const std::string& text = json.str();
    const size_t open = text.find('"'), close = text.rfind('"');
    return text.substr(open + 1, close - open - 1);
}

TEST(JsonWriter, WellFormedUtf8PassesThroughUnchanged)
{
    for (const std::string s : {"normal map é ü.png", "Ñandú 法线", "😀 \xf4\x8f\xbf\xbf", "\xe0\xa0\x80 \xef\xbf\xbd"})
        EXPECT_EQ(json_string(s), s);
    EXPECT_EQ(json_string("a\"b\\c\nd\te"), "a\\\"b\\\\c\\nd\\u0009e");  // escapes as before
    EXPECT_EQ(json_string(std::string("x\0y", 3)), "x\\u0000y");
}

// A file name is bytes: one that is not UTF-8 (Latin-1 here) must not make report.json invalid
// JSON. Each byte outside a well-formed sequence becomes \ufffd; the valid bytes around it stay.
TEST(JsonWriter, BytesThatAreNotUtf8BecomeReplacementCharacters)
{
    const std::string r = "\\ufffd";
    EXPECT_EQ(json_string("caf\xe9.png"), "caf" + r + ".png");           // Latin-1 é
    EXPECT_EQ(json_string("\xff\xfe"), r + r);                         // never in UTF-8
    EXPECT_EQ(json_string("\x80 \xbf"), r + " " + r);                  // lone continuation bytes
    EXPECT_EQ(json_string("\xc3"), r);                                 // truncated at the end
    EXPECT_EQ(json_string("\xe6\xb3 x"), r + r + " x");                // truncated inside
    EXPECT_EQ(json_string("\xc0\xaf \xe0\x80\xaf"), r + r + " " + r + r + r);  // overlong '/'
    EXPECT_EQ(json_string("\xed\xa0\x80"), r + r + r);                 // a UTF-16 surrogate
    EXPECT_EQ(json_string("\xf4\x90\x80\x80"), r + r + r + r);         // past U+10FFFF
    EXPECT_EQ(json_string("\xc3\xa9\xe9\xc3\xa9"), "\xc3\xa9" + r + "\xc3\xa9");
}

}  // namespace
}  // namespace ndfbake
