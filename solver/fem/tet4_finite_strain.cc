#include "fem/tet4_finite_strain.h"

#include <Eigen/LU>

#include "fem/strain_displacement.h"
#include "material/hyperelastic.h"

namespace pba {

Eigen::Matrix3d DeformationGradient(const Tet4Geometry& reference, const Vector12d& u) {
  Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
  for (int a = 0; a < 4; ++a) f += u.segment<3>(3 * a) * reference.grad.row(a);
  return f;
}

BMatrix GreenLagrangeVariation(const Tet4Geometry& reference, const Eigen::Matrix3d& f) {
  return GreenLagrangeB<4>(reference.grad, f);
}

bool Tet4FiniteStrain(const Tet4Geometry& reference, const Vector12d& u,
                      const HyperelasticMaterial& material, bool with_tangent,
                      Tet4FiniteStrainResult* result) {
  const Eigen::Matrix3d f = DeformationGradient(reference, u);
  result->jacobian = f.determinant();
  if (!(result->jacobian > 0)) return false;
  const double volume = std::abs(reference.volume);
  const Vector6d s = material.Stress(f);
  const BMatrix b = GreenLagrangeVariation(reference, f);
  result->force = volume * b.transpose() * s;
  result->energy = volume * material.Energy(f);
  if (!with_tangent) return true;
  result->tangent = volume * b.transpose() * material.Tangent(f) * b;
  // Geometric stiffness: (grad N_a . S grad N_b) I for every node pair.
  const Eigen::Matrix3d stress = VoigtToSymmetric(s);
  const Eigen::Matrix<double, 4, 4> g = reference.grad * stress * reference.grad.transpose();
  for (int a = 0; a < 4; ++a) {
    for (int c = 0; c < 4; ++c) {
      result->tangent.block<3, 3>(3 * a, 3 * c).diagonal().array() += volume * g(a, c);
    }
  }
  return true;
}

}  // namespace pba
