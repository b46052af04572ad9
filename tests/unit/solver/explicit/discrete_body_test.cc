// Every DiscreteBody (assembly/discrete_body.h), implicit and explicit, on
// the same checks: no force from a rigid motion, the force the gradient of
// the stored energy, the history saved and restored; and the implicit and
// explicit bodies giving the same forces where their elements are the same
// (TET4 and TET4_ANP), which is what their sharing one material-point
// kernel (material/material_point.h) must give.
#include "assembly/discrete_body.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "analysis/average_nodal_pressure_model.h"
#include "analysis/finite_strain_model.h"
#include "analysis/hex8_model.h"
#include "analysis/tet10_model.h"
#include "common/finite_strain_checks.h"
#include "explicit/tled_model.h"
#include "material/factory.h"
#include "material/material_field.h"
#include "mesh/quadratic.h"

namespace pba {
namespace {

// A 3 x 3 x 4 mm box of `element`'s node layout.
Mesh Box(ElementType element) {
  const Mesh mesh = testing::BoxMesh(3, 3, 4, 1.5, element);
  if (element == ElementType::kTet10 || element == ElementType::kTet10Md) {
    return MakeQuadratic(mesh);
  }
  return mesh;
}

MaterialSpec NeoHookeanSpec() {
  MaterialSpec neo;
  neo.kind = MaterialSpec::Kind::kNeoHookean;
  neo.neo_hookean = {1000, 5e4};
  return neo;
}

// A smooth displacement with strains of a few per cent.
Eigen::VectorXd Smooth(const Mesh& mesh, double amplitude = 1.5e-4) {
  Eigen::VectorXd u(3 * mesh.num_nodes());
  for (int n = 0; n < mesh.num_nodes(); ++n) {
    const Eigen::Vector3d x = mesh.nodes.row(n).transpose() / 3e-3;
    for (int i = 0; i < 3; ++i) {
      u(3 * n + i) = amplitude * std::sin(2 * x(i) + x((i + 1) % 3) + i);
    }
  }
  return u;
}

// A finite rotation (0.4 rad about a skew axis) and a translation.
Eigen::VectorXd Rigid(const Mesh& mesh) {
  const Eigen::Matrix3d r =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  Eigen::VectorXd u(3 * mesh.num_nodes());
  for (int n = 0; n < mesh.num_nodes(); ++n) {
    const Eigen::Vector3d x = mesh.nodes.row(n).transpose();
    u.segment<3>(3 * n) = r * x - x + Eigen::Vector3d(1e-3, -2e-3, 5e-4);
  }
  return u;
}

// One body under test with what keeps it alive.
struct Subject {
  std::string name;
  Mesh mesh;
  std::shared_ptr<const HyperelasticMaterial> material;
  std::unique_ptr<DiscreteBody> body;
};

std::unique_ptr<Subject> Implicit(ElementType element) {
  auto s = std::make_unique<Subject>();
  s->name = ElementName(element);
  s->mesh = Box(element);
  s->material = MakeHyperelasticMaterial(NeoHookeanSpec());
  const Mesh& mesh = s->mesh;
  const HyperelasticMaterial& m = *s->material;
  switch (element) {
    case ElementType::kTet4:
      s->body = MakeTet4Model(mesh, m);
      break;
    case ElementType::kTet4Anp:
      s->body = MakeAverageNodalPressureTet4Model(mesh, m);
      break;
    case ElementType::kTet10:
      s->body = MakeTet10Model(mesh, m);
      break;
    case ElementType::kTet10Md:
      s->body = MakeTet10MdModel(mesh, m);
      break;
    case ElementType::kHex8:
      s->body = MakeHex8Model(mesh, m);
      break;
    case ElementType::kHex8Full:
      s->body = MakeHex8FullModel(mesh, m);
      break;
    default:
      ADD_FAILURE() << "no implicit body for " << s->name;
  }
  return s;
}

// The explicit engine's body on the mesh of `element` (TET4, TET4_ANP or
// HEX8), without bulk viscosity; `relaxation` makes the material relax.
std::unique_ptr<Subject> Explicit(ElementType element, PronySeries relaxation = {}) {
  auto s = std::make_unique<Subject>();
  s->name = std::string("explicit ") + ElementName(element);
  s->mesh = Box(element);
  s->material = MakeHyperelasticMaterial(NeoHookeanSpec());
  TledMaterial t;
  t.model = s->material;
  t.relaxation = relaxation;
  t.density = 1040;
  t.mu = t.model->ShearModulus();
  t.bulk = t.model->BulkModulus();
  t.neo_hookean = relaxation.g.empty();
  TledOptions options;
  options.average_nodal_pressure = element != ElementType::kTet4;
  options.bulk_viscosity_linear = options.bulk_viscosity_quadratic = 0;
  std::unique_ptr<TledModel> tled;
  const Status status =
      TledModel::Build(s->mesh, {t}, std::vector<int>(s->mesh.num_elements(), 0), options, &tled);
  EXPECT_TRUE(status.ok()) << status.message();
  tled->SetTimeStep(1e-4);
  s->body = std::move(tled);
  return s;
}

std::vector<std::unique_ptr<Subject>> Elastic() {
  std::vector<std::unique_ptr<Subject>> out;
  for (ElementType e : {ElementType::kTet4, ElementType::kTet4Anp, ElementType::kTet10,
                        ElementType::kTet10Md, ElementType::kHex8, ElementType::kHex8Full}) {
    out.push_back(Implicit(e));
  }
  for (ElementType e : {ElementType::kTet4, ElementType::kTet4Anp, ElementType::kHex8}) {
    out.push_back(Explicit(e));
  }
  return out;
}

TEST(DiscreteBodyTest, NoForceFromARigidMotion) {
  for (const auto& s : Elastic()) {
    Eigen::VectorXd f;
    const BodyForce r = s->body->Force(Rigid(s->mesh), nullptr, &f);
    ASSERT_TRUE(r.ok) << s->name;
    // Against the forces of a strain of a few per cent on the same body.
    Eigen::VectorXd strained;
    s->body->Force(Smooth(s->mesh), nullptr, &strained);
    EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-9 * strained.cwiseAbs().maxCoeff()) << s->name;
    EXPECT_GT(strained.cwiseAbs().maxCoeff(), 0) << s->name;
    EXPECT_NEAR(r.energy, 0, 1e-12) << s->name;
  }
}

TEST(DiscreteBodyTest, ForceIsTheGradientOfTheEnergy) {
  for (const auto& s : Elastic()) {
    const Eigen::VectorXd u = Smooth(s->mesh);
    const Eigen::VectorXd d = Smooth(s->mesh, 1.0).unaryExpr([](double x) { return x * x - 0.3; });
    Eigen::VectorXd f, unused;
    const BodyForce at = s->body->Force(u, nullptr, &f);
    ASSERT_TRUE(at.ok) << s->name;
    const double h = 1e-9;
    const BodyForce plus = s->body->Force(u + h * d, nullptr, &unused);
    const BodyForce minus = s->body->Force(u - h * d, nullptr, &unused);
    const double slope =
        (plus.energy + plus.hourglass_energy - minus.energy - minus.hourglass_energy) / (2 * h);
    EXPECT_NEAR(f.dot(d), slope, 1e-5 * std::abs(slope)) << s->name;
    EXPECT_GT(std::abs(slope), 0) << s->name;
  }
}

TEST(DiscreteBodyTest, ImplicitAndExplicitBodiesGiveTheSameForces) {
  for (ElementType e : {ElementType::kTet4, ElementType::kTet4Anp}) {
    const auto implicit = Implicit(e);
    const auto explicit_body = Explicit(e);
    const Eigen::VectorXd u = Smooth(implicit->mesh);
    Eigen::VectorXd a, b;
    const BodyForce ra = implicit->body->Force(u, nullptr, &a);
    const BodyForce rb = explicit_body->body->Force(u, nullptr, &b);
    ASSERT_TRUE(ra.ok && rb.ok) << ElementName(e);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-10 * a.cwiseAbs().maxCoeff()) << ElementName(e);
    EXPECT_NEAR(ra.energy, rb.energy, 1e-10 * ra.energy) << ElementName(e);
  }
}

TEST(DiscreteBodyTest, EveryBodyRecoversUndeformedFieldsFromARigidMotion) {
  for (const auto& s : Elastic()) {
    const Eigen::VectorXd u = Rigid(s->mesh);
    if (auto* tled = dynamic_cast<TledModel*>(s->body.get())) tled->RecordStress(true);
    Eigen::VectorXd f;
    ASSERT_TRUE(s->body->Force(u, nullptr, &f).ok) << s->name;
    Solution solution;
    const double largest = s->body->RecoverFields(u, &solution);
    const std::size_t ne = s->mesh.num_elements();
    ASSERT_EQ(solution.strain.size(), 6 * ne) << s->name;
    ASSERT_EQ(solution.jacobian.size(), ne) << s->name;
    EXPECT_LT(largest, 1e-12) << s->name;
    for (std::size_t e = 0; e < ne; ++e) {
      ASSERT_NEAR(solution.jacobian[e], 1, 1e-12) << s->name;
      ASSERT_NEAR(solution.von_mises_pa[e], 0, 1e-6) << s->name;
    }
  }
}

TEST(DiscreteBodyTest, ImplicitAndExplicitBodiesRecoverTheSameFields) {
  for (ElementType e : {ElementType::kTet4, ElementType::kTet4Anp}) {
    const auto implicit = Implicit(e);
    const auto explicit_body = Explicit(e);
    const Eigen::VectorXd u = Smooth(implicit->mesh);
    static_cast<TledModel*>(explicit_body->body.get())->RecordStress(true);
    Eigen::VectorXd f;
    ASSERT_TRUE(explicit_body->body->Force(u, nullptr, &f).ok);
    Solution a, b;
    const double largest_a = implicit->body->RecoverFields(u, &a);
    const double largest_b = explicit_body->body->RecoverFields(u, &b);
    EXPECT_NEAR(largest_a, largest_b, 1e-12) << ElementName(e);
    EXPECT_GT(largest_a, 1e-3) << ElementName(e);  // strains of a few per cent
    double stress_scale = 0;
    for (double v : a.stress_pa) stress_scale = std::max(stress_scale, std::abs(v));
    ASSERT_EQ(a.stress_pa.size(), b.stress_pa.size());
    for (std::size_t k = 0; k < a.stress_pa.size(); ++k) {
      ASSERT_NEAR(a.strain[k], b.strain[k], 1e-12) << ElementName(e) << " " << k;
      ASSERT_NEAR(a.stress_pa[k], b.stress_pa[k], 1e-9 * stress_scale)
          << ElementName(e) << " " << k;
    }
  }
}

TEST(DiscreteBodyTest, OnlyTheImplicitBodiesHaveATangentOnlyTheExplicitAMass) {
  const auto implicit = Implicit(ElementType::kTet4Anp);
  const auto explicit_body = Explicit(ElementType::kTet4Anp);
  EXPECT_TRUE(implicit->body->has_tangent());
  EXPECT_FALSE(explicit_body->body->has_tangent());
  EXPECT_FALSE(implicit->body->advances_on_evaluation());
  EXPECT_TRUE(explicit_body->body->advances_on_evaluation());
  EXPECT_EQ(implicit->body->LumpedMass().size(), 0);
  // rho V of the 3 x 3 x 4 mm box.
  EXPECT_NEAR(explicit_body->body->LumpedMass().sum(), 1040 * 36e-9, 1e-12 * 1040 * 36e-9);
  DofMap dofs(implicit->mesh.num_nodes());
  LinearSystem system;
  const Status none = explicit_body->body->Assemble(Smooth(explicit_body->mesh), dofs, {}, &system);
  EXPECT_EQ(none.code(), Status::Code::kFailedPrecondition);
  EXPECT_NE(none.message().find("no tangent"), std::string::npos) << none.message();
}

TEST(DiscreteBodyTest, ExplicitHistoryRestoresToTheSameForces) {
  const PronySeries series{{0.5, 0.2}, {1e-3, 5e-2}};
  auto first = Explicit(ElementType::kTet4Anp, series);
  auto second = Explicit(ElementType::kTet4Anp, series);
  Eigen::VectorXd f;
  for (int n = 1; n <= 3; ++n) first->body->Force(Smooth(first->mesh, n * 5e-5), nullptr, &f);
  const std::vector<double> saved = first->body->SaveHistory();
  ASSERT_FALSE(saved.empty());
  ASSERT_TRUE(second->body->RestoreHistory(saved).ok());
  Eigen::VectorXd a, b;
  first->body->Force(Smooth(first->mesh, 2e-4), nullptr, &a);
  second->body->Force(Smooth(second->mesh, 2e-4), nullptr, &b);
  EXPECT_EQ(a, b);
  // A fresh body (no history) answers differently: the history matters.
  auto fresh = Explicit(ElementType::kTet4Anp, series);
  Eigen::VectorXd c;
  fresh->body->Force(Smooth(fresh->mesh, 2e-4), nullptr, &c);
  EXPECT_GT((a - c).cwiseAbs().maxCoeff(), 1e-6 * a.cwiseAbs().maxCoeff());
  const Status wrong = second->body->RestoreHistory(std::vector<double>(saved.size() - 6, 0.0));
  EXPECT_FALSE(wrong.ok());
  EXPECT_EQ(wrong.field(), "history");
  EXPECT_NE(wrong.message().find("keeps"), std::string::npos) << wrong.message();
}

TEST(DiscreteBodyTest, ImplicitHistoryIsTheMaterialFieldsCommittedAtTheEndOfAStep) {
  Mesh mesh = Box(ElementType::kTet4Anp);
  MaterialField::Entry entry;
  entry.material = MakeHyperelasticMaterial(NeoHookeanSpec());
  entry.relaxation = PronySeries{{0.4}, {0.1}};
  std::vector<MaterialField::Entry> entries = {entry};
  MaterialField field(entries, std::vector<int>(mesh.num_elements(), 0), ThreadContext());
  auto body = MakeAverageNodalPressureTet4Model(mesh, field, ThreadContext());
  const std::vector<double> before = body->SaveHistory();
  EXPECT_TRUE(before.empty());  // not attached: no history of its own
  body->KeepHistoryIn(&field, &mesh, ThreadContext());
  field.BeginStep(0.01, 1);
  const Eigen::VectorXd u = Smooth(mesh);
  Eigen::VectorXd f;
  ASSERT_TRUE(body->Force(u, nullptr, &f).ok);
  const std::vector<double> trial = body->SaveHistory();
  for (double v : trial) ASSERT_EQ(v, 0.0);  // a trial moves nothing
  body->CommitHistory(u);
  const std::vector<double> committed = body->SaveHistory();
  ASSERT_EQ(committed.size(), trial.size());
  EXPECT_EQ(committed, field.SaveHistory());
  double largest = 0;
  for (double v : committed) largest = std::max(largest, std::abs(v));
  EXPECT_GT(largest, 1.0);  // Pa: the committed S_iso of a strained body
  EXPECT_FALSE(body->RestoreHistory({1, 2, 3}).ok());
}

}  // namespace
}  // namespace pba
