// generate_tangent_frames (tangent_space.h): checks its arguments and runs one Generator, whose
// run() here fixes the order of the passes. Owns only that order; the passes are in
// tangent_welding.cpp, triangle_tangents.cpp, tangent_groups.cpp and corner_output.cpp (see
// tangent_generator.h). May call: tangent_generator.h, error.h.
#include "tangent/tangent_space.h"

#include <span>
#include <string>

#include "error.h"
#include "tangent/tangent_generator.h"

namespace ndfbake {

namespace tangent_generation {

TangentStats Generator::run()
{
    tris_ = mikk_triangles(mesh_, threads_);
    stats_.triangles = tris_.size();
    if (tris_.empty()) {
        fill_defaults();
        return stats_;
    }
    build_fans();
    weld_pass();
    triangle_pass();
    quad_pass();
    scatter_to_items();
    group_pass();
    if (any_affected_.load()) {
        ordered_groups();
        refresh_item_flags();
        affected_pass();
    }
    write_corners();
    if (stats_.degenerate_triangles > 0) degenerate_epilogue();
    stats_.groups = groups_.load();
    return stats_;
}

}  // namespace tangent_generation

TangentStats generate_tangent_frames(const MeshInput& mesh, int threads, std::span<float> tangents,
                                     std::span<float> magnitudes)
{
    if (mesh.ngon_faces() > 0)
        throw Error(Status::invalid_argument, "tangent frames need triangles and quads; the mesh has " +
                                                  std::to_string(mesh.ngon_faces()) + " n-gons");
    if (tangents.size() != mesh.corner_count() * 4)
        throw Error(Status::invalid_argument, "tangents must hold 4 floats per corner (" +
                                                  std::to_string(mesh.corner_count() * 4) + "), got " +
                                                  std::to_string(tangents.size()));
    if (!magnitudes.empty() && magnitudes.size() != mesh.corner_count() * 2)
        throw Error(Status::invalid_argument, "magnitudes must hold 2 floats per corner (" +
                                                  std::to_string(mesh.corner_count() * 2) + "), got " +
                                                  std::to_string(magnitudes.size()));
    return tangent_generation::Generator(mesh, threads, tangents, magnitudes).run();
}

}  // namespace ndfbake
