#include "synth/patterns.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "error.h"
#include "synth/height_field.h"
#include "synth/noise.h"
#include "synth/rng.h"

namespace ndfbake {

namespace {

constexpr double kPi = 3.14159265358979323846;

constexpr double radians(double degrees) { return degrees * kPi / 180.0; }

constexpr std::array<Pattern, 6> kPatterns = {Pattern::vgroove, Pattern::bumps,     Pattern::fbm,
                                              Pattern::brushed, Pattern::scratches, Pattern::weave};

// ---------------------------------------------------------------------------------------------
// Sizing shared by all patterns

// Features have their nominal size in pixels on maps up to this side and grow in proportion on
// larger ones, so a 4K map looks like an upscaled 256 one instead of a 16x16 tiling of it. They
// never shrink on smaller maps, which would blur them into flat normals.
constexpr double kReferenceSide = 256.0;

double feature_scale(int width, int height)
{
    return std::max(1.0, double(std::max(width, height)) / kReferenceSide);
}

// How many repeats of a feature of `period_px` pixels fit across `extent` pixels. The period is
// stretched to fit a whole number of them, which is what makes the map tile at any size.
int periods_across(int extent, double period_px)
{
    return std::max(1, int(std::lround(double(extent) / period_px)));
}

// Where the centre of pixel `i` falls when `extent` pixels hold `periods` repeats: which repeat,
// and the position within it in [-1, 1).
struct PeriodPosition {
    long long index;
    double local;
};

PeriodPosition period_position(int i, int extent, int periods)
{
    const double f = (i + 0.5) * periods / extent;
    const double index = std::floor(f);
    return {(long long)index, 2.0 * (f - index) - 1.0};
}

// ---------------------------------------------------------------------------------------------
// vgroove

constexpr double kVGrooveTiltDeg = 30.0;

NormalMap synthesize_vgroove(int width, int height)
{
    // One facet per column, so every 2x2 block already holds both normals (Han et al. 2007, Fig. 1).
    // An odd width gets one facet fewer than columns (one facet two columns wide) so that the
    // count stays even and the groove profile closes across the seam.
    const long long facets = std::max(2, width - width % 2);
    const float s = float(std::sin(radians(kVGrooveTiltDeg)));
    const float c = float(std::cos(radians(kVGrooveTiltDeg)));
    const Vec3 falling{s, 0.0f, c};  // wall going down towards +X: its normal leans to +X
    const Vec3 rising{-s, 0.0f, c};

    NormalMap map{width, height, std::vector<Vec3>(size_t(width) * size_t(height))};
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) map.at(x, y) = (x * facets / width) % 2 == 0 ? falling : rising;
    }
    return map;
}

// ---------------------------------------------------------------------------------------------
// bumps

constexpr double kBumpPeriodPx = 8.0;
// Bump radius relative to the period: leaves about half of the area flat, so the NDF keeps a
// sharp +Z peak beside the spread of bump normals.
constexpr double kBumpRadiusFraction = 0.4;
constexpr double kBumpMaxTiltDeg = 45.0;

HeightField bumps_heights(int width, int height)
{
    const double scale = feature_scale(width, height);
    const int nx = periods_across(width, kBumpPeriodPx * scale);
    const int ny = periods_across(height, kBumpPeriodPx * scale);
    const double cell_w = double(width) / nx, cell_h = double(height) / ny;
    const double radius = kBumpRadiusFraction * std::min(cell_w, cell_h);
    // h = A cos²(πd / 2r) is steepest at d = r/2, with slope Aπ / 2r.
    const double amplitude = 2.0 * radius * std::tan(radians(kBumpMaxTiltDeg)) / kPi;

    HeightField field(width, height);
    for (int y = 0; y < height; ++y) {
        const double dy = 0.5 * cell_h * period_position(y, height, ny).local;
        for (int x = 0; x < width; ++x) {
            const double dx = 0.5 * cell_w * period_position(x, width, nx).local;
            const double d = std::hypot(dx, dy);
            if (d < radius) field.at(x, y) = float(amplitude * 0.5 * (1.0 + std::cos(kPi * d / radius)));
        }
    }
    return field;
}

// ---------------------------------------------------------------------------------------------
// Random height fields (fbm, brushed)

void add_value_noise(HeightField& field, double cell_x_px, double cell_y_px, double amplitude, uint64_t key)
{
    add_periodic_value_noise(field, periods_across(field.width(), cell_x_px),
                             periods_across(field.height(), cell_y_px), amplitude, key);
}

// The raw steepness of a random field depends on the seed and on how many octaves fit the map; the
// width of the NDF should not, so the slopes are scaled to a fixed RMS.
NormalMap normals_with_rms_slope(const HeightField& field, double rms_slope_deg)
{
    const double rms = field.rms_slope();
    const double scale = rms > 0.0 ? std::tan(radians(rms_slope_deg)) / rms : 1.0;
    return normals_from_heights(field, float(scale));
}

constexpr int kFbmOctaves = 5;
constexpr double kFbmCoarsestCellPx = 32.0;
// Amplitude ∝ cell size^H. Below 1 the fine octaves carry more of the slope than in a smooth
// surface, so coarse MIP texels average many distinct tilts.
constexpr double kFbmHurst = 0.7;
constexpr double kFbmRmsSlopeDeg = 25.0;

NormalMap synthesize_fbm(int width, int height, uint32_t seed)
{
    SplitMix64 rng(seed);
    HeightField field(width, height);
    double cell = kFbmCoarsestCellPx * feature_scale(width, height);
    for (int octave = 0; octave < kFbmOctaves; ++octave, cell *= 0.5)
        add_value_noise(field, cell, cell, std::pow(cell, kFbmHurst), rng.next());
    return normals_with_rms_slope(field, kFbmRmsSlopeDeg);
}

constexpr int kBrushedOctaves = 4;
constexpr double kBrushedFinestCellPx = 2.0;  // across the streaks, along Y
// Streak length over width: x-slopes come out about this many times smaller than y-slopes.
constexpr double kBrushedStreakAspect = 32.0;
constexpr double kBrushedRmsSlopeDeg = 20.0;

NormalMap synthesize_brushed(int width, int height, uint32_t seed)
{
    SplitMix64 rng(seed);
    HeightField field(width, height);
    double cell = kBrushedFinestCellPx * feature_scale(width, height);
    // Amplitude ∝ cell size gives every octave the same slope: fine and coarse streaks both show.
    for (int octave = 0; octave < kBrushedOctaves; ++octave, cell *= 2.0)
        add_value_noise(field, kBrushedStreakAspect * cell, cell, cell, rng.next());
    return normals_with_rms_slope(field, kBrushedRmsSlopeDeg);
}

// ---------------------------------------------------------------------------------------------
// scratches

constexpr double kScratchHalfWidthPx = 2.0;
constexpr double kScratchWallTiltDeg = 55.0;
constexpr int kScratchDirections = 3;  // dominant directions, as left by a few wiping motions
constexpr double kScratchDirectionJitterDeg = 5.0;
constexpr double kScratchMinLengthPx = 32.0;
constexpr double kScratchMaxLengthPx = 128.0;
// Map area per scratch (at reference scale): puts roughly a tenth of the texels on scratch walls.
constexpr double kScratchAreaPx = 5000.0;

struct Point2 {
    double x, y;
};

double distance_to_segment(Point2 p, Point2 a, Point2 b)
{
    const double ex = b.x - a.x, ey = b.y - a.y;
    const double len2 = ex * ex + ey * ey;
    const double t = len2 > 0.0 ? std::clamp(((p.x - a.x) * ex + (p.y - a.y) * ey) / len2, 0.0, 1.0) : 0.0;
    return std::hypot(p.x - (a.x + t * ex), p.y - (a.y + t * ey));
}

// Calls visit(x, y) for every pixel, in unwrapped coordinates, whose centre may lie within `reach`
// of segment ab (and some more). It walks the segment's major axis and covers a band of the minor
// axis, so the cost follows the scratch's area rather than its bounding box. Any point within
// reach of the segment is within 2·reach of it along the minor axis, as the slope is at most 1.
template <class Visit>
void for_each_pixel_near_segment(Point2 a, Point2 b, double reach, Visit&& visit)
{
    const bool along_x = std::abs(b.x - a.x) >= std::abs(b.y - a.y);
    double m0 = along_x ? a.x : a.y, n0 = along_x ? a.y : a.x;
    double m1 = along_x ? b.x : b.y, n1 = along_x ? b.y : b.x;
    if (m0 > m1) {
        std::swap(m0, m1);
        std::swap(n0, n1);
    }
    const double slope = m1 > m0 ? (n1 - n0) / (m1 - m0) : 0.0;
    const double band = 2.0 * reach;
    for (long long i = std::llround(std::floor(m0 - reach)); i <= std::llround(std::ceil(m1 + reach)); ++i) {
        const double line = n0 + (std::clamp(i + 0.5, m0, m1) - m0) * slope;
        for (long long j = std::llround(std::floor(line - band)); j <= std::llround(std::ceil(line + band)); ++j) {
            if (along_x)
                visit(i, j);
            else
                visit(j, i);
        }
    }
}

HeightField scratches_heights(int width, int height, uint32_t seed)
{
    SplitMix64 rng(seed);
    const double scale = feature_scale(width, height);
    const double half_width = kScratchHalfWidthPx * scale;
    const double depth = half_width * std::tan(radians(kScratchWallTiltDeg));
    // Longer than the map, a scratch would only run over itself again.
    const double max_length = std::min(kScratchMaxLengthPx * scale, double(std::max(width, height)));
    const double min_length = std::min(kScratchMinLengthPx * scale, max_length);
    const int count =
        std::max(1, int(std::lround(double(width) * double(height) / (kScratchAreaPx * scale * scale))));

    std::array<double, kScratchDirections> directions;
    for (double& d : directions) d = rng.uniform(0.0, kPi);

    HeightField field(width, height);
    for (int k = 0; k < count; ++k) {
        const double angle = directions[rng.next() % kScratchDirections] +
                             radians(rng.uniform(-kScratchDirectionJitterDeg, kScratchDirectionJitterDeg));
        const double half_length = 0.5 * rng.uniform(min_length, max_length);
        const Point2 centre{rng.uniform(0.0, width), rng.uniform(0.0, height)};
        const Point2 a{centre.x - half_length * std::cos(angle), centre.y - half_length * std::sin(angle)};
        const Point2 b{centre.x + half_length * std::cos(angle), centre.y + half_length * std::sin(angle)};
        for_each_pixel_near_segment(a, b, half_width, [&](long long x, long long y) {
            const double d = distance_to_segment({x + 0.5, y + 0.5}, a, b);
            if (d >= half_width) return;
            // V-shaped cross-section; where scratches cross, the deeper one cuts through.
            float& h = field.at_wrapped(x, y);
            h = std::min(h, float(-depth * (1.0 - d / half_width)));
        });
    }
    return field;
}

// ---------------------------------------------------------------------------------------------
// weave

constexpr double kWeaveThreadPx = 8.0;  // thread width (pitch)
constexpr double kWeaveThreadTiltDeg = 50.0;  // steepest slope across a thread
// Over/under rise along a thread relative to its arch height. Kept small so the normals tilt mostly
// across the threads: four lobes rather than a ring.
constexpr double kWeaveUndulation = 0.3;

// Even, because the over/under pattern repeats every two threads.
int thread_count(int extent, double thread_px)
{
    return 2 * std::max(1, int(std::lround(double(extent) / (2.0 * thread_px))));
}

// Height of a thread: a cosine arch across it (across in [-1, 1)), riding a sine wave along it
// (along in thread widths) that takes it over one crossing thread and under the next. `over_first`
// flips the wave, alternating between neighbouring threads.
double thread_height(double across, double along, bool over_first, double arch, double undulation)
{
    const double wave = undulation * std::sin(kPi * along);
    return arch * std::cos(0.5 * kPi * across) + (over_first ? wave : -wave);
}

HeightField weave_heights(int width, int height)
{
    const double scale = feature_scale(width, height);
    const int nx = thread_count(width, kWeaveThreadPx * scale);   // threads running along Y
    const int ny = thread_count(height, kWeaveThreadPx * scale);  // threads running along X
    const double cell_w = double(width) / nx, cell_h = double(height) / ny;
    // The arch's steepest slope is arch·π / thread width.
    const double tilt = std::tan(radians(kWeaveThreadTiltDeg));
    const double arch_x = tilt * cell_h / kPi, arch_y = tilt * cell_w / kPi;

    HeightField field(width, height);
    for (int y = 0; y < height; ++y) {
        const PeriodPosition row = period_position(y, height, ny);
        const double along_y = (y + 0.5) * ny / height;
        for (int x = 0; x < width; ++x) {
            const PeriodPosition column = period_position(x, width, nx);
            const double along_x = (x + 0.5) * nx / width;
            // At crossing (column, row) the X thread is on top when column + row is even.
            const double h_x = thread_height(row.local, along_x, row.index % 2 == 0, arch_x, kWeaveUndulation * arch_x);
            const double h_y =
                thread_height(column.local, along_y, column.index % 2 != 0, arch_y, kWeaveUndulation * arch_y);
            field.at(x, y) = float(std::max(h_x, h_y));
        }
    }
    return field;
}

}  // namespace

std::span<const Pattern> all_patterns() { return kPatterns; }

const char* pattern_name(Pattern pattern)
{
    switch (pattern) {
    case Pattern::vgroove: return "vgroove";
    case Pattern::bumps: return "bumps";
    case Pattern::fbm: return "fbm";
    case Pattern::brushed: return "brushed";
    case Pattern::scratches: return "scratches";
    case Pattern::weave: return "weave";
    }
    return "unknown";
}

std::optional<Pattern> pattern_from_name(std::string_view name)
{
    for (Pattern p : kPatterns) {
        if (name == pattern_name(p)) return p;
    }
    return std::nullopt;
}

NormalMap synthesize(Pattern pattern, int width, int height, uint32_t seed)
{
    if (width < 1 || height < 1 || width > kMaxSynthSide || height > kMaxSynthSide) {
        throw Error{Status::invalid_argument, "synthesize: size " + std::to_string(width) + "x" +
                                                  std::to_string(height) + " is outside 1.." +
                                                  std::to_string(kMaxSynthSide) + " per side"};
    }
    switch (pattern) {
    case Pattern::vgroove: return synthesize_vgroove(width, height);
    case Pattern::bumps: return normals_from_heights(bumps_heights(width, height));
    case Pattern::fbm: return synthesize_fbm(width, height, seed);
    case Pattern::brushed: return synthesize_brushed(width, height, seed);
    case Pattern::scratches: return normals_from_heights(scratches_heights(width, height, seed));
    case Pattern::weave: return normals_from_heights(weave_heights(width, height));
    }
    throw Error{Status::invalid_argument, "synthesize: unknown pattern"};
}

}  // namespace ndfbake
