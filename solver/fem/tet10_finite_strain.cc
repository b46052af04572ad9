#include "fem/tet10_finite_strain.h"

#include <Eigen/LU>

#include "fem/strain_displacement.h"
#include "material/hyperelastic.h"

namespace pba {
namespace {

// delta E (Voigt) = B_NL delta u_e: delta E_ij = (F_ki G_aj + F_kj G_ai) delta u_ak / 2,
// the shear rows carrying 2 delta E_ij (as GreenLagrangeVariation for tet4).
Tet10BMatrix NonlinearStrainDisplacement(const Tet10Nodes& grad, const Eigen::Matrix3d& f) {
  return GreenLagrangeB<10>(grad, f);
}

}  // namespace

bool Tet10FiniteStrain(const Tet10Geometry& reference, const Vector30d& u,
                       const HyperelasticMaterial& material, bool with_tangent,
                       Tet10FiniteStrainResult* result, bool drop_pressure_stiffness) {
  if (!(reference.min_jacobian > 0)) return false;
  // All four F first: the material must not see an inadmissible one.
  for (int q = 0; q < 4; ++q) {
    Eigen::Matrix3d& f = result->f[q];
    f.setIdentity();
    for (int a = 0; a < 10; ++a) f += u.segment<3>(3 * a) * reference.grad[q].row(a);
    if (!IsAdmissible(f)) return false;
  }
  result->force.setZero();
  result->energy = 0;
  if (with_tangent) result->tangent.setZero();
  for (int q = 0; q < 4; ++q) {
    const Eigen::Matrix3d& f = result->f[q];
    const Tet10Nodes& grad = reference.grad[q];
    const double dv = reference.volume[q];
    const Vector6d s = material.Stress(f);
    const Tet10BMatrix b = NonlinearStrainDisplacement(grad, f);
    result->force.noalias() += dv * b.transpose() * s;
    result->energy += dv * material.Energy(f);
    if (!with_tangent) continue;
    Matrix6d tangent;
    Vector6d geometric_stress = s;
    if (drop_pressure_stiffness) {
      double w_iso;
      material.Isochoric(f, &w_iso, &geometric_stress, &tangent);
      const double j = f.determinant();
      const Vector6d c_inv = SymmetricToVoigt((f.transpose() * f).inverse());
      tangent += material.Volumetric(j).second * j * j * c_inv * c_inv.transpose();
    } else {
      tangent = material.Tangent(f);
    }
    result->tangent.noalias() += dv * b.transpose() * tangent * b;
    const Eigen::Matrix<double, 10, 10> geometric =
        dv * grad * VoigtToSymmetric(geometric_stress) * grad.transpose();
    for (int a = 0; a < 10; ++a) {
      for (int c = 0; c < 10; ++c) {
        result->tangent.block<3, 3>(3 * a, 3 * c).diagonal().array() += geometric(a, c);
      }
    }
  }
  return true;
}

bool Tet10FiniteStrain(const Tet10Nodes& reference, const Vector30d& u,
                       const HyperelasticMaterial& material, bool with_tangent,
                       Tet10FiniteStrainResult* result) {
  return Tet10FiniteStrain(ComputeTet10Geometry(reference), u, material, with_tangent, result);
}

}  // namespace pba
