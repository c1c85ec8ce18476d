#include "baselines/sh_ndf.h"

#include <string>
#include <vector>

#include "baselines/linear_pyramid.h"
#include "baselines/spherical_harmonics.h"
#include "error.h"

namespace ndfbake {

namespace {

int checked_order(int order)
{
    if (order < 0 || order > kMaxShOrder)
        throw Error(Status::invalid_argument, "SH order must be in [0, " + std::to_string(kMaxShOrder) + "], got " +
                                                  std::to_string(order));
    return order;
}

class ShPyramid final : public LinearNdfPyramid {
public:
    ShPyramid(const NormalMap& map, WrapMode wrap, int order)
        : LinearNdfPyramid(map, wrap, sh_count(checked_order(order)),
                           [order](const Vec3& n, float* out) {
                               // eq. 13 at the finest level: γ_lm = Y_lm(n).
                               double y[sh_count(kMaxShOrder)];
                               real_sh(n, order, y);
                               for (int i = 0; i < sh_count(order); ++i) out[i] = float(y[i]);
                           }),
          order_(order)
    {
    }

    std::string name() const override { return "sh-" + std::to_string(order_); }

    void effective_brdf(int level, int x, int y, const BaseBrdf& brdf, std::span<const Vec3> directions,
                        std::span<float> out) const override
    {
        check_output(directions, out);
        const std::span<const float> gamma = texel(level, x, y);
        const std::vector<double> rho = zonal_brdf_coefficients(brdf, order_);
        // ρ̂_l γ_lm, then eq. 12 per direction.
        std::vector<double> weighted(gamma.size());
        for (int l = 0; l <= order_; ++l)
            for (int m = -l; m <= l; ++m)
                weighted[size_t(sh_index(l, m))] = rho[size_t(l)] * double(gamma[size_t(sh_index(l, m))]);
        std::vector<double> basis(gamma.size());
        for (size_t d = 0; d < directions.size(); ++d) {
            real_sh(directions[d], order_, basis.data());
            double sum = 0.0;
            for (size_t i = 0; i < basis.size(); ++i) sum += weighted[i] * basis[i];
            out[d] = float(sum);
        }
    }

private:
    int order_;
};

}  // namespace

std::unique_ptr<NdfPyramid> make_sh_pyramid(const NormalMap& map, WrapMode wrap, int order)
{
    return std::make_unique<ShPyramid>(map, wrap, order);
}

}  // namespace ndfbake
