#include "baselines/mean_normal.h"

#include <algorithm>

#include "baselines/linear_pyramid.h"
#include "math/vmf.h"
#include "ndf/effective_brdf.h"

namespace ndfbake {

namespace {

enum class MeanNormalShader { naive, toksvig, single_vmf };

class MeanNormalPyramid final : public LinearNdfPyramid {
public:
    MeanNormalPyramid(const NormalMap& map, WrapMode wrap, MeanNormalShader shader)
        : LinearNdfPyramid(map, wrap, kMeanNormalFloats,
                           [](const Vec3& n, float* out) {
                               out[0] = n.x;
                               out[1] = n.y;
                               out[2] = n.z;
                           }),
          shader_(shader)
    {
    }

    std::string name() const override
    {
        switch (shader_) {
        case MeanNormalShader::naive: return "naive";
        case MeanNormalShader::toksvig: return "toksvig";
        case MeanNormalShader::single_vmf: return "single-vmf";
        }
        return "";
    }

    void effective_brdf(int level, int x, int y, const BaseBrdf& brdf, std::span<const Vec3> directions,
                        std::span<float> out) const override
    {
        check_output(directions, out);
        const std::span<const float> t = texel(level, x, y);
        const Vec3 mean{t[0], t[1], t[2]};
        // Normals that cancel leave no direction: +Z, the neutral normal (as mean_normal does).
        const Vec3 direction = normalize_or(mean, {0.0f, 0.0f, 1.0f});
        const double r = std::min(1.0, double(length(mean)));
        if (shader_ == MeanNormalShader::naive) {
            for (size_t d = 0; d < directions.size(); ++d) out[d] = brdf.eval(dot(directions[d], direction));
            return;
        }
        const float kappa = shader_ == MeanNormalShader::toksvig ? toksvig_kappa(r) : kappa_from_resultant(r);
        const VmfLobe lobe{1.0f, direction, kappa};
        mixture_effective_brdf(std::span(&lobe, 1), brdf, directions, out);
    }

private:
    MeanNormalShader shader_;
};

}  // namespace

float toksvig_kappa(double mean_length)
{
    if (!(mean_length > 0.0)) return kKappaMin;  // also catches NaN
    if (mean_length >= 1.0) return kKappaMax;
    const double kappa = mean_length / (1.0 - mean_length);
    return float(std::clamp(kappa, double(kKappaMin), double(kKappaMax)));
}

std::unique_ptr<NdfPyramid> make_naive_pyramid(const NormalMap& map, WrapMode wrap)
{
    return std::make_unique<MeanNormalPyramid>(map, wrap, MeanNormalShader::naive);
}

std::unique_ptr<NdfPyramid> make_toksvig_pyramid(const NormalMap& map, WrapMode wrap)
{
    return std::make_unique<MeanNormalPyramid>(map, wrap, MeanNormalShader::toksvig);
}

std::unique_ptr<NdfPyramid> make_single_vmf_pyramid(const NormalMap& map, WrapMode wrap)
{
    return std::make_unique<MeanNormalPyramid>(map, wrap, MeanNormalShader::single_vmf);
}

}  // namespace ndfbake
