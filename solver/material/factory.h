// From a scene's MaterialSpec to a material model: the checks that name the
// offending scene field, and the construction.
#pragma once

#include <memory>
#include <string>

#include "material/hyperelastic.h"
#include "material/viscoelastic.h"
#include "material/voigt.h"
#include "pba/scene.h"

namespace pba {

// Checks the parameters of whichever model `material` selects. `path` is the
// material's field path ("material"); a failure names e.g.
// "material.ogden.terms[0].alpha" or "material.polynomial.d_per_pa[1]".
Status ValidateMaterialSpec(const MaterialSpec& material, const std::string& path);

// The normalised Prony series of an enabled viscoelastic spec, whichever
// form gives it: kProny as written, kExponential through FromExponential(),
// kModuli through FromModuli(). A disabled spec gives an empty series (no
// relaxation). Checks nothing: ValidateMaterialSpec() does.
PronySeries PronySeriesOf(const ViscoelasticSpec& viscoelastic);

// The hyperelastic model of a validated spec (material.hyperelastic()).
std::unique_ptr<HyperelasticMaterial> MakeHyperelasticMaterial(const MaterialSpec& material);

// Initial (small-strain) Young's modulus and Poisson's ratio of a validated
// isotropic spec: the linear model itself, or a hyperelastic model's tangent
// at F = I. An orthotropic spec has no such pair; use ElasticityMatrix().
struct InitialModuli {
  double youngs_modulus_pa = 0;
  double poissons_ratio = 0;
};
InitialModuli InitialElasticModuli(const MaterialSpec& material);

// Small-strain elasticity matrix D of any validated spec in the global frame
// [Pa], Voigt order xx yy zz yz xz xy with engineering shear strains:
// isotropic from InitialElasticModuli(), orthotropic rotated from its
// material frame (RotateElasticity(OrthotropicElasticity(), MaterialFrame())).
Matrix6d ElasticityMatrix(const MaterialSpec& material);

// Its inverse, the compliance [1/Pa], built in closed form rather than by
// inverting D; what energy norms (the error estimator) measure stress with.
Matrix6d ComplianceMatrix(const MaterialSpec& material);

// One line for the summary, e.g. "linear elastic, E = 3000 Pa, nu = 0.45".
std::string DescribeMaterial(const MaterialSpec& material);

}  // namespace pba
