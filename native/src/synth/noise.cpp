#include "synth/noise.h"

#include <cmath>
#include <vector>

#include "synth/rng.h"

namespace ndfbake {

namespace {

double quintic_fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

double lerp(double a, double b, double t) { return a + (b - a) * t; }

// Where a pixel centre falls on a lattice of `cells` cells stretched over `extent` pixels: the
// lattice points on either side (already wrapped) and the faded weight of the second.
struct LatticeSpan {
    int lo, hi;
    double weight;
};

LatticeSpan lattice_span(int pixel, int extent, int cells)
{
    const double f = (pixel + 0.5) * cells / extent;
    const double lo = std::floor(f);
    const int i = int(lo);  // pixel centres lie inside the map, so only the upper neighbour wraps
    return {i, (i + 1) % cells, quintic_fade(f - lo)};
}

// One row of lattice values, hashed from the coordinates rather than stored for the whole lattice
// so memory stays flat for fine lattices on large maps.
void fill_lattice_row(std::vector<double>& row, int j, uint64_t key)
{
    for (size_t i = 0; i < row.size(); ++i) {
        const uint64_t point = (uint64_t(i) << 32) | uint64_t(uint32_t(j));
        row[i] = 2.0 * bits_to_unit(mix64(key ^ mix64(point))) - 1.0;
    }
}

}  // namespace

void add_periodic_value_noise(HeightField& field, int cells_x, int cells_y, double amplitude, uint64_t key)
{
    std::vector<LatticeSpan> columns(size_t(field.width()));
    for (int x = 0; x < field.width(); ++x) columns[size_t(x)] = lattice_span(x, field.width(), cells_x);

    const size_t lattice_width = size_t(cells_x);
    std::vector<double> lower(lattice_width), upper(lattice_width);
    int cached_row = -1;
    for (int y = 0; y < field.height(); ++y) {
        const LatticeSpan row = lattice_span(y, field.height(), cells_y);
        // Pixel rows advance slower than lattice rows, so the two lattice rows are rarely refilled.
        if (row.lo != cached_row) {
            fill_lattice_row(lower, row.lo, key);
            fill_lattice_row(upper, row.hi, key);
            cached_row = row.lo;
        }
        for (int x = 0; x < field.width(); ++x) {
            const LatticeSpan& c = columns[size_t(x)];
            const double below = lerp(lower[size_t(c.lo)], lower[size_t(c.hi)], c.weight);
            const double above = lerp(upper[size_t(c.lo)], upper[size_t(c.hi)], c.weight);
            field.at(x, y) += float(amplitude * lerp(below, above, row.weight));
        }
    }
}

}  // namespace ndfbake
