#include "material/factory.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <utility>

#include "core/number_format.h"
#include "material/linear_elastic.h"
#include "material/ogden.h"
#include "material/polynomial.h"

namespace pba {
namespace {

Status ValidateBulk(double bulk, double shear, const std::string& field) {
  PBA_RETURN_IF_ERROR(RequirePositive(bulk, field));
  if (bulk < shear) {
    return Status::InvalidArgument(
        field, "the bulk modulus (" + ShortNumber(bulk) + " Pa) is below the shear modulus (" +
                   ShortNumber(shear) +
                   " Pa), which makes Poisson's ratio negative; soft tissue is nearly "
                   "incompressible, with K / mu of 1e5 to 1e6");
  }
  return Status::Ok();
}

PolynomialCoefficients PolynomialOf(const PolynomialParams& p) {
  PolynomialCoefficients c;
  c.order = 0;
  for (const PolynomialTermSpec& t : p.terms) {
    c.c[t.i][t.j] = t.c_pa;
    c.order = std::max(c.order, t.i + t.j);
  }
  for (std::size_t k = 0; k < p.d_per_pa.size() && k < 3; ++k) c.volumetric.d[k] = p.d_per_pa[k];
  return c;
}

OgdenCoefficients OgdenOf(const OgdenParams& p) {
  OgdenCoefficients c;
  for (const OgdenTermSpec& t : p.terms) c.terms.push_back({t.mu_pa, t.alpha});
  c.volumetric.d = {2 / p.bulk_modulus_pa, 0, 0};
  return c;
}

Status ValidatePolynomial(const PolynomialParams& p, const std::string& path) {
  if (p.terms.empty()) {
    return Status::InvalidArgument(path + ".terms",
                                   "no terms given: list C_ij as {i: 1, j: 0, c_pa: 500}");
  }
  std::set<std::pair<int, int>> seen;
  int order = 0;
  for (std::size_t k = 0; k < p.terms.size(); ++k) {
    const PolynomialTermSpec& t = p.terms[k];
    const std::string term = path + ".terms[" + std::to_string(k) + "]";
    if (t.i < 0 || t.j < 0 || t.i + t.j < 1 || t.i + t.j > 3) {
      return Status::InvalidArgument(
          term, "powers i = " + std::to_string(t.i) + ", j = " + std::to_string(t.j) +
                    " are out of range: need i, j >= 0 and 1 <= i + j <= 3");
    }
    if (!seen.insert({t.i, t.j}).second) {
      return Status::InvalidArgument(
          term, "C" + std::to_string(t.i) + std::to_string(t.j) + " is given twice");
    }
    PBA_RETURN_IF_ERROR(RequireFinite(t.c_pa, term + ".c_pa"));
    order = std::max(order, t.i + t.j);
  }
  const PolynomialCoefficients c = PolynomialOf(p);
  if (!(c.ShearModulus() > 0)) {
    return Status::InvalidArgument(path + ".terms",
                                   "the initial shear modulus 2 (C10 + C01) must be > 0, got " +
                                       ShortNumber(c.ShearModulus()) + " Pa");
  }
  if (p.d_per_pa.empty() || p.d_per_pa.size() > static_cast<std::size_t>(order)) {
    return Status::InvalidArgument(
        path + ".d_per_pa", "a polynomial of order " + std::to_string(order) + " takes 1 to " +
                                std::to_string(order) + " values D_1..D_N, got " +
                                std::to_string(p.d_per_pa.size()));
  }
  for (std::size_t k = 0; k < p.d_per_pa.size(); ++k) {
    const std::string field = path + ".d_per_pa[" + std::to_string(k) + "]";
    PBA_RETURN_IF_ERROR(k == 0 ? RequirePositive(p.d_per_pa[k], field)
                               : RequireFinite(p.d_per_pa[k], field));
    if (p.d_per_pa[k] < 0) return Status::InvalidArgument(field, "must be >= 0");
  }
  PBA_RETURN_IF_ERROR(ValidateBulk(2 / p.d_per_pa[0], c.ShearModulus(), path + ".d_per_pa[0]"));
  return c.Validate(path);  // backstop: the same checks on the internal form
}

// A Prony series longer than this is a fit gone wrong, and each term costs a
// history variable per quadrature point.
constexpr std::size_t kMaxPronyTerms = 10;

Status ValidateTermCount(std::size_t terms, const std::string& field) {
  if (terms < 1 || terms > kMaxPronyTerms) {
    return Status::InvalidArgument(field, "takes 1 to " + std::to_string(kMaxPronyTerms) +
                                              " relaxation terms, got " + std::to_string(terms));
  }
  return Status::Ok();
}

// The relaxation of a material whose model has passed its own checks;
// `path` is the viscoelastic section's ("material.viscoelastic").
Status ValidateViscoelastic(const MaterialSpec& m, const std::string& path) {
  const ViscoelasticSpec& v = m.viscoelastic;
  if (!m.hyperelastic()) {
    return Status::InvalidArgument(
        path,
        "quasi-linear viscoelasticity relaxes a hyperelastic model's isochoric stress: it is "
        "only for hyperelastic models (neo_hookean, mooney_rivlin, polynomial or ogden)");
  }
  switch (v.form) {
    case ViscoelasticSpec::Form::kNone:
      return Status::Ok();
    case ViscoelasticSpec::Form::kProny: {
      const std::string p = path + ".prony";
      PBA_RETURN_IF_ERROR(ValidateTermCount(v.g.size(), p + ".g"));
      return PronySeriesOf(v).Validate(p);
    }
    case ViscoelasticSpec::Form::kExponential: {
      const std::string p = path + ".exponential";
      if (!std::isfinite(v.long_term_ratio) || v.long_term_ratio <= 0 || v.long_term_ratio > 1) {
        return Status::InvalidArgument(
            p + ".long_term_ratio",
            "G_inf / G0 must lie in (0, 1], got " + ShortNumber(v.long_term_ratio));
      }
      PBA_RETURN_IF_ERROR(RequirePositive(v.beta_per_s, p + ".beta_per_s"));
      return PronySeriesOf(v).Validate(p);
    }
    case ViscoelasticSpec::Form::kModuli: {
      const std::string p = path + ".moduli";
      PBA_RETURN_IF_ERROR(RequirePositive(v.long_term_modulus_pa, p + ".long_term_modulus_pa"));
      PBA_RETURN_IF_ERROR(ValidateTermCount(v.moduli_pa.size(), p + ".moduli_pa"));
      for (std::size_t k = 0; k < v.moduli_pa.size(); ++k) {
        const std::string field = p + ".moduli_pa[" + std::to_string(k) + "]";
        PBA_RETURN_IF_ERROR(RequireFinite(v.moduli_pa[k], field));
        if (v.moduli_pa[k] < 0) {
          return Status::InvalidArgument(field,
                                         "must be >= 0 Pa, got " + ShortNumber(v.moduli_pa[k]));
        }
      }
      // Sizes and relaxation times are checked on the series (".tau_s");
      // its g are the ratios of the moduli checked above.
      return PronySeriesOf(v).Validate(p);
    }
  }
  return Status::Internal("unhandled viscoelastic form");
}

Status ValidateModel(const MaterialSpec& m, const std::string& path) {
  switch (m.kind) {
    case MaterialSpec::Kind::kNone:
      return Status::InvalidArgument(path,
                                     "no material model given: set one of linear_elastic, "
                                     "orthotropic_elastic, neo_hookean, mooney_rivlin, "
                                     "polynomial, ogden");
    case MaterialSpec::Kind::kLinearElastic:
      return m.linear_elastic.Validate(path + ".linear_elastic");
    case MaterialSpec::Kind::kOrthotropicElastic:
      return m.orthotropic_elastic.Validate(path + ".orthotropic_elastic");
    case MaterialSpec::Kind::kNeoHookean: {
      const std::string p = path + ".neo_hookean";
      PBA_RETURN_IF_ERROR(RequirePositive(m.neo_hookean.shear_modulus_pa, p + ".shear_modulus_pa"));
      return ValidateBulk(m.neo_hookean.bulk_modulus_pa, m.neo_hookean.shear_modulus_pa,
                          p + ".bulk_modulus_pa");
    }
    case MaterialSpec::Kind::kMooneyRivlin: {
      const std::string p = path + ".mooney_rivlin";
      const MooneyRivlinParams& mr = m.mooney_rivlin;
      PBA_RETURN_IF_ERROR(RequireFinite(mr.c10_pa, p + ".c10_pa"));
      PBA_RETURN_IF_ERROR(RequireFinite(mr.c01_pa, p + ".c01_pa"));
      if (!(mr.c10_pa + mr.c01_pa > 0)) {
        return Status::InvalidArgument(p + ".c10_pa",
                                       "the initial shear modulus 2 (C10 + C01) must be > 0, got " +
                                           ShortNumber(2 * (mr.c10_pa + mr.c01_pa)) + " Pa");
      }
      return ValidateBulk(mr.bulk_modulus_pa, 2 * (mr.c10_pa + mr.c01_pa), p + ".bulk_modulus_pa");
    }
    case MaterialSpec::Kind::kPolynomial:
      return ValidatePolynomial(m.polynomial, path + ".polynomial");
    case MaterialSpec::Kind::kOgden: {
      const std::string p = path + ".ogden";
      OgdenCoefficients c;
      for (const OgdenTermSpec& t : m.ogden.terms) c.terms.push_back({t.mu_pa, t.alpha});
      c.volumetric.d = {1, 0, 0};  // checked below, with the field's own name
      PBA_RETURN_IF_ERROR(c.Validate(p));
      return ValidateBulk(m.ogden.bulk_modulus_pa, c.ShearModulus(), p + ".bulk_modulus_pa");
    }
  }
  return Status::Internal("unhandled material kind");
}

}  // namespace

Status ValidateMaterialSpec(const MaterialSpec& m, const std::string& path) {
  PBA_RETURN_IF_ERROR(ValidateModel(m, path));
  if (!m.viscoelastic.enabled()) return Status::Ok();
  return ValidateViscoelastic(m, path + ".viscoelastic");
}

PronySeries PronySeriesOf(const ViscoelasticSpec& v) {
  switch (v.form) {
    case ViscoelasticSpec::Form::kNone:
      break;
    case ViscoelasticSpec::Form::kProny:
      return PronySeries{v.g, v.tau_s};
    case ViscoelasticSpec::Form::kExponential:
      return FromExponential(v.long_term_ratio, v.beta_per_s);
    case ViscoelasticSpec::Form::kModuli:
      return FromModuli(v.long_term_modulus_pa, v.moduli_pa, v.tau_s);
  }
  return PronySeries();
}

std::unique_ptr<HyperelasticMaterial> MakeHyperelasticMaterial(const MaterialSpec& m) {
  switch (m.kind) {
    case MaterialSpec::Kind::kNeoHookean:
      return std::make_unique<PolynomialMaterial>(
          NeoHookeanCoefficients(m.neo_hookean.shear_modulus_pa, m.neo_hookean.bulk_modulus_pa));
    case MaterialSpec::Kind::kMooneyRivlin:
      return std::make_unique<PolynomialMaterial>(MooneyRivlinCoefficients(
          m.mooney_rivlin.c10_pa, m.mooney_rivlin.c01_pa, m.mooney_rivlin.bulk_modulus_pa));
    case MaterialSpec::Kind::kPolynomial:
      return std::make_unique<PolynomialMaterial>(PolynomialOf(m.polynomial));
    case MaterialSpec::Kind::kOgden:
      return std::make_unique<OgdenMaterial>(OgdenOf(m.ogden));
    default:
      return nullptr;
  }
}

InitialModuli InitialElasticModuli(const MaterialSpec& m) {
  if (m.kind == MaterialSpec::Kind::kLinearElastic) {
    return {m.linear_elastic.youngs_modulus_pa, m.linear_elastic.poissons_ratio};
  }
  const auto material = MakeHyperelasticMaterial(m);
  if (material == nullptr) {
    // An orthotropic (or missing) model has no isotropic pair; callers that
    // may meet one go through ElasticityMatrix().
    std::fprintf(stderr, "InitialElasticModuli: material kind %d is not isotropic\n",
                 static_cast<int>(m.kind));
    std::abort();
  }
  const double mu = material->ShearModulus(), k = material->BulkModulus();
  return {9 * k * mu / (3 * k + mu), (3 * k - 2 * mu) / (2 * (3 * k + mu))};
}

Matrix6d ElasticityMatrix(const MaterialSpec& m) {
  if (m.kind == MaterialSpec::Kind::kOrthotropicElastic) {
    const OrthotropicElasticParams& p = m.orthotropic_elastic;
    return RotateElasticity(OrthotropicElasticity(p), MaterialFrame(p.axis_1, p.axis_2));
  }
  const InitialModuli p = InitialElasticModuli(m);
  return IsotropicElasticity(p.youngs_modulus_pa, p.poissons_ratio);
}

Matrix6d ComplianceMatrix(const MaterialSpec& m) {
  if (m.kind == MaterialSpec::Kind::kOrthotropicElastic) {
    const OrthotropicElasticParams& p = m.orthotropic_elastic;
    return RotateCompliance(OrthotropicCompliance(p), MaterialFrame(p.axis_1, p.axis_2));
  }
  const InitialModuli p = InitialElasticModuli(m);
  return IsotropicCompliance(p.youngs_modulus_pa, p.poissons_ratio);
}

namespace {

// "[0.5, 0.2]"
std::string ListOf(const std::vector<double>& values) {
  std::string out;
  for (double v : values) out += (out.empty() ? "" : ", ") + ShortNumber(v);
  return "[" + out + "]";
}

std::string DescribeModel(const MaterialSpec& m) {
  if (m.kind == MaterialSpec::Kind::kLinearElastic) {
    return "linear elastic, E = " + RoundTripNumber(m.linear_elastic.youngs_modulus_pa) +
           " Pa, nu = " + RoundTripNumber(m.linear_elastic.poissons_ratio);
  }
  if (m.kind == MaterialSpec::Kind::kOrthotropicElastic) {
    const OrthotropicElasticParams& p = m.orthotropic_elastic;
    const Eigen::Matrix3d q = MaterialFrame(p.axis_1, p.axis_2);
    auto axis = [&](int c) {
      return "(" + ShortNumber(q(0, c)) + ", " + ShortNumber(q(1, c)) + ", " +
             ShortNumber(q(2, c)) + ")";
    };
    return "orthotropic linear elastic, E1 = " + RoundTripNumber(p.e1_pa) +
           " Pa, E2 = " + RoundTripNumber(p.e2_pa) + " Pa, E3 = " + RoundTripNumber(p.e3_pa) +
           " Pa, nu12 = " + RoundTripNumber(p.nu12) + ", nu13 = " + RoundTripNumber(p.nu13) +
           ", nu23 = " + RoundTripNumber(p.nu23) + ", G12 = " + RoundTripNumber(p.g12_pa) +
           " Pa, G13 = " + RoundTripNumber(p.g13_pa) + " Pa, G23 = " + RoundTripNumber(p.g23_pa) +
           " Pa, axis 1 = " + axis(0) + ", axis 2 = " + axis(1);
  }
  return MakeHyperelasticMaterial(m)->Describe();
}

}  // namespace

std::string DescribeMaterial(const MaterialSpec& m) {
  std::string out = DescribeModel(m);
  if (m.viscoelastic.enabled()) {
    const PronySeries series = PronySeriesOf(m.viscoelastic);
    out += ", relaxing: g = " + ListOf(series.g) + ", tau = " + ListOf(series.tau_s) +
           " s, mu_inf/mu0 = " + ShortNumber(series.LongTermFactor());
  }
  return out;
}

}  // namespace pba
