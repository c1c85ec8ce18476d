// Output: every corner takes its group's frame (a quad's diagonal corners average both halves'
// frames), corners no group reached take MikkTSpace's default (1, 0, 0), sign -1, and corners of
// degenerate triangles copy a good corner's frame. Writes out_ and mags_ only. May call:
// parallel_for.h, tangent_math.h, mesh_input.h.
#include <algorithm>
#include <cstring>

#include "tangent/parallel_for.h"
#include "tangent/tangent_generator.h"

namespace ndfbake::tangent_generation {

// MikkTSpace's frame for corners no group reached: (1, 0, 0), sign -1.
void Generator::fill_defaults()
{
    parallel_for(mesh_.corner_count(), threads_, 1 << 16, [&](size_t b, size_t e) {
        for (size_t c = b; c < e; ++c) {
            float* t = &out_[4 * c];
            t[0] = 1.0f, t[1] = 0.0f, t[2] = 0.0f, t[3] = -1.0f;
            if (!mags_.empty()) mags_[2 * c] = mags_[2 * c + 1] = 1.0f;
        }
    });
}

// Every corner takes the frame of its group; a quad's diagonal corners belong to both halves
// and average the second group in unless it is bitwise the same frame (the reference's rule, so
// that float noise does not split a frame). The sign is the last group's. Corners no group
// reached keep MikkTSpace's default (1, 0, 0), sign -1.
void Generator::write_corners()
{
    parallel_for(mesh_.face_count(), threads_, 1 << 14, [&](size_t b, size_t e) {
        size_t t = tri_of_face(b);
        for (size_t f = b; f < e; ++f) {
            const uint32_t offset = mesh_.face_offset(f), size = mesh_.face_size(f);
            uint32_t seen = 0;
            for (const size_t last = t + (size == 4 ? 2 : 1); t < last; ++t) {
                if (!good(uint32_t(t))) continue;
                for (uint32_t i = 0; i < 3; ++i) {
                    const uint32_t k = item_of_[t * 3 + i];
                    if (result_sign_[k] == 0) continue;
                    const Float3& r = contrib_[k];
                    const uint32_t c = tris_[t].corner[i];
                    float* o = &out_[4 * c];
                    const uint32_t bit = 1u << (c - offset);
                    if (!(seen & bit)) {
                        o[0] = r.x, o[1] = r.y, o[2] = r.z;
                        if (!mags_.empty()) mags_[2 * c] = result_mags_[k].s, mags_[2 * c + 1] = result_mags_[k].t;
                    } else {
                        if (!(o[0] == r.x && o[1] == r.y && o[2] == r.z)) {
                            const Vec3 avg = normalize_keep_zero(Vec3{o[0], o[1], o[2]} + Vec3{r.x, r.y, r.z});
                            o[0] = avg.x, o[1] = avg.y, o[2] = avg.z;
                        }
                        if (!mags_.empty()) {
                            mags_[2 * c] = 0.5f * (mags_[2 * c] + result_mags_[k].s);
                            mags_[2 * c + 1] = 0.5f * (mags_[2 * c + 1] + result_mags_[k].t);
                        }
                    }
                    seen |= bit;
                    o[3] = float(result_sign_[k]);
                }
            }
            for (uint32_t c = offset; c < offset + size; ++c) {
                if (seen & (1u << (c - offset))) continue;
                float* o = &out_[4 * c];
                o[0] = 1.0f, o[1] = 0.0f, o[2] = 0.0f, o[3] = -1.0f;
                if (!mags_.empty()) mags_[2 * c] = mags_[2 * c + 1] = 1.0f;
            }
        }
    });
}

// Triangle index of face f's first triangle: faces before it plus quads before it. Only needed
// at chunk starts, so it is found by binary search over the triangles' faces.
size_t Generator::tri_of_face(size_t f) const
{
    return size_t(std::lower_bound(tris_.begin(), tris_.end(), uint32_t(f),
                                   [](const MeshTriangle& tri, uint32_t face) { return tri.face < face; }) -
                  tris_.begin());
}


void Generator::copy_corner(uint32_t dst, uint32_t src)
{
    std::memcpy(&out_[4 * dst], &out_[4 * src], 4 * sizeof(float));
    if (!mags_.empty()) std::memcpy(&mags_[2 * dst], &mags_[2 * src], 2 * sizeof(float));
}

void Generator::degenerate_epilogue()
{
    // A degenerate triangle's corner copies the frame of the first good corner welded to it.
    for (size_t t = 0; t < tris_.size(); ++t) {
        if (good(uint32_t(t)) || (flags_[t] & kQuadOneDegen)) continue;
        for (uint32_t i = 0; i < 3; ++i) {
            const uint32_t c = tris_[t].corner[i];
            const uint32_t src = first_good_[weld_tc_[t * 3 + i]];
            if (src != kUnset) copy_corner(c, src);
        }
    }
    // A quad with one degenerate half: its lone corner copies the coincident corner of the
    // good half (one always exists, since the bad half has two equal positions).
    for (size_t t = 0; t < tris_.size(); ++t) {
        if (!good(uint32_t(t)) || !(flags_[t] & kQuadOneDegen)) continue;
        const MeshTriangle& tri = tris_[t];
        const uint32_t offset = mesh_.face_offset(tri.face);
        uint32_t present = 0;
        for (uint32_t i = 0; i < 3; ++i) present |= 1u << (tri.corner[i] - offset);
        uint32_t missing = 0;
        for (uint32_t v = 1; v < 4; ++v)
            if (!(present & (1u << v))) {
                missing = v;
                break;
            }
        const Vec3 target = mesh_.position(offset + missing);
        for (uint32_t i = 0; i < 3; ++i)
            if (same_position(mesh_.position(tri.corner[i]), target)) {
                copy_corner(offset + missing, tri.corner[i]);
                break;
            }
    }
}

}  // namespace ndfbake::tangent_generation
