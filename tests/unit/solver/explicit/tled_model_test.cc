// The TLED internal force against a plain element-by-element evaluation
// written from the formulas of tled_model.h (F, average nodal pressure per
// (node, material), bulk viscosity, P through the material's isochoric
// stress, the hexahedra's hourglass forces), on meshes of two materials, a
// neo-Hookean one (the kernel's closed form) and a Mooney-Rivlin one (its
// general path); and the forces the same on 1 and 2 threads, bit for bit.
#include "explicit/tled_model.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "fem/hex8.h"
#include "fem/tet4.h"
#include "material/factory.h"
#include "mesh/primitive_mesher.h"

namespace pba {
namespace {

constexpr double kC1 = 0.06, kC2 = 1.5, kHourglass = 0.05;

Mesh Cube(ElementType element) {
  GeometrySpec g;
  g.kind = GeometrySpec::Kind::kBox;
  g.box.size_mm = {3, 3, 4};
  MeshSpec m;
  m.element = element;
  m.element_size_mm = 1;
  MeshStats stats;
  return BuildPrimitiveMesh(g, m, &stats);
}

std::vector<TledMaterial> Materials() {
  MaterialSpec neo;
  neo.kind = MaterialSpec::Kind::kNeoHookean;
  neo.neo_hookean = {1000, 2e5};
  MaterialSpec mr;
  mr.kind = MaterialSpec::Kind::kMooneyRivlin;
  mr.mooney_rivlin = {300, 200, 5e4};
  std::vector<TledMaterial> out;
  for (const MaterialSpec* spec : {&neo, &mr}) {
    TledMaterial t;
    t.model = MakeHyperelasticMaterial(*spec);
    t.density = 1040;
    t.mu = t.model->ShearModulus();
    t.bulk = t.model->BulkModulus();
    t.neo_hookean = spec == &neo;
    out.push_back(std::move(t));
  }
  return out;
}

// A smooth displacement (strains of several per cent) and a velocity that
// compresses some elements and stretches others.
void State(const Mesh& mesh, Eigen::VectorXd* u, Eigen::VectorXd* v) {
  u->resize(3 * mesh.num_nodes());
  v->resize(3 * mesh.num_nodes());
  for (int n = 0; n < mesh.num_nodes(); ++n) {
    const Eigen::Vector3d x = mesh.nodes.row(n).transpose() / 4e-3;
    for (int i = 0; i < 3; ++i) {
      (*u)(3 * n + i) = 2e-4 * std::sin(3 * x(i) + x((i + 1) % 3));
      (*v)(3 * n + i) = 2 * std::cos(4 * x((i + 2) % 3) + i);
    }
  }
}

Eigen::MatrixXd Corners(const Mesh& mesh, int e) {
  if (mesh.hexahedral()) return HexCorners(mesh, e);
  return TetCorners(mesh, e);
}

// The smallest altitude 3V / A_max (tetrahedron) or V / A_max (brick).
double Length(const Eigen::MatrixXd& x, double volume) {
  double area = 0;
  if (x.rows() == 4) {
    const int faces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
    for (const auto& f : faces) {
      const Eigen::Vector3d a = (x.row(f[1]) - x.row(f[0])).transpose();
      const Eigen::Vector3d b = (x.row(f[2]) - x.row(f[0])).transpose();
      area = std::max(area, 0.5 * a.cross(b).norm());
    }
    return 3 * volume / area;
  }
  const int faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                           {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};
  for (const auto& f : faces) {
    const Eigen::Vector3d d1 = (x.row(f[2]) - x.row(f[0])).transpose();
    const Eigen::Vector3d d2 = (x.row(f[3]) - x.row(f[1])).transpose();
    area = std::max(area, 0.5 * d1.cross(d2).norm());
  }
  return volume / area;
}

struct Reference {
  Eigen::VectorXd force;
  std::vector<Eigen::Matrix3d> f;
  std::vector<double> pressure;
  std::vector<Eigen::Matrix3d> stress;  // Cauchy, without the viscosity
  double hourglass_energy = 0;
};

Reference Evaluate(const TledModel& t, const Mesh& mesh, const std::vector<TledMaterial>& mats,
                   const std::vector<int>& material_of, bool anp, const Eigen::VectorXd& u,
                   const Eigen::VectorXd& v) {
  const int ne = mesh.num_elements(), npe = t.nodes_per_element();
  std::vector<Eigen::MatrixXd> grad(ne);
  std::vector<double> volume(ne), j(ne);
  Reference r;
  r.f.resize(ne);
  r.pressure.assign(ne, 0);
  r.stress.assign(ne, Eigen::Matrix3d::Zero());
  r.force = Eigen::VectorXd::Zero(3 * mesh.num_nodes());
  for (int e = 0; e < ne; ++e) {
    const Eigen::MatrixXd x = Corners(mesh, e);
    if (npe == 4) {
      const Tet4Geometry g = ComputeTet4Geometry(x);
      grad[e] = g.grad, volume[e] = g.volume;
    } else {
      const Hex8Geometry g = ComputeHex8Geometry(x);
      grad[e] = g.mean_grad, volume[e] = g.element_volume;
    }
    Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
    for (int a = 0; a < npe; ++a) {
      f += u.segment<3>(3 * t.element_nodes(e)[a]) * grad[e].row(a);
    }
    r.f[e] = f;
    j[e] = f.determinant();
  }
  // J_n per (node, material); an eroded element's V0 J stays frozen at its
  // value when it went (here before any evaluation: J = 1).
  std::map<std::pair<int, int>, std::pair<double, double>> groups;
  for (int e = 0; e < ne; ++e) {
    for (int a = 0; a < npe; ++a) {
      auto& g = groups[{t.element_nodes(e)[a], material_of[e]}];
      g.first += volume[e] * (t.eroded(e) ? 1.0 : j[e]), g.second += volume[e];
    }
  }
  for (int e = 0; e < ne; ++e) {
    if (t.eroded(e)) continue;
    const TledMaterial& m = mats[material_of[e]];
    const Eigen::Matrix3d& f = r.f[e];
    const Eigen::Matrix3d cof = j[e] * f.inverse().transpose();
    double p = 0;
    if (anp) {
      for (int a = 0; a < npe; ++a) {
        const auto& g = groups[{t.element_nodes(e)[a], material_of[e]}];
        p += m.model->Volumetric(g.first / g.second).first / npe;
      }
    } else {
      p = m.model->Volumetric(j[e]).first;
    }
    Eigen::Matrix3d fdot = Eigen::Matrix3d::Zero();
    for (int a = 0; a < npe; ++a) {
      fdot += v.segment<3>(3 * t.element_nodes(e)[a]) * grad[e].row(a);
    }
    const double rate = (fdot.array() * cof.array()).sum() / j[e];
    double q = 0;
    if (rate < 0) {
      const double l = Length(Corners(mesh, e), volume[e]) * std::cbrt(j[e]);
      q = m.density * l * (kC2 * l * rate * rate - kC1 * m.WaveSpeed() * rate);
    }
    Vector6d s_iso;
    m.model->Isochoric(f, nullptr, &s_iso, nullptr);
    const Eigen::Matrix3d pk = f * VoigtToSymmetric(s_iso) + (p - q) * cof;
    r.pressure[e] = -(pk.array() * f.array()).sum() / (3 * j[e]) - q;
    r.stress[e] = pk * f.transpose() / j[e] + q * Eigen::Matrix3d::Identity();
    Eigen::MatrixXd fe = volume[e] * grad[e] * pk.transpose();  // npe x 3
    if (npe == 8) {
      // Flanagan-Belytschko: gamma = (h - (h . X) b) / 8.
      const Eigen::MatrixXd x = Corners(mesh, e);
      Eigen::Matrix<double, 8, 4> h, gamma;
      for (int a = 0; a < 8; ++a) {
        const double* n = kHex8NodeNatural[a];
        h.row(a) << n[0] * n[1], n[1] * n[2], n[2] * n[0], n[0] * n[1] * n[2];
      }
      gamma = (h - grad[e] * (x.transpose() * h)) / 8;
      const double k = kHourglass * (m.bulk + 4 * m.mu / 3) * volume[e] * grad[e].squaredNorm();
      Eigen::Matrix<double, 8, 3> ue;
      for (int a = 0; a < 8; ++a) ue.row(a) = u.segment<3>(3 * t.element_nodes(e)[a]);
      const Eigen::Matrix<double, 4, 3> hq = gamma.transpose() * ue;
      r.hourglass_energy += 0.5 * k * hq.squaredNorm();
      fe += k * gamma * hq;
    }
    for (int a = 0; a < npe; ++a) {
      r.force.segment<3>(3 * t.element_nodes(e)[a]) += fe.row(a).transpose();
    }
  }
  return r;
}

void Check(ElementType element, bool erode) {
  const Mesh mesh = Cube(element);
  const std::vector<TledMaterial> mats = Materials();
  std::vector<int> material_of(mesh.num_elements());
  // Runs of 16: whole blocks of one material (the neo-Hookean blocks take
  // the kernel's blocked path) and nodes shared by both.
  for (int e = 0; e < mesh.num_elements(); ++e) material_of[e] = (e / 16) % 2;
  TledOptions options;
  options.average_nodal_pressure = element == ElementType::kTet4Anp;
  options.bulk_viscosity_linear = kC1;
  options.bulk_viscosity_quadratic = kC2;
  options.hourglass = kHourglass;
  std::unique_ptr<TledModel> t;
  ASSERT_TRUE(TledModel::Build(mesh, mats, material_of, options, &t).ok());
  if (erode) {
    for (int e = 3; e < mesh.num_elements(); e += 11) t->Erode(e);
  }
  Eigen::VectorXd u, v, f1, f2;
  State(mesh, &u, &v);
  t->SetThreads(ThreadContext(1));
  const TledEvaluation e1 = t->InternalForce(u, v, &f1);
  t->SetThreads(ThreadContext(2));
  const TledEvaluation e2 = t->InternalForce(u, v, &f2);
  EXPECT_EQ(e1.inverted_element, -1);
  // The same sums in the same order on any number of threads.
  for (Eigen::Index i = 0; i < f1.size(); ++i) ASSERT_EQ(f1(i), f2(i)) << i;
  // The energy is summed per thread, then over the threads: to rounding.
  EXPECT_NEAR(e1.hourglass_energy, e2.hourglass_energy, 1e-14 * e1.hourglass_energy);
  // Recording the stress takes the element-by-element path: the same forces.
  Eigen::VectorXd f3;
  t->RecordStress(true);
  t->InternalForce(u, v, &f3);
  for (Eigen::Index i = 0; i < f1.size(); ++i) ASSERT_EQ(f1(i), f3(i)) << i;

  const Reference r = Evaluate(*t, mesh, mats, material_of, options.average_nodal_pressure, u, v);
  const double scale = r.force.cwiseAbs().maxCoeff();
  ASSERT_GT(scale, 0);
  EXPECT_LT((f1 - r.force).cwiseAbs().maxCoeff(), 1e-12 * scale);
  EXPECT_NEAR(e1.hourglass_energy, r.hourglass_energy, 1e-12 * r.hourglass_energy + 1e-300);
  if (element == ElementType::kHex8) {
    EXPECT_GT(r.hourglass_energy, 0);
  }
  double p_scale = 0;
  for (int e = 0; e < mesh.num_elements(); ++e)
    p_scale = std::max(p_scale, std::abs(r.pressure[e]));
  for (int e = 0; e < mesh.num_elements(); ++e) {
    EXPECT_LT((t->DeformationGradient(e) - r.f[e]).cwiseAbs().maxCoeff(), 1e-14) << e;
    if (t->eroded(e)) continue;
    EXPECT_NEAR(t->pressure(e), r.pressure[e], 1e-12 * p_scale) << e;
    const Vector6d s = t->CauchyStress(e);
    const Eigen::Matrix3d& rs = r.stress[e];
    const Vector6d expected =
        (Vector6d() << rs(0, 0), rs(1, 1), rs(2, 2), rs(1, 2), rs(0, 2), rs(0, 1)).finished();
    EXPECT_LT((s - expected).cwiseAbs().maxCoeff(), 1e-12 * p_scale) << e;
  }
}

TEST(TledModel, Tet4AnpForcesAreThoseOfTheFormulas) { Check(ElementType::kTet4Anp, false); }
TEST(TledModel, Tet4ForcesAreThoseOfTheFormulas) { Check(ElementType::kTet4, false); }
TEST(TledModel, Hex8ForcesAreThoseOfTheFormulas) { Check(ElementType::kHex8, false); }
TEST(TledModel, ErodedElementsLeaveTheForcesAndFreezeTheirNodalVolumes) {
  Check(ElementType::kTet4Anp, true);
  Check(ElementType::kHex8, true);
}

}  // namespace
}  // namespace pba
