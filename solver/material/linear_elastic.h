// Isotropic small-strain linear elasticity (DOMAIN.md eq. 2.21), Voigt order
// xx yy zz yz xz xy with engineering shear strains.
#pragma once

#include "fem/tet4.h"

namespace pba {

// Elasticity matrix D: stress = D strain [Pa].
Matrix6d IsotropicElasticity(double youngs_modulus, double poissons_ratio);

// Its inverse, the compliance matrix [1/Pa].
Matrix6d IsotropicCompliance(double youngs_modulus, double poissons_ratio);

// von Mises equivalent stress of a Voigt stress vector [Pa].
double VonMises(const Vector6d& stress);

}  // namespace pba
