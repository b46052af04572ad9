#include "fem/hex8_finite_strain.h"

#include <Eigen/Geometry>
#include <Eigen/LU>

#include "fem/strain_displacement.h"
#include "material/hyperelastic.h"

namespace pba {
namespace {

// Derivation (Pi as in the header; x_a = X_a + u_a the current positions,
// so F_q = sum_a x_a (x) G_a,q and dF_q/dx_a,i = e_i (x) G_a,q):
//
//   d(det F)/dF = cof F = (det F) F^-T (Jacobi's formula), hence
//     dv/dx_a = sum_q dV_q cof(F_q) G_a,q.
//   det F = (1/6) eps_ijm eps_kln F_ik F_jl F_mn, so
//     d2(det F)/dF_ik dF_jl = eps_ijm eps_kln F_mn and
//     d2v/dx_a,i dx_b,j = sum_q dV_q eps_ijm eps_kln F_mn G_ak G_bl
//                       = sum_q dV_q eps_ijm w_m,  w = F_q (G_a x G_b),
//                       = -sum_q dV_q [w]_x(i, j),
//     since [w]_x(i, j) = eps_imj w_m = -eps_ijm w_m. Each point's term is
//     skew in the node pair (block (b, a) = block (a, b)^T = -block (a, b),
//     blocks (a, a) = 0), as in analysis/average_nodal_pressure_model.cc.
//   d/dx [V U(v / V)] = U'(theta) dv/dx, and once more
//     (U''(theta) / V) (dv/dx)(dv/dx)^T + U'(theta) d2v/dx2.
//   The isochoric sum is the usual total-Lagrangian element of W_iso
//     (fem/tet10_finite_strain.h): force B_NL^T S_iso, tangent material
//     B_NL^T C_iso B_NL plus geometric (G_a . S_iso G_b) I.
//
// On a homogeneous deformation theta = det F and Pi = V W(F), the plain
// element's (Hex8FiniteStrainFull) value. At u = 0, U'(1) = 0,
// dv/dx_a = V mean(G_a) and C_iso = the deviatoric part of the initial
// elasticity, so K is the B-bar stiffness of fem/hex8.h with
// D = D_dev + K m m^T.

// delta E (Voigt) = B_NL delta u_e: delta E_ij = (F_ki G_aj + F_kj G_ai) delta u_ak / 2,
// the shear rows carrying 2 delta E_ij (as for the tetrahedra).
Hex8BMatrix NonlinearStrainDisplacement(const Hex8Nodes& grad, const Eigen::Matrix3d& f) {
  return GreenLagrangeB<8>(grad, f);
}

// cof F by columns: (f2 x f3, f3 x f1, f1 x f2), no inverse needed.
Eigen::Matrix3d Cofactor(const Eigen::Matrix3d& f) {
  Eigen::Matrix3d cof;
  cof.col(0) = f.col(1).cross(f.col(2));
  cof.col(1) = f.col(2).cross(f.col(0));
  cof.col(2) = f.col(0).cross(f.col(1));
  return cof;
}

// [w]_x, the matrix of y -> w x y.
Eigen::Matrix3d Skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d s;
  s << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return s;
}

// F at all eight points into result->f and the force, energy and (when
// `with_tangent`) tangent zeroed; false when the reference element is
// inverted or an F is not admissible. All eight F come first: the material
// must not see an inadmissible one.
bool StartElement(const Hex8Geometry& reference, const Vector24d& u, bool with_tangent,
                  Hex8FiniteStrainResult* result) {
  if (!(reference.min_jacobian > 0)) return false;
  for (int q = 0; q < 8; ++q) {
    Eigen::Matrix3d& f = result->f[q];
    f.setIdentity();
    for (int a = 0; a < 8; ++a) f += u.segment<3>(3 * a) * reference.grad[q].row(a);
    if (!IsAdmissible(f)) return false;
  }
  result->force.setZero();
  result->energy = 0;
  if (with_tangent) result->tangent.setZero();
  return true;
}

// The initial-stress stiffness of stress `s` (Voigt) at one point of volume
// `dv`: (G_a . S G_b) I in block (a, b).
void AddGeometricStiffness(const Hex8Nodes& grad, const Vector6d& s, double dv,
                           Matrix24d* tangent) {
  const Eigen::Matrix<double, 8, 8> geometric = dv * grad * VoigtToSymmetric(s) * grad.transpose();
  for (int a = 0; a < 8; ++a) {
    for (int e = 0; e < 8; ++e) {
      tangent->block<3, 3>(3 * a, 3 * e).diagonal().array() += geometric(a, e);
    }
  }
}

}  // namespace

bool Hex8FiniteStrain(const Hex8Geometry& reference, const Vector24d& u,
                      const HyperelasticMaterial& material, bool with_tangent,
                      Hex8FiniteStrainResult* result, bool drop_pressure_stiffness) {
  if (!StartElement(reference, u, with_tangent, result)) return false;
  const bool with_pressure_stiffness = with_tangent && !drop_pressure_stiffness;
  Vector24d volume_gradient = Vector24d::Zero();  // dv/dx
  Matrix24d volume_hessian;                       // d2v/dx2
  if (with_pressure_stiffness) volume_hessian.setZero();
  double volume = 0;  // v
  for (int q = 0; q < 8; ++q) {
    const Eigen::Matrix3d& f = result->f[q];
    const Hex8Nodes& grad = reference.grad[q];
    const double dv = reference.volume[q];
    double w_iso = 0;
    Vector6d s;
    Matrix6d c;
    material.Isochoric(f, &w_iso, &s, with_tangent ? &c : nullptr);
    const Hex8BMatrix b = NonlinearStrainDisplacement(grad, f);
    result->force.noalias() += dv * b.transpose() * s;
    result->energy += dv * w_iso;
    volume += dv * f.determinant();
    const Eigen::Matrix3d cof = Cofactor(f);
    for (int a = 0; a < 8; ++a) {
      volume_gradient.segment<3>(3 * a) += dv * cof * grad.row(a).transpose();
    }
    if (!with_tangent) continue;
    result->tangent.noalias() += dv * b.transpose() * c * b;
    AddGeometricStiffness(grad, s, dv, &result->tangent);
    if (!with_pressure_stiffness) continue;
    for (int a = 0; a < 8; ++a) {
      for (int e = a + 1; e < 8; ++e) {
        const Eigen::Vector3d ga = grad.row(a).transpose(), ge = grad.row(e).transpose();
        const Eigen::Matrix3d block = -dv * Skew(f * ga.cross(ge));
        volume_hessian.block<3, 3>(3 * a, 3 * e) += block;
        volume_hessian.block<3, 3>(3 * e, 3 * a) += block.transpose();
      }
    }
  }
  const double reference_volume = reference.element_volume;
  result->theta = volume / reference_volume;
  const ScalarDerivatives vol = material.Volumetric(result->theta);
  result->energy += reference_volume * vol.value;
  result->force += vol.first * volume_gradient;
  if (with_tangent) {
    result->tangent.noalias() +=
        (vol.second / reference_volume) * volume_gradient * volume_gradient.transpose();
    if (with_pressure_stiffness) result->tangent += vol.first * volume_hessian;
  }
  return true;
}

bool Hex8FiniteStrain(const Hex8Nodes& reference, const Vector24d& u,
                      const HyperelasticMaterial& material, bool with_tangent,
                      Hex8FiniteStrainResult* result, bool drop_pressure_stiffness) {
  return Hex8FiniteStrain(ComputeHex8Geometry(reference), u, material, with_tangent, result,
                          drop_pressure_stiffness);
}

bool Hex8FiniteStrainFull(const Hex8Geometry& reference, const Vector24d& u,
                          const HyperelasticMaterial& material, bool with_tangent,
                          Hex8FiniteStrainResult* result, bool drop_pressure_stiffness) {
  if (!StartElement(reference, u, with_tangent, result)) return false;
  double volume = 0;  // v, for theta only
  for (int q = 0; q < 8; ++q) {
    const Eigen::Matrix3d& f = result->f[q];
    const Hex8Nodes& grad = reference.grad[q];
    const double dv = reference.volume[q];
    const Vector6d s = material.Stress(f);
    const Hex8BMatrix b = NonlinearStrainDisplacement(grad, f);
    result->force.noalias() += dv * b.transpose() * s;
    result->energy += dv * material.Energy(f);
    volume += dv * f.determinant();
    if (!with_tangent) continue;
    Matrix6d c;
    Vector6d geometric_stress = s;
    if (drop_pressure_stiffness) {
      // The point's volumetric Hessian is U'' dJ dJ^T + U' d2J; with
      // dJ = J C^-1 : delta E the first is U'' J^2 C^-1 (x) C^-1 in the
      // material part, and U' d2J is what the J U' C^-1 parts of the
      // material tangent and of S in the geometric term add up to.
      double w_iso = 0;
      material.Isochoric(f, &w_iso, &geometric_stress, &c);
      const double j = f.determinant();
      const Vector6d c_inv = SymmetricToVoigt((f.transpose() * f).inverse());
      c.noalias() += material.Volumetric(j).second * j * j * c_inv * c_inv.transpose();
    } else {
      c = material.Tangent(f);
    }
    result->tangent.noalias() += dv * b.transpose() * c * b;
    AddGeometricStiffness(grad, geometric_stress, dv, &result->tangent);
  }
  result->theta = volume / reference.element_volume;
  return true;
}

bool Hex8FiniteStrainFull(const Hex8Nodes& reference, const Vector24d& u,
                          const HyperelasticMaterial& material, bool with_tangent,
                          Hex8FiniteStrainResult* result, bool drop_pressure_stiffness) {
  return Hex8FiniteStrainFull(ComputeHex8Geometry(reference), u, material, with_tangent, result,
                              drop_pressure_stiffness);
}

}  // namespace pba
