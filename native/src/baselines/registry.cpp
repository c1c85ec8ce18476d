#include "baselines/registry.h"

#include <charconv>

#include "baselines/lean.h"
#include "baselines/mean_normal.h"
#include "baselines/sh_ndf.h"
#include "baselines/spherical_harmonics.h"
#include "baselines/xu_partitions.h"
#include "error.h"

namespace ndfbake {

std::vector<std::string> baseline_names()
{
    std::vector<std::string> names = {"naive",  "toksvig", "single-vmf", "lean",
                                      "xu-1x1", "xu-1x4",  "xu-2x4",     "xu-adaptive"};
    for (int order = kListedShOrderMin; order <= kListedShOrderMax; ++order) names.push_back("sh-" + std::to_string(order));
    return names;
}

std::unique_ptr<NdfPyramid> build_baseline(const std::string& name, const NormalMap& map, WrapMode wrap)
{
    if (name == "naive") return make_naive_pyramid(map, wrap);
    if (name == "toksvig") return make_toksvig_pyramid(map, wrap);
    if (name == "single-vmf") return make_single_vmf_pyramid(map, wrap);
    if (name == "lean") return make_lean_pyramid(map, wrap);
    if (name == "xu-1x1") return make_xu_pyramid(map, wrap, XuPartition::whole);
    if (name == "xu-1x4") return make_xu_pyramid(map, wrap, XuPartition::sectors);
    if (name == "xu-2x4") return make_xu_pyramid(map, wrap, XuPartition::sectors_bands);
    if (name == "xu-adaptive") return make_xu_adaptive_pyramid(map, wrap);
    if (name.starts_with("sh-")) {
        int order = -1;
        const char* first = name.data() + 3;
        const char* last = name.data() + name.size();
        const auto [end, error] = std::from_chars(first, last, order);
        if (error == std::errc() && end == last && first != last && order >= 0 && order <= kMaxShOrder)
            return make_sh_pyramid(map, wrap, order);
    }
    throw Error(Status::invalid_argument, "unknown baseline '" + name + "': expected one of naive, toksvig, "
                                          "single-vmf, lean, xu-1x1, xu-1x4, xu-2x4, xu-adaptive, sh-N (N in 0.." +
                                              std::to_string(kMaxShOrder) + ")");
}

}  // namespace ndfbake
