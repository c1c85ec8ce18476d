// The text of report.json (see bake/report.h). Calls bake/lobe_files (attributes shared with
// the files), bake/memory_budget (the estimate and the limit) and io/json_writer.
#include "bake/report.h"

#include <algorithm>

#include "bake/lobe_atlas.h"
#include "bake/lobe_files.h"
#include "bake/memory_budget.h"
#include "io/json_writer.h"
#include "platform/files.h"
#include "pyramid/footprint.h"

namespace ndfbake {

namespace {

void write_summary(JsonWriter& json, const char* key, const ErrorSummary& summary)
{
    json.begin_object(key).value("mean", summary.mean).value("p95", summary.p95).end_object();
}

// The layout of the file a map was decoded from (none for pixels from memory or synthesized).
SourceLayout source_layout(const DecodeResult& decoded)
{
    if (decoded.format == "memory" || decoded.format == "synthetic" || decoded.bits_per_channel <= 0) return {};
    return {decoded.channels, std::max(1, decoded.bits_per_channel / 8), decoded.float_data};
}

}  // namespace

std::string report_json(const LobePyramid& pyramid, const DecodeResult& decoded, const PyramidSettings& settings,
                        const WriteSettings& write, const std::vector<LevelStats>& stats,
                        const BakeTimings& timings, const std::vector<std::string>& files)
{
    const MemoryEstimate memory = estimate_bake_memory(pyramid.source.width, pyramid.source.height,
                                                       source_layout(decoded), settings, write);
    JsonWriter json;
    json.begin_object();
    json.value("format_version", kFileFormatVersion).value("ndfbake_version", NDFBAKE_VERSION_STRING);
    json.begin_object("input")
        .value("source", write.source_name)
        .value("width", pyramid.source.width)
        .value("height", pyramid.source.height)
        .value("format", decoded.format)
        .value("bits_per_channel", decoded.bits_per_channel)
        .value("channels", decoded.channels)
        .value("srgb_tagged", decoded.srgb_tagged)
        .value("signed_encoding", decoded.signed_encoding)
        .value("source_hash", hex64(decoded.source_hash));
    json.begin_array("assumptions");
    for (const std::string& a : decoded.assumptions) json.value(nullptr, a);
    json.end_array().end_object();

    json.begin_object("settings")
        .value("method", settings.method == FitMethod::hierarchical ? "hierarchical" : "per-level")
        .value("max_lobes", settings.fit.max_lobes)
        .value("max_iterations", settings.fit.em.max_iterations)
        .value("tolerance", settings.fit.tolerance)
        .value("brdf", settings.brdf.to_string())
        .value("refined_for_brdf", settings.refine)
        .value("wrap", settings.wrap == WrapMode::wrap ? "repeat" : "clamp")
        .value("aligned", settings.align)
        .value("alignment_strength", settings.alignment_strength)
        .value("precision", write.precision == PixelPrecision::half ? "half" : "float")
        .value("per_lobe_color", !write.color_path.empty())
        .end_object();

    json.begin_object("repairs")
        .value("non_finite", decoded.repairs.non_finite)
        .value("zero_length", decoded.repairs.zero_length)
        .value("renormalized", decoded.repairs.renormalized)
        .value("below_horizon", decoded.repairs.below_horizon)
        .value("rule", "non-finite or shorter than 0.01: +Z; z < 0: z = -z; then normalized")
        .end_object();

    json.begin_object("error_measure")
        .value("what", "relative L2 distance to the exact effective BRDF (Han 2007 eq. 4) over a fixed "
                       "Fibonacci set of hemisphere directions")
        .value("directions", error_direction_count(settings.brdf))
        .value("texels_per_level", kReportTexelsPerLevel)
        .value("fine_normals_per_texel", kReportSampleCap)
        .value("without_alignment", "error_without_alignment is an independent refit of the same texels, "
                                    "alignment_cost the error minus its mean; measured above level 0 when lobes "
                                    "are pulled into alignment (aligned, alignment_strength > 0), null otherwise")
        .end_object();

    // Slots with no lobe at any level (possible with a tolerance): their textures are all zero.
    json.begin_array("slots_used");
    for (bool used : pyramid.slots_used()) json.value(nullptr, used);
    json.end_array();

    json.begin_array("levels");
    for (const LevelStats& s : stats) {
        json.begin_object()
            .value("level", s.level)
            .value("width", s.size.width)
            .value("height", s.size.height);
        json.begin_array("lobe_histogram");
        for (int k = 0; k <= pyramid.slots; ++k) json.value(nullptr, s.lobe_histogram[size_t(k)]);
        json.end_array();
        json.value("measured_texels", s.measured_texels);
        write_summary(json, "error", s.fit);
        // Not measured (see "error_measure"): null, never a made-up 0 beside the real error.
        if (s.independent_fit) {
            write_summary(json, "error_without_alignment", *s.independent_fit);
            json.value("alignment_cost", double(s.fit.mean) - double(s.independent_fit->mean));
        } else {
            json.null("error_without_alignment").null("alignment_cost");
        }
        write_summary(json, "error_naive", s.naive);
        write_summary(json, "error_single_vmf", s.single_vmf);
        write_summary(json, "error_toksvig", s.toksvig);
        json.end_object();
    }
    json.end_array();

    json.begin_object("timings_seconds")
        .value("decode", timings.decode)
        .value("fit", timings.fit)
        .value("measure", timings.measure)
        .value("write", timings.write)
        .end_object();
    // Measured: the process's peak resident memory so far (peak_resident_bytes), which includes the host
    // application's own; estimated: this bake's peak as checked against the limit before it ran.
    json.value("peak_memory_bytes", process_peak_memory())
        .value("estimated_memory_bytes", memory.peak())
        .value("memory_limit_bytes", effective_memory_limit(settings.max_memory_bytes));
    if (write.atlas) {
        const AtlasLayout layout = pyramid_atlas_layout(pyramid);
        json.begin_object("atlas").value("width", layout.width).value("height", layout.height).begin_array("levels");
        for (const AtlasLevel& l : layout.levels)
            json.begin_object().value("x", l.x).value("y", l.y).value("width", l.width).value("height", l.height).end_object();
        json.end_array().end_object();
    }
    if (write.mipmap)
        json.begin_object("mipmap")
            .value("levels", level_count(pyramid.source.width, pyramid.source.height))
            .value("fitted_levels", pyramid.level_count())
            .value("rounding", "up: level L is ceil(w / 2^L) x ceil(h / 2^L), as the fitted levels")
            .value("tile", kMipTileSize)
            .end_object();
    json.begin_array("files");
    for (const std::string& f : files) json.value(nullptr, path_to_utf8(path_from_utf8(f).filename()));
    json.value(nullptr, "report.json");
    json.end_array();
    json.end_object();
    return json.str();
}

}  // namespace ndfbake
