// Numerical convolution of a zonal BRDF lobe with a vMF lobe: the ground truth that the closed-form
// convolution rules (eq. 20, eq. 21, our GGX rule) are measured against.
#pragma once

#include <functional>
#include <vector>

#include "math/brdf.h"

namespace ndfbake {

// (f ⊗ γ_κ)(β) = ∫ f(ω·n) γ(n; μ, κ) dn for ω at angle β from μ, by quadrature in the angle θ of n
// from μ (fine enough for both the vMF's width 1/√κ and f's width `f_width`) and in azimuth.
double convolve_with_vmf(const std::function<double(double)>& f, double f_width, double kappa, double beta);

// The numerical convolution of brdf.eval with a κ lobe, tabulated over the angle β from μ with
// the sphere's measure, so that candidate rules can be scored against it cheaply.
struct ConvolutionTable {
    std::vector<double> cos_beta, measure, value;
};
ConvolutionTable tabulate_convolution(const BaseBrdf& brdf, double kappa);

// Relative L2 distance over the whole sphere between a rule g(cos β) and the table.
double rule_error(const ConvolutionTable& table, const std::function<double(double)>& rule);

// The same for brdf.convolved(κ), the rule shaders use.
double convolution_rule_error(const BaseBrdf& brdf, double kappa);

}  // namespace ndfbake
