// The add-on's library as Blender loads it: loaded from its own folder by a process with an
// empty environment (no LD_LIBRARY_PATH), it must find what it needs there, bake pixels from
// memory through ndfb_bake_map, and refuse every call that needs image files with
// NDFB_ERROR_UNSUPPORTED_FORMAT and a message saying what to call instead; it carries none of
// ndfbake_research.h. Built for every
// platform that runs here (Linux natively and under qemu-user, Windows under wine).
// Usage: addon_library_bake_from_pixels <folder>/<library file> <out_dir>
// Prints one line per check; exit status 0 when all pass.
#ifdef _WIN32
#include <windows.h>
#else
#include <dlfcn.h>
#include <link.h>
#endif

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "ndfbake.h"

namespace {

int g_failures = 0;

void check(bool ok, const std::string& what)
{
    std::printf("%s: %s\n", ok ? "ok" : "FAIL", what.c_str());
    if (!ok) ++g_failures;
}

// The C API, looked up in the library the OS loaded.
struct Api {
#ifdef _WIN32
    HMODULE library = nullptr;
    void* symbol(const char* name) { return reinterpret_cast<void*>(GetProcAddress(library, name)); }
#else
    void* library = nullptr;
    void* symbol(const char* name) { return dlsym(library, name); }
#endif
    template <typename Fn>
    Fn* get(const char* name)
    {
        auto* fn = reinterpret_cast<Fn*>(symbol(name));
        if (!fn) {
            std::printf("FAIL: %s is not exported\n", name);
            std::exit(1);
        }
        return fn;
    }
};
#define NDFB(api, name) (api).get<decltype(name)>(#name)

#ifndef _WIN32
// Every loaded object outside the C and C++ runtimes must come from the library's own folder.
// (On Windows the DLL's import table says the same: check_platform_library.py reads it.)
int check_loaded_object(dl_phdr_info* info, size_t, void* data)
{
    static const std::set<std::string> runtime = {"libc.so.6", "libm.so.6", "libstdc++.so.6", "libgcc_s.so.1",
                                                  "ld-linux-x86-64.so.2", "ld-linux-aarch64.so.1",
                                                  "libpthread.so.0", "libdl.so.2", "librt.so.1",
                                                  "linux-vdso.so.1"};
    const std::string path = info->dlpi_name ? info->dlpi_name : "";
    if (path.empty()) return 0;  // the program itself
    const std::filesystem::path file(path);
    const std::string& folder = *static_cast<const std::string*>(data);
    if (!runtime.count(file.filename().string()))
        check(file.parent_path() == folder, "loaded from the library's folder: " + path);
    return 0;
}
#endif

}  // namespace

int main(int argc, char** argv)
{
    if (argc != 3) {
        std::fprintf(stderr, "usage: %s <folder>/<library file> <out_dir>\n", argv[0]);
        return 2;
    }
    const std::filesystem::path library_file = std::filesystem::canonical(argv[1]);
    const std::string out_dir = argv[2];
    Api api;
#ifdef _WIN32
    api.library = LoadLibraryW(library_file.wstring().c_str());
    if (!api.library) {
        std::printf("FAIL: LoadLibraryW: error %lu\n", GetLastError());
        return 1;
    }
#else
    api.library = dlopen(library_file.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!api.library) {
        std::printf("FAIL: dlopen: %s\n", dlerror());
        return 1;
    }
    std::string folder = library_file.parent_path().string();
    dl_iterate_phdr(&check_loaded_object, &folder);
#endif

    check(NDFB(api, ndfb_abi_version)() == NDFB_ABI_MAJOR && NDFB(api, ndfb_abi_minor)() >= NDFB_ABI_MINOR, "ABI version");
    check(NDFB(api, ndfb_max_lobes)() == 8, "ndfb_max_lobes() is 8");
    check(NDFB(api, ndfb_has_image_files)() == 0, "ndfb_has_image_files() is 0");
    ndfb_context ctx = nullptr;
    check(NDFB(api, ndfb_context_create)(&ctx) == NDFB_OK, "context");
    const auto last_error = NDFB(api, ndfb_last_error);

    // A 64 x 64 map of bumps, [0, 1]-encoded RGB as Blender's image pixels are.
    const uint32_t size = 64;
    std::vector<float> pixels(size * size * 3);
    for (uint32_t y = 0; y < size; ++y)
        for (uint32_t x = 0; x < size; ++x) {
            const float u = 0.5f * std::sin(float(x) * 0.4f), v = 0.5f * std::cos(float(y) * 0.3f);
            const float z = std::sqrt(1.0f - u * u - v * v);
            float* p = &pixels[(y * size + x) * 3];
            p[0] = 0.5f * u + 0.5f, p[1] = 0.5f * v + 0.5f, p[2] = 0.5f * z + 0.5f;
        }
    ndfb_decode_options decode;
    NDFB(api, ndfb_decode_options_init)(&decode);
    ndfb_normal_map map = nullptr;
    check(NDFB(api, ndfb_normal_map_from_pixels)(ctx, pixels.data(), pixels.size(), size, size, 3, 0, &decode,
                                                   &map) == NDFB_OK,
          "ndfb_normal_map_from_pixels");

    ndfb_fit_options fit;
    NDFB(api, ndfb_fit_options_init)(&fit);
    fit.max_lobes = 2;
    std::set<std::string> stages;
    const ndfb_progress_fn note_stage = [](void* user, const char* stage, float) {
        static_cast<std::set<std::string>*>(user)->insert(stage);
        return 0;
    };
    ndfb_write_options write;
    NDFB(api, ndfb_write_options_init)(&write);
    write.source_name = "bumps (Blender image)";
    write.atlas = 1;
    ndfb_bake_result result = nullptr;
    const ndfb_status baked = NDFB(api, ndfb_bake_map)(ctx, map, out_dir.c_str(), &fit, &write, note_stage, &stages,
                                                       &result);
    check(baked == NDFB_OK, std::string("ndfb_bake_map: ") + last_error(ctx));
    check(stages == std::set<std::string>{"fit", "measure", "write"}, "progress stages fit, measure, write");
    for (const char* file : {"level00_lobe0.exr", "level00_lobe1.exr", "level06_lobe1.exr", "atlas_lobe0.exr",
                             "report.json", "ndfbake.glsl"})
        check(std::filesystem::exists(std::filesystem::path(out_dir) / file), std::string("wrote ") + file);
    // The result names what is in the folder: 7 levels x 2 slots, 2 atlases, the shader, the report.
    check(NDFB(api, ndfb_bake_result_level_count)(result) == 7 && NDFB(api, ndfb_bake_result_lobe_slots)(result) == 2,
          "the result's 7 levels of 2 slots");
    const uint32_t file_count = NDFB(api, ndfb_bake_result_file_count)(result);
    check(file_count == 7 * 2 + 2 + 2, "the result's 18 files");
    for (uint32_t i = 0; i < file_count; ++i) {
        ndfb_bake_file file{};
        check(NDFB(api, ndfb_bake_result_file)(result, i, &file) == NDFB_OK &&
                  std::filesystem::exists(std::filesystem::path(out_dir) / file.name) &&
                  NDFB(api, ndfb_is_bake_file)(file.name) == 1,
              std::string("the result's file ") + (file.name ? file.name : "?") + " is there");
    }
    uint32_t atlas_width = 0, atlas_height = 0;
    check(NDFB(api, ndfb_bake_result_atlas_size)(result, &atlas_width, &atlas_height) == NDFB_OK &&
              atlas_width == (64 + 2) + (32 + 2) && atlas_height == (32 + 2) + (16 + 2) + (8 + 2) + (4 + 2) + (2 + 2) + (1 + 2),
          "the atlas is 100 x 75 (level 0 framed, levels 1.. framed in a column beside it)");
    NDFB(api, ndfb_bake_result_destroy)(result);

    // What needs image files: refused with the documented status and a message naming the way out.
    const auto refused = [&](ndfb_status status, const std::string& call) {
        const std::string message = last_error(ctx);
        check(status == NDFB_ERROR_UNSUPPORTED_FORMAT &&
                  message.find("reads and writes no image files") != std::string::npos &&
                  message.find("ndfb_normal_map_from_pixels") != std::string::npos &&
                  message.find("ndfb_bake_map") != std::string::npos,
              call + " refused: " + message);
    };
    const std::string refused_dir = out_dir + "-refused";
    ndfb_normal_map loaded = nullptr;
    refused(NDFB(api, ndfb_normal_map_load)(ctx, "normal.png", &decode, &loaded), "ndfb_normal_map_load");
    check(loaded == nullptr, "ndfb_normal_map_load leaves its output NULL");
    refused(NDFB(api, ndfb_bake)(ctx, "normal.png", refused_dir.c_str(), &decode, &fit, &write, nullptr, nullptr, nullptr),
            "ndfb_bake");
    char text[64];
    refused(NDFB(api, ndfb_describe_image)(ctx, "level00_lobe0.exr", text, sizeof text, nullptr),
            "ndfb_describe_image");
    refused(NDFB(api, ndfb_normal_map_save)(ctx, map, (refused_dir + "/map.png").c_str()), "ndfb_normal_map_save");
    // ndfbake_research.h's code is not in the add-on's library at all.
    for (const char* name : {"ndfb_bench", "ndfb_bench_options_init", "ndfb_texel_error",
                             "ndfb_effective_brdf_reference"})
        check(api.symbol(name) == nullptr, std::string("the research entry point ") + name + " is not exported");
    write.color_path = "color.png";
    refused(NDFB(api, ndfb_bake_map)(ctx, map, refused_dir.c_str(), &fit, &write, nullptr, nullptr, nullptr),
            "ndfb_bake_map with color_path");
    check(!std::filesystem::exists(refused_dir), "refused calls leave no folder behind");

    NDFB(api, ndfb_normal_map_destroy)(map);
    NDFB(api, ndfb_context_destroy)(ctx);
    std::printf("%s addon_library_bake_from_pixels\n", g_failures == 0 ? "PASS" : "FAIL");
    return g_failures == 0 ? 0 : 1;
}
