// From a scene's MaterialSpec to a material model: the checks that name the
// offending scene field, and the construction.
#pragma once

#include <memory>
#include <string>

#include "material/hyperelastic.h"
#include "pba/scene.h"

namespace pba {

// Checks the parameters of whichever model `material` selects. `path` is the
// material's field path ("material"); a failure names e.g.
// "material.ogden.terms[0].alpha" or "material.polynomial.d_per_pa[1]".
Status ValidateMaterialSpec(const MaterialSpec& material, const std::string& path);

// The hyperelastic model of a validated spec (material.hyperelastic()).
std::unique_ptr<HyperelasticMaterial> MakeHyperelasticMaterial(const MaterialSpec& material);

// Initial (small-strain) Young's modulus and Poisson's ratio of any validated
// spec: the linear model itself, or a hyperelastic model's tangent at F = I.
struct InitialModuli {
  double youngs_modulus_pa = 0;
  double poissons_ratio = 0;
};
InitialModuli InitialElasticModuli(const MaterialSpec& material);

// One line for the summary, e.g. "linear elastic, E = 3000 Pa, nu = 0.45".
std::string DescribeMaterial(const MaterialSpec& material);

}  // namespace pba
