// The exported GLSL's decoding constants against the library's own convolution rule.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <string>

#include "export/lobe_shader.h"
#include "math/brdf.h"
#include "math/vmf.h"

namespace ndfbake {
namespace {

double shader_constant(const std::string& shader, const std::string& name)
{
    std::smatch match;
    const std::regex define("#define " + name + " ([-+0-9.eE]+)");
    if (!std::regex_search(shader, match, define)) ADD_FAILURE() << name << " is not defined";
    return match.empty() ? 0.0 : std::stod(match[1].str());
}

// The widened α' the shader's documented decoding gives a lobe stored at |r| = R.
double shader_alpha(double alpha, double resultant, double widening, double offset)
{
    const double r2 = resultant * resultant;
    const double inv_kappa = std::max((1.0 - r2) / std::max(resultant * (3.0 - r2), 1e-6) - offset, 0.0);
    return std::min(1.0, std::sqrt(alpha * alpha + widening * inv_kappa));
}

TEST(LobeShader, SingleFloatLobesShadeAsTheLibraryWidensThem)
{
    // A single-float file holds r at lobe_resultant(κ) (|r| = 1 at the cap); the shader's
    // decoding must give the α' the library's rule gives, the cap's lobe unwidened included.
    const std::string shader = lobe_shader_glsl(4, PixelPrecision::single);
    const double widening = shader_constant(shader, "NDFB_GGX_VMF_WIDENING");
    const double offset = shader_constant(shader, "NDFB_INV_KAPPA_RESOLUTION");
    for (float roughness : {0.05f, 0.2f, 0.5f}) {
        const BaseBrdf ggx = BaseBrdf::ggx(roughness);
        for (float kappa : {2.0f, 50.0f, 1000.0f, 5000.0f, 9999.0f, kKappaMax}) {
            const double stored = lobe_resultant(kappa);
            const double alpha = double(roughness) * double(roughness);
            EXPECT_NEAR(shader_alpha(alpha, stored, widening, offset), ggx.convolved(kappa).lobe_parameter(), 2e-5)
                << "roughness " << roughness << " kappa " << kappa;
        }
    }
}

TEST(LobeShader, HalfFloatLobesTakeOffTheirRounding)
{
    // Half floats round |r| of a single direction up to 3.6e-4 off 1 (io/lobe_exr.h).
    const std::string shader = lobe_shader_glsl(2, PixelPrecision::half);
    EXPECT_FLOAT_EQ(float(shader_constant(shader, "NDFB_INV_KAPPA_RESOLUTION")), kHalfInvKappaResolution);
    EXPECT_EQ(shader_constant(shader, "NDFB_LOBES"), 2.0);
}

}  // namespace
}  // namespace ndfbake
