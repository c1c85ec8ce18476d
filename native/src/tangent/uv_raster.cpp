#include "tangent/uv_raster.h"

#include <algorithm>
#include <cmath>

#include "tangent/parallel_for.h"
#include "tangent/triangulation.h"

namespace ndfbake {

std::vector<RenderTriangle> render_triangles(const MeshInput& mesh)
{
    std::vector<RenderTriangle> tris;
    tris.reserve(mesh.face_count() * 2);
    for (size_t f = 0; f < mesh.face_count(); ++f) {
        const uint32_t o = mesh.face_offset(f);
        if (mesh.face_size(f) == 3) {
            tris.push_back({{o, o + 1, o + 2}});
        } else if (render_quad_splits_02(mesh, f)) {
            tris.push_back({{o, o + 1, o + 2}});
            tris.push_back({{o, o + 2, o + 3}});
        } else {
            tris.push_back({{o, o + 1, o + 3}});
            tris.push_back({{o + 1, o + 2, o + 3}});
        }
    }
    return tris;
}

void rasterize_uv(const MeshInput& mesh, const std::vector<RenderTriangle>& triangles, int width, int height,
                  int threads, std::vector<uint8_t>& covered, const TexelVisitor& visit)
{
    covered.assign(size_t(width) * height, 0);
    struct Screen {
        double x[3], y[3], area;
        int x0, x1, y0, y1;
    };
    // Texel space: X = u * width, Y = (1 - v) * height; centres at integer + 0.5.
    std::vector<Screen> screens(triangles.size());
    for (size_t t = 0; t < triangles.size(); ++t) {
        Screen& s = screens[t];
        double minx = 1e300, maxx = -1e300, miny = 1e300, maxy = -1e300;
        for (int k = 0; k < 3; ++k) {
            const Vec2 uv = mesh.uv(triangles[t].corner[k]);
            s.x[k] = double(uv.x) * width;
            s.y[k] = (1.0 - double(uv.y)) * height;
            minx = std::min(minx, s.x[k]), maxx = std::max(maxx, s.x[k]);
            miny = std::min(miny, s.y[k]), maxy = std::max(maxy, s.y[k]);
        }
        s.area = (s.x[1] - s.x[0]) * (s.y[2] - s.y[0]) - (s.y[1] - s.y[0]) * (s.x[2] - s.x[0]);
        // Bounds of the texel centres inside the box, clipped to the image (empty when outside).
        // Clamped on both sides in double before converting: a UV far outside [0, 1] (1e10) is out
        // of int's range, and converting it would be undefined (found by fuzz_tangent).
        s.x0 = int(std::clamp(std::ceil(minx - 0.5), 0.0, double(width)));
        s.x1 = int(std::clamp(std::floor(maxx - 0.5), -1.0, double(width - 1)));
        s.y0 = int(std::clamp(std::ceil(miny - 0.5), 0.0, double(height)));
        s.y1 = int(std::clamp(std::floor(maxy - 0.5), -1.0, double(height - 1)));
        if (s.area == 0.0) s.x1 = -1;  // no UV area: covers nothing
    }
    // Bands of rows; every band walks the triangle list in order, so the first triangle wins.
    const int bands = std::max(1, std::min(height, resolve_thread_count(threads) * 4));
    const int rows_per_band = (height + bands - 1) / bands;
    parallel_for(size_t(bands), threads, 1, [&](size_t b0, size_t b1) {
        for (size_t band = b0; band < b1; ++band) {
            const int row0 = int(band) * rows_per_band, row1 = std::min(height - 1, row0 + rows_per_band - 1);
            for (size_t t = 0; t < screens.size(); ++t) {
                const Screen& s = screens[t];
                if (s.x1 < s.x0 || s.y1 < row0 || s.y0 > row1) continue;
                const double inv = 1.0 / s.area;
                for (int y = std::max(s.y0, row0); y <= std::min(s.y1, row1); ++y) {
                    const double py = y + 0.5;
                    for (int x = s.x0; x <= s.x1; ++x) {
                        const double px = x + 0.5;
                        // Edge functions divided by the signed area: barycentric weights.
                        const double w0 = ((s.x[1] - px) * (s.y[2] - py) - (s.y[1] - py) * (s.x[2] - px)) * inv;
                        const double w1 = ((s.x[2] - px) * (s.y[0] - py) - (s.y[2] - py) * (s.x[0] - px)) * inv;
                        const double w2 = 1.0 - w0 - w1;
                        if (w0 < 0.0 || w1 < 0.0 || w2 < -1e-12) continue;
                        uint8_t& c = covered[size_t(y) * width + x];
                        if (c) continue;
                        c = 1;
                        visit(x, y, uint32_t(t), w0, w1, std::max(0.0, w2));
                    }
                }
            }
        }
    });
}

}  // namespace ndfbake
