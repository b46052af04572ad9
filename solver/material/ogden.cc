#include "material/ogden.h"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace pba {

Status OgdenCoefficients::Validate(const std::string& path) const {
  if (terms.empty() || terms.size() > 3) {
    return Status::InvalidArgument(
        path + ".terms", "an Ogden model has 1 to 3 terms, got " + std::to_string(terms.size()));
  }
  for (std::size_t p = 0; p < terms.size(); ++p) {
    const std::string term = path + ".terms[" + std::to_string(p) + "]";
    PBA_RETURN_IF_ERROR(RequireFinite(terms[p].mu, term + ".mu_pa"));
    PBA_RETURN_IF_ERROR(RequireFinite(terms[p].alpha, term + ".alpha"));
    if (terms[p].alpha == 0) return Status::InvalidArgument(term + ".alpha", "must be nonzero");
  }
  if (!(ShearModulus() > 0)) {
    return Status::InvalidArgument(path + ".terms",
                                   "the initial shear modulus sum mu_p must be > 0, got " +
                                       ShortNumber(ShearModulus()) + " Pa");
  }
  return volumetric.Validate(path, 1);
}

double OgdenCoefficients::ShearModulus() const {
  double mu = 0;
  for (const OgdenTerm& t : terms) mu += t.mu;
  return mu;
}

OgdenMaterial::OgdenMaterial(const OgdenCoefficients& coefficients) : p_(coefficients) {}

double OgdenMaterial::IsochoricEnergy(const Eigen::Matrix3d& f) const {
  const Eigen::Matrix3d c = f.transpose() * f;
  const Eigen::Vector3d eig =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(c, Eigen::EigenvaluesOnly).eigenvalues();
  const double scale = std::pow(f.determinant(), -1.0 / 3.0);
  double w = 0;
  for (const OgdenTerm& t : p_.terms) {
    double sum = -3;
    for (int a = 0; a < 3; ++a) sum += std::pow(scale * std::sqrt(eig(a)), t.alpha);
    w += 2 * t.mu / (t.alpha * t.alpha) * sum;
  }
  return w;
}

double OgdenMaterial::Energy(const Eigen::Matrix3d& f) const {
  if (!IsAdmissible(f)) return INFINITY;
  return IsochoricEnergy(f) + VolumetricEnergy(p_.volumetric, f.determinant()).value;
}

void OgdenMaterial::Isochoric(const Eigen::Matrix3d& f, double* energy, Vector6d* stress,
                              Matrix6d* tangent) const {
  CheckAdmissible(f, "OgdenMaterial::Isochoric");
  if (energy) *energy = IsochoricEnergy(f);
  if (stress || tangent) Response(f, false, stress, tangent);
}

void OgdenMaterial::Response(const Eigen::Matrix3d& f, bool volumetric, Vector6d* stress,
                             Matrix6d* tangent) const {
  const Eigen::Matrix3d c = f.transpose() * f;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(c);
  const Eigen::Matrix3d n = eigen.eigenvectors();  // column a = N_a
  Eigen::Vector3d lambda;
  for (int a = 0; a < 3; ++a) lambda(a) = std::sqrt(eigen.eigenvalues()(a));
  const double j = f.determinant();
  const double scale = std::pow(j, -1.0 / 3.0);

  // Principal Kirchhoff stresses tau_a = lambda_a dW/dlambda_a and
  // gamma_ab = lambda_b d tau_a / d lambda_b. For one term with
  // beta_a = lb_a^alpha and B = sum beta: tau_a = (2 mu/alpha)(beta_a - B/3),
  // gamma_ab = 2 mu (beta_a delta_ab - (beta_a + beta_b)/3 + B/9).
  Eigen::Vector3d tau = Eigen::Vector3d::Zero();
  Eigen::Matrix3d gamma = Eigen::Matrix3d::Zero();
  for (const OgdenTerm& t : p_.terms) {
    Eigen::Vector3d beta;
    for (int a = 0; a < 3; ++a) beta(a) = std::pow(scale * lambda(a), t.alpha);
    const double sum = beta.sum();
    for (int a = 0; a < 3; ++a) {
      tau(a) += 2 * t.mu / t.alpha * (beta(a) - sum / 3);
      for (int b = 0; b < 3; ++b) {
        gamma(a, b) += 2 * t.mu * ((a == b ? beta(a) : 0) - (beta(a) + beta(b)) / 3 + sum / 9);
      }
    }
  }
  // Volumetric part: tau_a = J U'(J), gamma_ab = J U' + J^2 U''.
  const ScalarDerivatives u = volumetric ? VolumetricEnergy(p_.volumetric, j) : ScalarDerivatives();
  tau.array() += j * u.first;
  gamma.array() += j * u.first + j * j * u.second;

  // S_a = tau_a / lambda_a^2.
  Eigen::Vector3d s;
  for (int a = 0; a < 3; ++a) s(a) = tau(a) / (lambda(a) * lambda(a));
  if (stress) *stress = SymmetricToVoigt(n * s.asDiagonal() * n.transpose());
  if (!tangent) return;

  // C = sum_ab (1/lambda_b dS_a/dlambda_b) N_a N_a N_b N_b
  //   + sum_{a != b} g_ab (N_a N_b N_a N_b + N_a N_b N_b N_a),
  // g_ab = (S_b - S_a) / (lambda_b^2 - lambda_a^2), and for coincident
  // stretches its limit (1/lambda_b)(dS_b/dlambda_b - dS_a/dlambda_b) / 2.
  Eigen::Matrix3d normal;  // (1/lambda_b) dS_a/dlambda_b
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      const double la2 = lambda(a) * lambda(a), lb2 = lambda(b) * lambda(b);
      normal(a, b) = (gamma(a, b) - (a == b ? 2 * tau(a) : 0)) / (la2 * lb2);
    }
  }
  Eigen::Matrix3d spin = Eigen::Matrix3d::Zero();
  for (int a = 0; a < 3; ++a) {
    for (int b = 0; b < 3; ++b) {
      if (a == b) continue;
      const double la2 = lambda(a) * lambda(a), lb2 = lambda(b) * lambda(b);
      if (std::abs(lb2 - la2) > 1e-7 * std::max(la2, lb2)) {
        spin(a, b) = (s(b) - s(a)) / (lb2 - la2);
      } else {
        spin(a, b) = 0.5 * (normal(b, b) - normal(a, b));
      }
    }
  }
  *tangent = FourthOrderToVoigt([&](int i, int jj, int k, int l) {
    double value = 0;
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) {
        value += normal(a, b) * n(i, a) * n(jj, a) * n(k, b) * n(l, b);
        if (a != b) {
          value += spin(a, b) * n(i, a) * n(jj, b) * (n(k, a) * n(l, b) + n(k, b) * n(l, a));
        }
      }
    }
    return value;
  });
}

Vector6d OgdenMaterial::Stress(const Eigen::Matrix3d& f) const {
  CheckAdmissible(f, "OgdenMaterial::Stress");
  Vector6d stress;
  Response(f, true, &stress, nullptr);
  return stress;
}

Matrix6d OgdenMaterial::Tangent(const Eigen::Matrix3d& f) const {
  CheckAdmissible(f, "OgdenMaterial::Tangent");
  Matrix6d tangent;
  Response(f, true, nullptr, &tangent);
  return tangent;
}

std::string OgdenMaterial::Describe() const {
  std::string text = "Ogden";
  for (std::size_t p = 0; p < p_.terms.size(); ++p) {
    const std::string index = p_.terms.size() > 1 ? std::to_string(p + 1) : "";
    text += (p ? ", mu" : " mu") + index + " = " + ShortNumber(p_.terms[p].mu) + " Pa, alpha" +
            index + " = " + ShortNumber(p_.terms[p].alpha);
  }
  return text + ", K = " + ShortNumber(BulkModulus()) + " Pa";
}

}  // namespace pba
