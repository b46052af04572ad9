#include "explicit/tled_model.h"

#include <omp.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/element_fields.h"
#include "core/format.h"
#include "explicit/cube_root.h"
#include "fem/hex8.h"
#include "fem/tet4.h"
#include "material/material_point.h"

namespace pba {
namespace {

// Faces of a tetrahedron (corner indices) and of a hexahedron (C3D8 order).
constexpr int kTetFaces[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
constexpr int kHexFaces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                 {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}};

// Characteristic length of an element with corners `x` (rows) and volume
// `volume`: the smallest altitude 3V / A_max of a tetrahedron, V / A_max of
// a hexahedron (a quad's area as half its diagonals' cross product).
template <int N>
double CharacteristicLength(const Eigen::Matrix<double, N, 3>& x, double volume) {
  double max_area = 0;
  if constexpr (N == 4) {
    for (const auto& f : kTetFaces) {
      const Eigen::Vector3d a = x.row(f[1]) - x.row(f[0]), b = x.row(f[2]) - x.row(f[0]);
      max_area = std::max(max_area, 0.5 * a.cross(b).norm());
    }
    return 3 * volume / max_area;
  } else {
    for (const auto& f : kHexFaces) {
      const Eigen::Vector3d d1 = x.row(f[2]) - x.row(f[0]), d2 = x.row(f[3]) - x.row(f[1]);
      max_area = std::max(max_area, 0.5 * d1.cross(d2).norm());
    }
    return volume / max_area;
  }
}

}  // namespace

double TledMaterial::WaveSpeed() const { return std::sqrt((bulk + 4 * mu / 3) / density); }

Status TledModel::Build(const Mesh& mesh, std::vector<TledMaterial> materials,
                        std::vector<int> material_of, const TledOptions& options,
                        std::unique_ptr<TledModel>* out) {
  // A scene's validation refuses both (scene_checks::ValidateExplicit).
  if (mesh.shape() == ElementShape::kTet10) {
    return Status::Internal(
        "the explicit engine takes 4-node tetrahedra or 8-node hexahedra, not 10-node tetrahedra");
  }
  for (std::size_t m = 0; m < materials.size(); ++m) {
    if (!(materials[m].density > 0)) {
      return Status::Internal("the explicit engine was given material " + materials[m].name +
                              ", which has no density");
    }
  }
  std::unique_ptr<TledModel> model(new TledModel());
  TledModel& t = *model;
  t.mesh_ = &mesh;
  t.options_ = options;
  t.materials_ = std::move(materials);
  t.material_of_ = std::move(material_of);
  t.num_nodes_ = mesh.num_nodes();
  t.num_elements_ = mesh.num_elements();
  const int ne = t.num_elements_;
  const bool hex = mesh.shape() == ElementShape::kHex8;
  t.npe_ = hex ? 8 : 4;
  const int npe = t.npe_;
  t.anp_ = !hex && options.average_nodal_pressure;
  t.conn_.resize(static_cast<std::size_t>(npe) * ne);
  t.grad_.resize(static_cast<std::size_t>(3 * npe) * ne);
  t.volume_.resize(ne);
  t.length_.resize(ne);
  t.mass_ = Eigen::VectorXd::Zero(t.num_nodes_);
  if (hex) {
    t.gamma_.resize(32 * static_cast<std::size_t>(ne));
    t.hourglass_k_.resize(ne);
  }
  // Hourglass base vectors at the nodes: xi eta, eta zeta, zeta xi, xi eta zeta.
  double h[8][4];
  for (int a = 0; a < 8; ++a) {
    const double r = kHex8NodeNatural[a][0], s = kHex8NodeNatural[a][1], z = kHex8NodeNatural[a][2];
    h[a][0] = r * s, h[a][1] = s * z, h[a][2] = z * r, h[a][3] = r * s * z;
  }
  for (int e = 0; e < ne; ++e) {
    double volume = 0;
    if (hex) {
      const Hex8Nodes x = HexCorners(mesh, e);
      const Hex8Geometry g = ComputeHex8Geometry(x);
      volume = g.element_volume;
      if (!(g.min_jacobian > 0)) {
        return Status::FailedPrecondition(
            "mesh",
            Format("hexahedron %d is inverted or degenerate (det J %g)", e, g.min_jacobian));
      }
      for (int a = 0; a < 8; ++a) {
        t.conn_[8 * e + a] = mesh.hexes[e][a];
        for (int j = 0; j < 3; ++j) t.grad_[24 * e + 3 * a + j] = g.mean_grad(a, j);
      }
      t.length_[e] = CharacteristicLength<8>(x, volume);
      // gamma_{a alpha} = (h_{a alpha} - sum_b h_{b alpha} X_bi b_ai) / 8.
      for (int alpha = 0; alpha < 4; ++alpha) {
        Eigen::Vector3d hx = Eigen::Vector3d::Zero();
        for (int b = 0; b < 8; ++b) hx += h[b][alpha] * x.row(b).transpose();
        for (int a = 0; a < 8; ++a) {
          t.gamma_[32 * e + 4 * a + alpha] = (h[a][alpha] - hx.dot(g.mean_grad.row(a))) / 8;
        }
      }
      const TledMaterial& m = t.materials_[t.material_of_[e]];
      t.hourglass_k_[e] =
          options.hourglass * (m.bulk + 4 * m.mu / 3) * volume * g.mean_grad.squaredNorm();
    } else {
      const Eigen::Matrix<double, 4, 3> x = TetCorners(mesh, e);
      const Tet4Geometry g = ComputeTet4Geometry(x);
      volume = g.volume;
      if (!(volume > 0)) {
        return Status::FailedPrecondition(
            "mesh", Format("tetrahedron %d is inverted or degenerate (volume %g m^3)", e, volume));
      }
      for (int a = 0; a < 4; ++a) {
        t.conn_[4 * e + a] = mesh.tets[e][a];
        for (int j = 0; j < 3; ++j) t.grad_[12 * e + 3 * a + j] = g.grad(a, j);
      }
      t.length_[e] = CharacteristicLength<4>(x, volume);
    }
    t.volume_[e] = volume;
    const double corner_mass = t.materials_[t.material_of_[e]].density * volume / npe;
    for (int a = 0; a < npe; ++a) t.mass_(t.conn_[npe * e + a]) += corner_mass;
  }
  // Node-to-corner lists.
  t.node_start_.assign(t.num_nodes_ + 1, 0);
  for (int c = 0; c < npe * ne; ++c) ++t.node_start_[t.conn_[c] + 1];
  for (int n = 0; n < t.num_nodes_; ++n) t.node_start_[n + 1] += t.node_start_[n];
  t.node_corner_.resize(static_cast<std::size_t>(npe) * ne);
  {
    std::vector<int> next(t.node_start_.begin(), t.node_start_.end() - 1);
    for (int c = 0; c < npe * ne; ++c) t.node_corner_[next[t.conn_[c]]++] = c;
  }
  // Nodal groups of one material each (average nodal pressure).
  if (t.anp_) {
    t.corner_group_.assign(static_cast<std::size_t>(npe) * ne, -1);
    std::vector<std::vector<int>> members;
    for (int n = 0; n < t.num_nodes_; ++n) {
      const int first = static_cast<int>(members.size());
      for (int k = t.node_start_[n]; k < t.node_start_[n + 1]; ++k) {
        const int c = t.node_corner_[k];
        const int m = t.material_of_[c / npe];
        int g = first;
        while (g < static_cast<int>(members.size()) && t.group_material_[g] != m) ++g;
        if (g == static_cast<int>(members.size())) {
          members.emplace_back();
          t.group_material_.push_back(m);
        }
        members[g].push_back(c);
        t.corner_group_[c] = g;
      }
    }
    t.group_start_.assign(1, 0);
    for (const std::vector<int>& g : members) {
      for (int c : g) t.group_element_.push_back(c / npe);
      t.group_start_.push_back(static_cast<int>(t.group_element_.size()));
    }
    t.group_pressure_.assign(members.size(), 0.0);
    t.group_volume_.assign(members.size(), 0.0);
    for (int g = 0; g < static_cast<int>(members.size()); ++g) t.SumGroupVolume(g);
    t.volume_ratio_ = t.volume_;  // J = 1 until evaluated
  }
  for (const TledMaterial& m : t.materials_) t.wave_speed_.push_back(m.WaveSpeed());
  // Relaxation history.
  t.history_start_.assign(ne, -1);
  std::size_t history = 0;
  for (int e = 0; e < ne; ++e) {
    const std::size_t terms = t.materials_[t.material_of_[e]].relaxation.g.size();
    if (terms == 0) continue;
    t.history_start_[e] = static_cast<int>(history);
    history += 6 * (terms + 1);
  }
  t.history_.assign(history, 0.0);
  t.steps_.resize(t.materials_.size());
  t.f_.assign(9 * static_cast<std::size_t>(ne), 0.0);
  for (int e = 0; e < ne; ++e) t.f_[9 * e] = t.f_[9 * e + 4] = t.f_[9 * e + 8] = 1;
  t.j_.assign(ne, 1.0);
  t.pressure_.assign(ne, 0.0);
  t.force_.assign(static_cast<std::size_t>(3 * npe) * ne, 0.0);
  *out = std::move(model);
  return Status::Ok();
}

double TledModel::ElementStableStep(int e, const Eigen::VectorXd* u, const Eigen::VectorXd* v,
                                    double* length) const {
  const double c1 = options_.bulk_viscosity_linear, c2 = options_.bulk_viscosity_quadratic;
  double l = length_[e];
  if (u != nullptr) {
    // The current length, from the current corners.
    if (npe_ == 4) {
      Eigen::Matrix<double, 4, 3> x;
      for (int a = 0; a < 4; ++a) {
        const int n = conn_[4 * e + a];
        x.row(a) = mesh_->nodes.row(n) + u->segment<3>(3 * n).transpose();
      }
      l = CharacteristicLength<4>(x, j_[e] * volume_[e]);
    } else {
      Eigen::Matrix<double, 8, 3> x;
      for (int a = 0; a < 8; ++a) {
        const int n = conn_[8 * e + a];
        x.row(a) = mesh_->nodes.row(n) + u->segment<3>(3 * n).transpose();
      }
      l = CharacteristicLength<8>(x, j_[e] * volume_[e]);
    }
  }
  const double c = material(e).WaveSpeed() * (speed_scale_.empty() ? 1.0 : speed_scale_[e]);
  double q = 0;
  if (v != nullptr) {
    // tr D = dJ/dt / J = (dF/dt : cof F) / J.
    const double* g = &grad_[3 * npe_ * static_cast<std::size_t>(e)];
    double fdot[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    for (int a = 0; a < npe_; ++a) {
      const int n = conn_[npe_ * e + a];
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) fdot[3 * i + j] += (*v)(3 * n + i) * g[3 * a + j];
      }
    }
    double cof[9];
    Cofactor(&f_[9 * static_cast<std::size_t>(e)], cof);
    double rate = 0;
    for (int k = 0; k < 9; ++k) rate += fdot[k] * cof[k];
    rate /= j_[e];
    if (rate < 0) q = c1 * c + c2 * l * -rate;
  }
  *length = l;
  return q > 0 ? l / (q + std::sqrt(q * q + c * c)) : l / c;
}

double TledModel::StableTimeStep(const Eigen::VectorXd* u, const Eigen::VectorXd* v, int* element,
                                 double* length) const {
  double best = std::numeric_limits<double>::infinity();
  int best_e = -1;
  double best_l = 0;
#pragma omp parallel num_threads(options_.threads.threads())
  {
    double local = std::numeric_limits<double>::infinity();
    int local_e = -1;
    double local_l = 0;
#pragma omp for schedule(static) nowait
    for (int e = 0; e < num_elements_; ++e) {
      if (eroded(e)) continue;
      double l = 0;
      const double dt = ElementStableStep(e, u, v, &l);
      if (!(dt >= local)) {
        local = dt, local_e = e, local_l = l;
      }
    }
#pragma omp critical
    if (local < best || (local == best && local_e < best_e)) {
      best = local, best_e = local_e, best_l = local_l;
    }
  }
  if (element != nullptr) *element = best_e;
  if (length != nullptr) *length = best_l;
  return best;
}

TledModel::MassScaling TledModel::RescaleMass(const Eigen::VectorXd& u, Eigen::VectorXd* v,
                                              double min_stable_step, double* stable_step,
                                              int* element, double* length) {
  MassScaling out;
  if (speed_scale_.empty()) speed_scale_.assign(num_elements_, 1.0);
  std::vector<double> steps(num_elements_, std::numeric_limits<double>::infinity());
#pragma omp parallel for schedule(static) num_threads(options_.threads.threads())
  for (int e = 0; e < num_elements_; ++e) {
    if (eroded(e)) continue;
    double l = 0;
    steps[e] = ElementStableStep(e, &u, v, &l);
  }
  for (int e = 0; e < num_elements_; ++e) {
    // A thousandth of slack, so that an element does not take mass for
    // every rounding of its step.
    if (!(steps[e] < min_stable_step * (1 - 1e-3))) continue;
    // The step scales as 1 / c, so as sqrt(rho): rho' = rho (min / step)^2
    // (the bulk viscosity's share of the step taken along, a little more).
    const double ratio = min_stable_step / steps[e];
    const double mass = material(e).density * volume_[e] / (speed_scale_[e] * speed_scale_[e]);
    const double added = mass * (ratio * ratio - 1);
    for (int a = 0; a < npe_; ++a) {
      // The node keeps its momentum: m v = (m + dm) v'. Its kinetic energy
      // falls by m dm / (m + dm) |v|^2 / 2, as in a plastic collision.
      const int n = conn_[npe_ * static_cast<std::size_t>(e) + a];
      const double m = mass_(n), dm = added / npe_;
      const Eigen::Vector3d before = v->segment<3>(3 * n);
      v->segment<3>(3 * n) = before * (m / (m + dm));
      mass_(n) += dm;
      out.added_kinetic +=
          0.5 * (m + dm) * v->segment<3>(3 * n).squaredNorm() - 0.5 * m * before.squaredNorm();
    }
    speed_scale_[e] /= ratio;
    out.added_mass += added;
    ++out.elements;
    // Its step now (the bulk viscosity's share does not scale with c).
    double l = 0;
    steps[e] = ElementStableStep(e, &u, v, &l);
  }
  // The smallest step after the scaling, as StableTimeStep would find it.
  *stable_step = std::numeric_limits<double>::infinity();
  *element = -1;
  for (int e = 0; e < num_elements_; ++e) {
    if (steps[e] < *stable_step) *stable_step = steps[e], *element = e;
  }
  *length = 0;
  if (*element >= 0) ElementStableStep(*element, &u, v, length);
  return out;
}

TledModel::MassScaling TledModel::ScaleMass(double min_stable_step) {
  MassScaling out;
  for (int e = 0; e < num_elements_; ++e) out.model_mass += material(e).density * volume_[e];
  speed_scale_.assign(num_elements_, 1.0);
  for (int e = 0; e < num_elements_; ++e) {
    const double step = length_[e] / material(e).WaveSpeed();
    if (step >= min_stable_step) continue;
    // rho' = rho (min / step)^2 makes l / c' = min.
    const double ratio = min_stable_step / step;
    const double added = material(e).density * volume_[e] * (ratio * ratio - 1);
    for (int a = 0; a < npe_; ++a)
      mass_(conn_[npe_ * static_cast<std::size_t>(e) + a]) += added / npe_;
    speed_scale_[e] = 1 / ratio;
    out.added_mass += added;
    ++out.elements;
  }
  return out;
}

void TledModel::SetTimeStep(double dt) {
  dt_ = dt;
  for (std::size_t m = 0; m < materials_.size(); ++m) {
    if (!materials_[m].relaxation.g.empty()) {
      steps_[m] = ViscousStep::Of(materials_[m].relaxation, dt);
    }
  }
}

void TledModel::SumGroupVolume(int g) {
  double sum_v = 0;
  for (int k = group_start_[g]; k < group_start_[g + 1]; ++k) {
    const int e = group_element_[k];
    if (!eroded(e)) sum_v += volume_[e];
  }
  group_volume_[g] = sum_v;
}

void TledModel::VolumeRatios(const Eigen::VectorXd& u) {
  const double* ud = u.data();
#pragma omp for schedule(static)
  for (int e = 0; e < num_elements_; ++e) {
    // An eroded element keeps the V0 J it had when it went (see Erode).
    if (eroded(e)) continue;
    // Four corners: F as in ElementForces<4>, in the same order.
    const int* nodes = &conn_[4 * static_cast<std::size_t>(e)];
    const double* g = &grad_[12 * static_cast<std::size_t>(e)];
    double f[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int a = 0; a < 4; ++a) {
      const double* ua = ud + 3 * nodes[a];
      const double* ga = g + 3 * a;
      for (int i = 0; i < 3; ++i) {
        f[3 * i + 0] += ua[i] * ga[0];
        f[3 * i + 1] += ua[i] * ga[1];
        f[3 * i + 2] += ua[i] * ga[2];
      }
    }
    volume_ratio_[e] = volume_[e] * Determinant(f);
  }
}

void TledModel::AverageNodalPressure() {
  const int groups = static_cast<int>(group_pressure_.size());
#pragma omp for schedule(static)
  for (int g = 0; g < groups; ++g) {
    const double sum_v = group_volume_[g];
    if (sum_v == 0) {
      group_pressure_[g] = 0;
      continue;
    }
    double sum_vj = 0;
    for (int k = group_start_[g]; k < group_start_[g + 1]; ++k) {
      const int e = group_element_[k];
      sum_vj += volume_ratio_[e];
    }
    const double j = sum_vj / sum_v;
    const TledMaterial& m = materials_[group_material_[g]];
    group_pressure_[g] = m.neo_hookean ? m.bulk * (j - 1) : m.model->Volumetric(j).first;
  }
}

// The hourglass forces of brick e, added to its buffer `force`, and their
// energy to *hourglass.
void TledModel::HourglassForces(int e, const double* ud, double* force, double* hourglass) const {
  const double* gamma = &gamma_[32 * static_cast<std::size_t>(e)];
  double hq[4][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  for (int a = 0; a < 8; ++a) {
    const double* ua = ud + 3 * conn_[8 * static_cast<std::size_t>(e) + a];
    for (int alpha = 0; alpha < 4; ++alpha) {
      for (int i = 0; i < 3; ++i) hq[alpha][i] += gamma[4 * a + alpha] * ua[i];
    }
  }
  const double k = hourglass_k_[e];
  double sq = 0;
  for (int alpha = 0; alpha < 4; ++alpha) {
    for (int i = 0; i < 3; ++i) sq += hq[alpha][i] * hq[alpha][i];
  }
  *hourglass += 0.5 * k * sq;
  for (int a = 0; a < 8; ++a) {
    for (int i = 0; i < 3; ++i) {
      double sum = 0;
      for (int alpha = 0; alpha < 4; ++alpha) sum += gamma[4 * a + alpha] * hq[alpha][i];
      force[3 * a + i] += k * sum;
    }
  }
}

// One element, any material: F and J (stored), stress, pressure and the
// force buffer; an eroded or inverted element gets no forces.
template <int kNpe>
void TledModel::ElementForce(int e, const double* ud, const double* vd, double* hourglass,
                             int* inverted) {
  const double c1 = options_.bulk_viscosity_linear, c2 = options_.bulk_viscosity_quadratic;
  const int* nodes = &conn_[kNpe * static_cast<std::size_t>(e)];
  const double* g = &grad_[3 * kNpe * static_cast<std::size_t>(e)];
  // F = I + sum_a u_a (x) dN_a/dX, and J, stored for the accessors and
  // the stable step; F is not read back.
  double fe[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int a = 0; a < kNpe; ++a) {
    const double* ua = ud + 3 * nodes[a];
    const double* ga = g + 3 * a;
    for (int i = 0; i < 3; ++i) {
      fe[3 * i + 0] += ua[i] * ga[0];
      fe[3 * i + 1] += ua[i] * ga[1];
      fe[3 * i + 2] += ua[i] * ga[2];
    }
  }
  const double j = Determinant(fe);
  std::copy(fe, fe + 9, &f_[9 * static_cast<std::size_t>(e)]);
  j_[e] = j;
  double* force = &force_[3 * kNpe * static_cast<std::size_t>(e)];
  if (eroded(e) || !(j > 0) || !std::isfinite(j)) {
    std::fill(force, force + 3 * kNpe, 0.0);
    if (!eroded(e)) *inverted = std::min(*inverted, e);
    return;
  }
  const int mi = material_of_[e];
  const TledMaterial& m = materials_[mi];
  double cof[9];
  Cofactor(fe, cof);
  // Pressure U'(J): the element's, or the mean of its corners' groups.
  double p;
  if (kNpe == 4 && anp_) {
    p = 0;
    for (int a = 0; a < kNpe; ++a) p += group_pressure_[corner_group_[kNpe * e + a]];
    p /= kNpe;
  } else {
    p = m.neo_hookean ? m.bulk * (j - 1) : m.model->Volumetric(j).first;
  }
  // J^(1/3): J^-2/3 for the deviatoric stress and the current length.
  const double cbrt_j = CubeRoot(j);
  // Bulk viscosity from tr D = (dF/dt : cof F) / J.
  double q = 0;
  if (c1 > 0 || c2 > 0) {
    double rate = 0;
    for (int a = 0; a < kNpe; ++a) {
      const double* va = vd + 3 * nodes[a];
      const double* ga = g + 3 * a;
      for (int i = 0; i < 3; ++i) {
        rate += va[i] * (ga[0] * cof[3 * i] + ga[1] * cof[3 * i + 1] + ga[2] * cof[3 * i + 2]);
      }
    }
    rate /= j;
    if (rate < 0) {
      const double l = length_[e] * cbrt_j;
      q = m.density * l * (c2 * l * rate * rate - c1 * wave_speed_[mi] * rate);
    }
  }
  double pk[9];  // first Piola-Kirchhoff stress, row-major
  if (m.neo_hookean) {
    NeoHookeanFirstPiola(m.mu, p - q, fe, cof, j, cbrt_j, pk);
  } else {
    const bool relaxes = history_start_[e] >= 0;
    FirstPiola(*m.model, relaxes ? &steps_[mi] : nullptr,
               relaxes ? &history_[history_start_[e]] : nullptr, fe, cof, p - q, pk);
  }
  // Pressure -tr(sigma)/3 = -(P : F) / (3 J), less the viscosity's q.
  double pf = 0;
  for (int k = 0; k < 9; ++k) pf += pk[k] * fe[k];
  pressure_[e] = -pf / (3 * j) - q;
  if (record_stress_) {
    // sigma = P F^T / J + q I (the stress without the viscosity).
    double s[9];
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < 3; ++k) {
        s[3 * i + k] = (pk[3 * i] * fe[3 * k] + pk[3 * i + 1] * fe[3 * k + 1] +
                        pk[3 * i + 2] * fe[3 * k + 2]) /
                       j;
      }
    }
    double* out = &stress_[6 * static_cast<std::size_t>(e)];
    out[0] = s[0] + q, out[1] = s[4] + q, out[2] = s[8] + q;
    out[3] = s[5], out[4] = s[2], out[5] = s[1];
  }
  const double v0 = volume_[e];
  for (int a = 0; a < kNpe; ++a) {
    const double* ga = g + 3 * a;
    for (int i = 0; i < 3; ++i) {
      force[3 * a + i] = v0 * (pk[3 * i] * ga[0] + pk[3 * i + 1] * ga[1] + pk[3 * i + 2] * ga[2]);
    }
  }
  if (kNpe == 8 && options_.hourglass > 0) HourglassForces(e, ud, force, hourglass);
}

// kBlock neo-Hookean elements from e0 at once, with the arithmetic of
// ElementForce element by element in the same order, but each step over the
// block in the inner loop: kBlock independent chains of operations where
// one element alone is a chain of dependent ones (the sums of F, cof F : dF,
// I1 and P : F, and the divisions), so that the core overlaps them and the
// compiler may use vector registers. False, leaving the block to
// ElementForce, when an element is eroded, not admissible (J <= 0) or of
// another material.
template <int kNpe>
bool TledModel::NeoHookeanBlock(int e0, const double* ud, const double* vd, double* hourglass) {
  constexpr int kB = kBlock;
  double mu[kB], bulk[kB], density[kB], speed[kB];
  for (int b = 0; b < kB; ++b) {
    const int e = e0 + b;
    const int mi = material_of_[e];
    const TledMaterial& m = materials_[mi];
    if (eroded(e) || !m.neo_hookean) return false;
    mu[b] = m.mu, bulk[b] = m.bulk, density[b] = m.density, speed[b] = wave_speed_[mi];
  }
  const int* nodes = &conn_[kNpe * static_cast<std::size_t>(e0)];
  const double* grad = &grad_[3 * kNpe * static_cast<std::size_t>(e0)];
  double f[9][kB], cof[9][kB], j[kB];
  for (int b = 0; b < kB; ++b) {
    const int* nb = nodes + kNpe * b;
    const double* g = grad + 3 * kNpe * b;
    double fe[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int a = 0; a < kNpe; ++a) {
      const double* ua = ud + 3 * nb[a];
      const double* ga = g + 3 * a;
      for (int i = 0; i < 3; ++i) {
        fe[3 * i + 0] += ua[i] * ga[0];
        fe[3 * i + 1] += ua[i] * ga[1];
        fe[3 * i + 2] += ua[i] * ga[2];
      }
    }
    for (int k = 0; k < 9; ++k) f[k][b] = fe[k];
    std::copy(fe, fe + 9, &f_[9 * static_cast<std::size_t>(e0 + b)]);
  }
  for (int b = 0; b < kB; ++b) {
    j[b] = f[0][b] * (f[4][b] * f[8][b] - f[5][b] * f[7][b]) -
           f[1][b] * (f[3][b] * f[8][b] - f[5][b] * f[6][b]) +
           f[2][b] * (f[3][b] * f[7][b] - f[4][b] * f[6][b]);
    j_[e0 + b] = j[b];
  }
  for (int b = 0; b < kB; ++b) {
    if (!(j[b] > 0) || !std::isfinite(j[b])) return false;
  }
  for (int b = 0; b < kB; ++b) {
    cof[0][b] = f[4][b] * f[8][b] - f[5][b] * f[7][b];
    cof[1][b] = f[5][b] * f[6][b] - f[3][b] * f[8][b];
    cof[2][b] = f[3][b] * f[7][b] - f[4][b] * f[6][b];
    cof[3][b] = f[2][b] * f[7][b] - f[1][b] * f[8][b];
    cof[4][b] = f[0][b] * f[8][b] - f[2][b] * f[6][b];
    cof[5][b] = f[1][b] * f[6][b] - f[0][b] * f[7][b];
    cof[6][b] = f[1][b] * f[5][b] - f[2][b] * f[4][b];
    cof[7][b] = f[2][b] * f[3][b] - f[0][b] * f[5][b];
    cof[8][b] = f[0][b] * f[4][b] - f[1][b] * f[3][b];
  }
  double p[kB], cbrt_j[kB], q[kB];
  if (kNpe == 4 && anp_) {
    const int* groups = &corner_group_[kNpe * static_cast<std::size_t>(e0)];
    for (int b = 0; b < kB; ++b) {
      p[b] = 0;
      for (int a = 0; a < kNpe; ++a) p[b] += group_pressure_[groups[kNpe * b + a]];
      p[b] /= kNpe;
    }
  } else {
    for (int b = 0; b < kB; ++b) p[b] = bulk[b] * (j[b] - 1);
  }
  for (int b = 0; b < kB; ++b) cbrt_j[b] = CubeRoot(j[b]);
  const double c1 = options_.bulk_viscosity_linear, c2 = options_.bulk_viscosity_quadratic;
  for (int b = 0; b < kB; ++b) q[b] = 0;
  if (c1 > 0 || c2 > 0) {
    double rate[kB];
    for (int b = 0; b < kB; ++b) {
      const int* nb = nodes + kNpe * b;
      const double* g = grad + 3 * kNpe * b;
      rate[b] = 0;
      for (int a = 0; a < kNpe; ++a) {
        const double* va = vd + 3 * nb[a];
        const double* ga = g + 3 * a;
        for (int i = 0; i < 3; ++i) {
          rate[b] += va[i] * (ga[0] * cof[3 * i][b] + ga[1] * cof[3 * i + 1][b] +
                              ga[2] * cof[3 * i + 2][b]);
        }
      }
    }
    for (int b = 0; b < kB; ++b) {
      rate[b] /= j[b];
      if (rate[b] < 0) {
        const double l = length_[e0 + b] * cbrt_j[b];
        q[b] = density[b] * l * (c2 * l * rate[b] * rate[b] - c1 * speed[b] * rate[b]);
      }
    }
  }
  // P = a F + (p - q - a I1 / (3 J)) cof F, a = mu J^-2/3.
  double i1[kB], pk[9][kB], pf[kB];
  for (int b = 0; b < kB; ++b) i1[b] = 0;
  for (int k = 0; k < 9; ++k) {
    for (int b = 0; b < kB; ++b) i1[b] += f[k][b] * f[k][b];
  }
  for (int b = 0; b < kB; ++b) {
    const double a = mu[b] / (cbrt_j[b] * cbrt_j[b]);
    const double c = p[b] - q[b] - a * i1[b] / (3 * j[b]);
    for (int k = 0; k < 9; ++k) pk[k][b] = a * f[k][b] + c * cof[k][b];
  }
  for (int b = 0; b < kB; ++b) pf[b] = 0;
  for (int k = 0; k < 9; ++k) {
    for (int b = 0; b < kB; ++b) pf[b] += pk[k][b] * f[k][b];
  }
  for (int b = 0; b < kB; ++b) pressure_[e0 + b] = -pf[b] / (3 * j[b]) - q[b];
  double* force = &force_[3 * kNpe * static_cast<std::size_t>(e0)];
  for (int b = 0; b < kB; ++b) {
    const double v0 = volume_[e0 + b];
    const double* g = grad + 3 * kNpe * b;
    for (int a = 0; a < kNpe; ++a) {
      const double* ga = g + 3 * a;
      for (int i = 0; i < 3; ++i) {
        force[3 * kNpe * b + 3 * a + i] =
            v0 * (pk[3 * i][b] * ga[0] + pk[3 * i + 1][b] * ga[1] + pk[3 * i + 2][b] * ga[2]);
      }
    }
  }
  if (kNpe == 8 && options_.hourglass > 0) {
    for (int b = 0; b < kB; ++b) {
      HourglassForces(e0 + b, ud, force + 3 * kNpe * b, hourglass);
    }
  }
  return true;
}

template <int kNpe>
void TledModel::ElementForces(const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                              TledEvaluation* eval) {
  const double* vd = v.data();
  const double* ud = u.data();
  // This thread's share; `eval` (shared) receives the sums.
  double hourglass = 0;
  int inverted = std::numeric_limits<int>::max();
  const int blocks = (num_elements_ + kBlock - 1) / kBlock;
#pragma omp for schedule(static) nowait
  for (int block = 0; block < blocks; ++block) {
    const int e0 = block * kBlock;
    if (record_stress_ || e0 + kBlock > num_elements_ ||
        !NeoHookeanBlock<kNpe>(e0, ud, vd, &hourglass)) {
      for (int e = e0; e < std::min(e0 + kBlock, num_elements_); ++e) {
        ElementForce<kNpe>(e, ud, vd, &hourglass, &inverted);
      }
    }
  }
#pragma omp critical(tled_evaluation)
  {
    eval->hourglass_energy += hourglass;
    if (inverted != std::numeric_limits<int>::max() &&
        (eval->inverted_element < 0 || inverted < eval->inverted_element)) {
      eval->inverted_element = inverted;
    }
  }
#pragma omp barrier
}

void TledModel::Gather(Eigen::VectorXd* f_int) const {
  double* out = f_int->data();
#pragma omp for schedule(static)
  for (int n = 0; n < num_nodes_; ++n) {
    double fx = 0, fy = 0, fz = 0;
    for (int k = node_start_[n]; k < node_start_[n + 1]; ++k) {
      const double* f = &force_[3 * static_cast<std::size_t>(node_corner_[k])];
      fx += f[0], fy += f[1], fz += f[2];
    }
    out[3 * n] = fx, out[3 * n + 1] = fy, out[3 * n + 2] = fz;
  }
}

TledEvaluation TledModel::InternalForce(const Eigen::VectorXd& u, const Eigen::VectorXd& v,
                                        Eigen::VectorXd* f_int) {
  TledEvaluation eval;
  if (record_stress_) stress_.resize(6 * static_cast<std::size_t>(num_elements_));
  f_int->resize(3 * static_cast<Eigen::Index>(num_nodes_));
#pragma omp parallel num_threads(options_.threads.threads())
  {
    if (anp_) {
      VolumeRatios(u);
      AverageNodalPressure();
    }
    if (npe_ == 4) {
      ElementForces<4>(u, v, &eval);
    } else {
      ElementForces<8>(u, v, &eval);
    }
    Gather(f_int);
  }
  return eval;
}

std::string TledModel::Describe() const {
  const char* element = npe_ == 8 ? "HEX8 (one point, hourglass control)"
                        : anp_    ? "TET4_ANP"
                                  : "TET4";
  return std::string(element) + ", explicit total Lagrangian";
}

BodyForce TledModel::Force(const Eigen::VectorXd& u, const Eigen::VectorXd* v,
                           Eigen::VectorXd* f_int) {
  const TledEvaluation eval = v != nullptr
                                  ? InternalForce(u, *v, f_int)
                                  : InternalForce(u, Eigen::VectorXd::Zero(u.size()), f_int);
  BodyForce out;
  out.inverted_element = eval.inverted_element;
  out.ok = eval.inverted_element < 0 && f_int->allFinite();
  out.hourglass_energy = eval.hourglass_energy;
  if (out.ok) out.energy = StoredEnergy();
  return out;
}

double TledModel::RecoverFields(const Eigen::VectorXd& u, Solution* solution) const {
  StartFiniteStrainFields(num_elements_, solution);
  double largest = 0;
  for (int e = 0; e < num_elements_; ++e) {
    if (eroded(e)) continue;
    // One point per element: its fields are written as they are, not
    // through a weighted sum (which would turn a -0 into a +0).
    const ElementFields fields = FieldsFromCauchy(DeformationGradient(e), CauchyStress(e));
    largest = std::max(largest, WriteFiniteStrainFields(e, fields, solution));
  }
  return largest;
}

Status TledModel::RestoreHistory(const std::vector<double>& values) {
  if (values.size() != history_.size()) {
    return Status::InvalidArgument(
        "history", "holds " + std::to_string(values.size()) + " numbers where this model keeps " +
                       std::to_string(history_.size()) + " (a different mesh or material?)");
  }
  history_ = values;
  return Status::Ok();
}

Eigen::Matrix3d TledModel::DeformationGradient(int e) const {
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(
      &f_[9 * static_cast<std::size_t>(e)]);
}

Vector6d TledModel::CauchyStress(int e) const {
  if (stress_.empty()) return Vector6d::Zero();
  return Eigen::Map<const Vector6d>(&stress_[6 * static_cast<std::size_t>(e)]);
}

void TledModel::Erode(int e) {
  if (eroded_.empty()) eroded_.assign(num_elements_, 0);
  eroded_[e] = 1;
}

double TledModel::StoredEnergy() const {
  double total = 0;
#pragma omp parallel for schedule(static) num_threads(options_.threads.threads()) reduction(+ : total)
  for (int e = 0; e < num_elements_; ++e) {
    if (eroded(e) || !(j_[e] > 0)) continue;
    const Eigen::Matrix3d f = DeformationGradient(e);
    const HyperelasticMaterial& m = *material(e).model;
    double w = 0;
    m.Isochoric(f, &w, nullptr, nullptr);
    if (!anp_) w += m.Volumetric(j_[e]).value;
    if (std::isfinite(w)) total += w * volume_[e];
  }
  if (!anp_) return total;
  const int groups = static_cast<int>(group_material_.size());
#pragma omp parallel for schedule(static) num_threads(options_.threads.threads()) reduction(+ : total)
  for (int g = 0; g < groups; ++g) {
    double sum_vj = 0, sum_v = 0;
    for (int k = group_start_[g]; k < group_start_[g + 1]; ++k) {
      const int e = group_element_[k];
      sum_vj += volume_ratio_[e];  // an eroded element's, frozen
      sum_v += volume_[e];
    }
    if (sum_v == 0) continue;
    // The group's volume V_n: a quarter of each of its elements'.
    const double u = materials_[group_material_[g]].model->Volumetric(sum_vj / sum_v).value;
    if (std::isfinite(u)) total += 0.25 * sum_v * u;
  }
  return total;
}

std::vector<int> TledModel::OrphanNodes() const {
  std::vector<int> out;
  if (eroded_.empty()) return out;
  for (int n = 0; n < num_nodes_; ++n) {
    bool alive = false;
    for (int k = node_start_[n]; k < node_start_[n + 1] && !alive; ++k) {
      alive = !eroded_[node_corner_[k] / npe_];
    }
    if (!alive && node_start_[n + 1] > node_start_[n]) out.push_back(n);
  }
  return out;
}

}  // namespace pba
