// The lobe, colour, atlas and MIP-mapped files of a bake (see bake/lobe_files.h): texel
// encodings, attributes, and one file written at the path given. Calls io/ (EXR writing), ndf/,
// pyramid/ and bake/lobe_atlas; never bake.cpp or report.cpp.
#include "bake/lobe_files.h"

#include <algorithm>
#include <cstdio>

#include "ndf/spherical_em.h"

namespace ndfbake {

namespace {

// Lobe texture texel: R = α, GBA = α·r with |r| the resultant whose Banerjee κ is the lobe's.
void encode_lobe(const VmfLobe& lobe, float* rgba)
{
    if (!(lobe.alpha > 0.0f)) {
        rgba[0] = rgba[1] = rgba[2] = rgba[3] = 0.0f;
        return;
    }
    const float r = float(lobe_resultant(lobe.kappa));  // 1 at the κ cap: a single direction
    rgba[0] = lobe.alpha;
    rgba[1] = lobe.alpha * r * lobe.mu.x;
    rgba[2] = lobe.alpha * r * lobe.mu.y;
    rgba[3] = lobe.alpha * r * lobe.mu.z;
}

// Level `level` + 1 of a slot's texture from level `level` (w × h, RGBA): each texel the mean of
// the texels below it (two by two, fewer at an odd edge) weighted by their footprints, which
// averages their distributions as the linear encoding does under hardware filtering. For the
// levels of a MIP file beyond the fitted ones (--levels N): an estimate, not a fit.
std::vector<float> averaged_coarser_level(const std::vector<float>& rgba, const NormalMap& source, int level,
                                          WrapMode wrap)
{
    const LevelSize fine = level_size(source.width, source.height, level);
    const LevelSize coarse = level_size(source.width, source.height, level + 1);
    std::vector<float> out(size_t(coarse.width) * size_t(coarse.height) * 4, 0.0f);
    for (int y = 0; y < coarse.height; ++y)
        for (int x = 0; x < coarse.width; ++x) {
            double sum[4] = {0, 0, 0, 0}, weight = 0;
            for (int cy = 2 * y; cy < std::min(2 * y + 2, fine.height); ++cy)
                for (int cx = 2 * x; cx < std::min(2 * x + 2, fine.width); ++cx) {
                    const double w = footprint_weight(source.width, source.height, level, cx, cy, wrap);
                    const float* texel = &rgba[(size_t(cy) * size_t(fine.width) + size_t(cx)) * 4];
                    for (int c = 0; c < 4; ++c) sum[c] += w * double(texel[c]);
                    weight += w;
                }
            for (int c = 0; c < 4; ++c)
                out[(size_t(y) * size_t(coarse.width) + size_t(x)) * 4 + size_t(c)] =
                    weight > 0 ? float(sum[c] / weight) : 0.0f;
        }
    return out;
}

}  // namespace

// Per-lobe colour (eq. 22): y_j = Σ ⟨z_ij⟩ w_i y_i / Σ ⟨z_ij⟩ w_i over the texel's fine texels;
// stored as RGB = α_j y_j, A = α_j so that it filters linearly like the lobe textures.
std::vector<std::vector<float>> color_textures(const LobePyramid& pyramid, const ColorImage& color, int level)
{
    const LevelSize size = pyramid.size(level);
    const int slots = pyramid.slots;
    std::vector<std::vector<float>> textures(size_t(slots),
                                             std::vector<float>(size_t(size.width) * size_t(size.height) * 4, 0.0f));
    // Colours travel with the normals: gather the footprint of a colour "map" alongside.
    NormalMap rgb;
    rgb.width = color.width;
    rgb.height = color.height;
    const size_t n = size_t(color.width) * size_t(color.height);
    rgb.normals.resize(n);
    for (size_t p = 0; p < n; ++p) rgb.normals[p] = {color.rgb[p * 3], color.rgb[p * 3 + 1], color.rgb[p * 3 + 2]};

    std::vector<WeightedNormal> samples, colors;
    std::vector<float> z;
    std::vector<VmfLobe> lobes(static_cast<size_t>(slots));
    for (int y = 0; y < size.height; ++y)
        for (int x = 0; x < size.width; ++x) {
            gather_footprint(pyramid.source, level, x, y, pyramid.settings.wrap, samples);
            gather_footprint(rgb, level, x, y, pyramid.settings.wrap, colors);
            pyramid.texel(level, x, y, lobes);
            vmf_responsibilities(samples, lobes, z);
            for (int j = 0; j < slots; ++j) {
                if (!(lobes[size_t(j)].alpha > 0.0f)) continue;
                Vec3d sum;
                double weight = 0.0;
                for (size_t i = 0; i < samples.size(); ++i) {
                    const double w = double(samples[i].weight) * z[i * size_t(slots) + size_t(j)];
                    sum.add(colors[i].n, w);
                    weight += w;
                }
                float* out = &textures[size_t(j)][(size_t(y) * size_t(size.width) + size_t(x)) * 4];
                const float alpha = lobes[size_t(j)].alpha;
                const Vec3 mean = weight > 0.0 ? sum.to_float() / float(weight) : Vec3{};
                out[0] = alpha * mean.x;
                out[1] = alpha * mean.y;
                out[2] = alpha * mean.z;
                out[3] = alpha;
            }
        }
    return textures;
}

AtlasLayout pyramid_atlas_layout(const LobePyramid& pyramid)
{
    std::vector<LevelSize> sizes;
    for (int level = 0; level < pyramid.level_count(); ++level) sizes.push_back(pyramid.size(level));
    return atlas_layout(sizes);
}

std::string hex64(uint64_t value)
{
    char buffer[17];
    std::snprintf(buffer, sizeof buffer, "%016llx", static_cast<unsigned long long>(value));
    return buffer;
}

std::vector<ExrAttribute> file_attributes(const LobePyramid& pyramid, const DecodeResult& decoded,
                                          const PyramidSettings& settings, const WriteSettings& write,
                                          int level, int lobe, float level_error, const char* content)
{
    return {
        {"ndfbake:format_version", kFileFormatVersion},
        {"ndfbake:content", std::string(content)},
        {"ndfbake:level", level},
        {"ndfbake:lobe", lobe},
        {"ndfbake:lobe_slots", pyramid.slots},
        {"ndfbake:level_count", pyramid.level_count()},
        {"ndfbake:source", write.source_name},
        {"ndfbake:source_hash", hex64(decoded.source_hash)},
        {"ndfbake:source_width", pyramid.source.width},
        {"ndfbake:source_height", pyramid.source.height},
        {"ndfbake:convention", std::string("opengl tangent space, +Z out, +Y up V")},
        {"ndfbake:wrap", std::string(settings.wrap == WrapMode::wrap ? "repeat" : "clamp")},
        {"ndfbake:brdf", settings.brdf.to_string()},
        {"ndfbake:tolerance", settings.fit.tolerance},
        {"ndfbake:aligned", settings.align ? 1 : 0},
        {"ndfbake:refined_for_brdf", settings.refine ? 1 : 0},
        {"ndfbake:kappa_max", kKappaMax},
        {"ndfbake:fit_error", level_error},
        {"ndfbake:version", std::string(NDFBAKE_VERSION_STRING)},
    };
}

// Every level of lobe slot `lobe` in one image (write option `atlas`, see ndfbake.h).
void write_atlas(const LobePyramid& pyramid, const DecodeResult& decoded, const PyramidSettings& settings,
                 const WriteSettings& write, const AtlasLayout& layout, int lobe, const std::string& path)
{
    std::string places;
    for (const AtlasLevel& l : layout.levels) {
        if (!places.empty()) places += ';';
        for (int v : {l.x, l.y, l.width, l.height}) places.append(std::to_string(v)).push_back(',');
        places.pop_back();
    }
    std::vector<float> atlas(size_t(layout.width) * size_t(layout.height) * 4, 0.0f);
    for (int level = 0; level < pyramid.level_count(); ++level)
        place_atlas_level(layout, level, lobe_texture(pyramid, level, lobe).data(), pyramid.settings.wrap, atlas);
    std::vector<ExrAttribute> attributes = file_attributes(pyramid, decoded, settings, write, -1, lobe, -1.0f,
                                                           "mip atlas of a vmf lobe slot: R = alpha, GBA = alpha * r");
    attributes.push_back({"ndfbake:atlas_levels", places});
    write_rgba_exr(path, layout.width, layout.height, atlas.data(), write.precision, attributes);
}

// Lobe slot `lobe` as one MIP-mapped file (write option `mipmap`, see ndfbake.h): its levels are
// the fitted levels, then (if fewer were fitted than the chain has) averaged ones down to 1×1.
void write_mip_file(const LobePyramid& pyramid, const DecodeResult& decoded, const PyramidSettings& settings,
                    const WriteSettings& write, const std::vector<LevelStats>& stats, int lobe,
                    const std::string& path)
{
    const int chain = level_count(pyramid.source.width, pyramid.source.height);
    std::vector<std::vector<float>> textures;
    for (int level = 0; level < chain; ++level)
        textures.push_back(level < pyramid.level_count()
                               ? lobe_texture(pyramid, level, lobe)
                               : averaged_coarser_level(textures.back(), pyramid.source, level - 1, settings.wrap));
    std::vector<RgbaLevel> levels;
    std::string errors;
    for (int level = 0; level < chain; ++level) {
        const LevelSize size = level_size(pyramid.source.width, pyramid.source.height, level);
        levels.push_back({size.width, size.height, textures[size_t(level)].data()});
        if (level < pyramid.level_count())
            errors += (errors.empty() ? "" : ";") + std::to_string(stats[size_t(level)].fit.mean);
    }
    std::vector<ExrAttribute> attributes = file_attributes(
        pyramid, decoded, settings, write, -1, lobe, -1.0f,
        "mip-mapped vmf lobe slot: R = alpha, GBA = alpha * r; MIP level L is fitted level L (the first "
        "ndfbake:fitted_levels; the rest averaged)");
    attributes.push_back({"ndfbake:mip_levels", chain});
    attributes.push_back({"ndfbake:fitted_levels", pyramid.level_count()});
    attributes.push_back({"ndfbake:mip_rounding", std::string("up: level L is ceil(w / 2^L) x ceil(h / 2^L)")});
    attributes.push_back({"ndfbake:level_errors", errors});
    write_mip_rgba_exr(path, levels, write.precision, attributes);
}

std::vector<float> lobe_texture(const LobePyramid& pyramid, int level, int slot)
{
    const LevelSize size = pyramid.size(level);
    std::vector<float> rgba(size_t(size.width) * size_t(size.height) * 4);
    std::vector<VmfLobe> lobes(static_cast<size_t>(pyramid.slots));
    for (int y = 0; y < size.height; ++y)
        for (int x = 0; x < size.width; ++x) {
            pyramid.texel(level, x, y, lobes);
            encode_lobe(lobes[size_t(slot)], &rgba[(size_t(y) * size_t(size.width) + size_t(x)) * 4]);
        }
    return rgba;
}

std::string lobe_file_name(int level, int lobe)
{
    char buffer[48];
    std::snprintf(buffer, sizeof buffer, "level%02d_lobe%d.exr", level, lobe);
    return buffer;
}

std::string atlas_file_name(int lobe)
{
    char buffer[48];
    std::snprintf(buffer, sizeof buffer, "atlas_lobe%d.exr", lobe);
    return buffer;
}

std::string mip_file_name(int lobe)
{
    char buffer[48];
    std::snprintf(buffer, sizeof buffer, "mip_lobe%d.exr", lobe);
    return buffer;
}

std::string color_file_name(int level, int lobe)
{
    char buffer[48];
    std::snprintf(buffer, sizeof buffer, "level%02d_color%d.exr", level, lobe);
    return buffer;
}

}  // namespace ndfbake
