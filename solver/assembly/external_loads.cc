#include "assembly/external_loads.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "fem/hex8.h"
#include "fem/tet10.h"
#include "fem/tet4.h"
#include "mesh/quadratic.h"

namespace pba {
namespace {

// [w]_x, the matrix of y -> w x y.
Eigen::Matrix3d Skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d s;
  s << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return s;
}

// A point of a rule on the reference triangle xi, eta >= 0, xi + eta <= 1;
// the weights of a rule sum to 1/2, its area.
struct TrianglePoint {
  Eigen::Vector2d xi;
  double weight = 0;
};

// The 7-point rule exact for degree 5 (Radon 1948; Dunavant 1985, IJNME 21,
// degree 5): the centroid with weight 9/40 of the area and the orbits of the
// area coordinates (a, a, 1 - 2a), a = (6 -+ sqrt 15) / 21, with weights
// (155 -+ sqrt 15) / 1200.
std::vector<TrianglePoint> MakeTriangleRule() {
  const double r = std::sqrt(15.0);
  std::vector<TrianglePoint> rule = {{Eigen::Vector2d(1.0 / 3, 1.0 / 3), 0.5 * 9 / 40}};
  for (const double sign : {-1.0, 1.0}) {
    const double a = (6 + sign * r) / 21, w = 0.5 * (155 + sign * r) / 1200;
    rule.push_back({Eigen::Vector2d(a, a), w});
    rule.push_back({Eigen::Vector2d(1 - 2 * a, a), w});
    rule.push_back({Eigen::Vector2d(a, 1 - 2 * a), w});
  }
  return rule;
}

const std::vector<TrianglePoint>& TriangleRule() {
  static const std::vector<TrianglePoint> rule = MakeTriangleRule();
  return rule;
}

using Tri6Vector = Eigen::Matrix<double, 6, 1>;
using Tri6Gradients = Eigen::Matrix<double, 6, 2>;  // dN_a/dxi, dN_a/deta

// The 6-node triangle's shape functions at `xi` (see the header) and their
// natural derivatives; nodes: corners 0..2, then edges (0,1), (1,2), (2,0).
void Tri6Shape(const Eigen::Vector2d& xi, Tri6Vector* n, Tri6Gradients* dn) {
  const Eigen::Vector3d l(1 - xi.x() - xi.y(), xi.x(), xi.y());
  Eigen::Matrix<double, 3, 2> dl;
  dl << -1, -1, 1, 0, 0, 1;
  for (int a = 0; a < 3; ++a) {
    (*n)(a) = l(a) * (2 * l(a) - 1);
    dn->row(a) = (4 * l(a) - 1) * dl.row(a);
  }
  for (int k = 0; k < 3; ++k) {
    const int i = k, j = (k + 1) % 3;
    (*n)(3 + k) = 4 * l(i) * l(j);
    dn->row(3 + k) = 4 * (l(j) * dl.row(i) + l(i) * dl.row(j));
  }
}

// A point of a rule on a reference face with the shape functions of an
// N-node face there and their natural derivatives (dN_a/dxi, dN_a/deta).
template <int N>
struct SurfacePoint {
  Eigen::Matrix<double, N, 1> n;
  Eigen::Matrix<double, N, 2> dn;
  double weight = 0;
};

const std::vector<SurfacePoint<6>>& Tri6Rule() {
  static const std::vector<SurfacePoint<6>> rule = [] {
    std::vector<SurfacePoint<6>> points;
    for (const TrianglePoint& q : TriangleRule()) {
      SurfacePoint<6> p;
      Tri6Shape(q.xi, &p.n, &p.dn);
      p.weight = q.weight;
      points.push_back(p);
    }
    return points;
  }();
  return rule;
}

// Natural coordinates of the C3D8 nodes (see Mesh::hexes); the first four
// are those of a bilinear quad's nodes 0..3 on (xi, eta).
constexpr int kHexCorner[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                  {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};

// The 2-point Gauss abscissa on [-1, 1] (weights 1), exact for cubics.
const double kGauss = 1 / std::sqrt(3.0);

// The bilinear quad N_a = (1 + xi xi_a)(1 + eta eta_a) / 4 at the 2 x 2
// Gauss points. Pressure's integrand N_a (g1 x g2) is at most quadratic in
// each coordinate (g1 = x_,xi is linear in eta alone, g2 in xi alone) and
// so is the load stiffness's, so the rule integrates both exactly.
const std::vector<SurfacePoint<4>>& Quad4Rule() {
  static const std::vector<SurfacePoint<4>> rule = [] {
    std::vector<SurfacePoint<4>> points;
    for (const double eta : {-kGauss, kGauss}) {
      for (const double xi : {-kGauss, kGauss}) {
        SurfacePoint<4> p;
        for (int a = 0; a < 4; ++a) {
          const double ca = kHexCorner[a][0], cb = kHexCorner[a][1];
          p.n(a) = (1 + xi * ca) * (1 + eta * cb) / 4;
          p.dn(a, 0) = ca * (1 + eta * cb) / 4;
          p.dn(a, 1) = cb * (1 + xi * ca) / 4;
        }
        p.weight = 1;
        points.push_back(p);
      }
    }
    return points;
  }();
  return rule;
}

// integral N_a |G1 x G2| dxi deta over a face with node positions `x`
// (one row per node): its share of a uniform traction per unit area.
template <int N>
Eigen::Matrix<double, N, 1> AreaShares(const Eigen::Matrix<double, N, 3>& x,
                                       const std::vector<SurfacePoint<N>>& rule) {
  Eigen::Matrix<double, N, 1> share = Eigen::Matrix<double, N, 1>::Zero();
  for (const SurfacePoint<N>& q : rule) {
    const Eigen::Matrix<double, 3, 2> g = x.transpose() * q.dn;  // columns G1, G2
    share += q.weight * g.col(0).cross(g.col(1)).norm() * q.n;
  }
  return share;
}

// integral N_a (g1 x g2) dxi deta (row a): minus a pressure's force on node
// a per unit pressure.
template <int N>
Eigen::Matrix<double, N, 3> VectorAreaShares(const Eigen::Matrix<double, N, 3>& x,
                                             const std::vector<SurfacePoint<N>>& rule) {
  Eigen::Matrix<double, N, 3> share = Eigen::Matrix<double, N, 3>::Zero();
  for (const SurfacePoint<N>& q : rule) {
    const Eigen::Matrix<double, 3, 2> g = x.transpose() * q.dn;
    share += q.weight * q.n * g.col(0).cross(g.col(1)).transpose();
  }
  return share;
}

// The symmetric part of a pressure's load stiffness on one face, [v_ab]_x
// of the header (v_ab = -v_ba, so the diagonal blocks vanish), times
// `scale` = factor p, passed block by block to add_block(a, b, block) for
// local nodes a != b.
template <int N, typename AddBlock>
void SymmetricPressureStiffness(const Eigen::Matrix<double, N, 3>& x,
                                const std::vector<SurfacePoint<N>>& rule, double scale,
                                const AddBlock& add_block) {
  std::array<std::array<Eigen::Vector3d, N>, N> v;
  for (auto& row : v) row.fill(Eigen::Vector3d::Zero());
  for (const SurfacePoint<N>& q : rule) {
    const Eigen::Matrix<double, 3, 2> g = x.transpose() * q.dn;
    for (int a = 0; a < N; ++a) {
      for (int b = a + 1; b < N; ++b) {
        const double c_eta = q.n(a) * q.dn(b, 1) - q.n(b) * q.dn(a, 1);
        const double c_xi = q.n(a) * q.dn(b, 0) - q.n(b) * q.dn(a, 0);
        v[a][b] += q.weight * (c_eta * g.col(0) - c_xi * g.col(1));
      }
    }
  }
  for (int a = 0; a < N; ++a) {
    for (int b = a + 1; b < N; ++b) {
      const Eigen::Matrix3d block = scale / 2 * Skew(v[a][b]);
      add_block(a, b, block);
      add_block(b, a, block.transpose());
    }
  }
}

// The mid-edge nodes of triangle `corners`, a face of element `element`.
std::array<int, 3> MidsideFromElement(const Mesh& mesh, int element,
                                      const std::array<int, 3>& corners) {
  const auto& tet = mesh.tets[element];
  const auto local = [&](int node) {
    return static_cast<int>(std::find(tet.begin(), tet.end(), node) - tet.begin());
  };
  std::array<int, 3> mid = {-1, -1, -1};
  for (int k = 0; k < 3; ++k) {
    const int i = local(corners[k]), j = local(corners[(k + 1) % 3]);
    for (int edge = 0; edge < 6; ++edge) {
      const int p = kTet10Edges[edge][0], q = kTet10Edges[edge][1];
      if ((p == i && q == j) || (p == j && q == i)) mid[k] = mesh.midside[element][edge];
    }
  }
  return mid;
}

// The mid-edge nodes of each triangle of `set` on quadratic `mesh`: the
// set's own, or, for a set assembled without them, those of the element
// behind each triangle.
std::vector<std::array<int, 3>> TriangleMidside(const Mesh& mesh, const FaceSet& set) {
  if (set.triangle_midside.size() == set.triangles.size()) return set.triangle_midside;
  const std::vector<std::array<int, 2>> owners = FaceElements(mesh, set);
  std::vector<std::array<int, 3>> mid(set.triangles.size());
  for (std::size_t i = 0; i < set.triangles.size(); ++i) {
    if (owners[i][0] < 0) {
      // Without an element there is no edge to take the mid-edge node from.
      std::fprintf(stderr,
                   "pba: ExternalLoads: triangle (%d, %d, %d) of a quadratic mesh has no "
                   "mid-edge nodes and is no element's face\n",
                   set.triangles[i][0], set.triangles[i][1], set.triangles[i][2]);
      std::abort();
    }
    mid[i] = MidsideFromElement(mesh, owners[i][0], set.triangles[i]);
  }
  return mid;
}

// f_a = integral b(x) N_a dV over each element of `mesh`, added to `dead`,
// by a rule exact for a uniform b (and of degree 5 on tetrahedra, 5 per
// coordinate on bricks, for a varying one); |det J| so that a consistently
// negatively oriented element still loads along b, not against it. One
// function per element shape.
void AddHex8BodyForce(const Mesh& mesh,
                      const ExternalLoads::ElementBodyForceField& force_per_volume,
                      Eigen::VectorXd* dead) {
  const double g[3] = {-std::sqrt(0.6), 0, std::sqrt(0.6)}, w[3] = {5.0 / 9, 8.0 / 9, 5.0 / 9};
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const Hex8Nodes x = HexCorners(mesh, e);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        for (int k = 0; k < 3; ++k) {
          const Eigen::Vector3d xi(g[i], g[j], g[k]);
          const Hex8Vector n = Hex8ShapeFunctions(xi);
          const double det = (x.transpose() * Hex8NaturalGradients(xi)).determinant();
          const Eigen::Vector3d b =
              w[i] * w[j] * w[k] * std::abs(det) * force_per_volume(x.transpose() * n, e);
          for (int a = 0; a < 8; ++a) dead->segment<3>(3 * mesh.hexes[e][a]) += n(a) * b;
        }
      }
    }
  }
}

void AddTet10BodyForce(const Mesh& mesh,
                       const ExternalLoads::ElementBodyForceField& force_per_volume,
                       Eigen::VectorXd* dead) {
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const Tet10Nodes x = Tet10Coordinates(mesh, e);
    const std::array<int, 10> nodes = Tet10NodeIndices(mesh, e);
    for (const QuadraturePoint& q : Tet10MassRule()) {
      const Tet10Vector n = Tet10ShapeFunctions(q.xi);
      const double det = (x.transpose() * Tet10NaturalGradients(q.xi)).determinant();
      const Eigen::Vector3d b = q.weight * std::abs(det) * force_per_volume(x.transpose() * n, e);
      for (int a = 0; a < 10; ++a) dead->segment<3>(3 * nodes[a]) += n(a) * b;
    }
  }
}

void AddTet4BodyForce(const Mesh& mesh,
                      const ExternalLoads::ElementBodyForceField& force_per_volume,
                      Eigen::VectorXd* dead) {
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const Eigen::Matrix<double, 4, 3> x = TetCorners(mesh, e);
    const double volume = std::abs(ComputeTet4Geometry(x).volume);
    for (const QuadraturePoint& q : Tet10MassRule()) {
      // Linear shape functions: the volume coordinates at xi.
      const Eigen::Vector4d n(1 - q.xi.sum(), q.xi.x(), q.xi.y(), q.xi.z());
      const Eigen::Vector3d b = q.weight * 6 * volume * force_per_volume(x.transpose() * n, e);
      for (int a = 0; a < 4; ++a) dead->segment<3>(3 * mesh.tets[e][a]) += n(a) * b;
    }
  }
}

}  // namespace

ExternalLoads::ExternalLoads(const Mesh& mesh)
    : mesh_(mesh),
      face_(ShapeInfo(mesh.shape()).boundary_face),
      dead_(Eigen::VectorXd::Zero(3 * mesh.num_nodes())) {}

Eigen::Vector3d ExternalLoads::Position(int node, const Eigen::VectorXd* u) const {
  Eigen::Vector3d x = mesh_.nodes.row(node).transpose();
  if (u != nullptr) x += u->segment<3>(3 * node);
  return x;
}

void ExternalLoads::AddTraction(const FaceSet& set, const Eigen::Vector3d& traction_pa) {
  for (const auto& quad : set.quads) {
    Eigen::Matrix<double, 4, 3> x;
    for (int a = 0; a < 4; ++a) x.row(a) = Position(quad[a], nullptr).transpose();
    const Eigen::Vector4d share = AreaShares<4>(x, Quad4Rule());  // integral N_a dA
    for (int a = 0; a < 4; ++a) dead_.segment<3>(3 * quad[a]) += traction_pa * share(a);
  }
  if (face_ != BoundaryFace::kTri6) {
    for (const auto& t : set.triangles) {
      const double area = 0.5 * (Position(t[1], nullptr) - Position(t[0], nullptr))
                                    .cross(Position(t[2], nullptr) - Position(t[0], nullptr))
                                    .norm();
      for (int a : t) dead_.segment<3>(3 * a) += traction_pa * area / 3;
    }
    return;
  }
  const std::vector<std::array<int, 3>> midside = TriangleMidside(mesh_, set);
  for (std::size_t i = 0; i < set.triangles.size(); ++i) {
    std::array<int, 6> nodes;
    Eigen::Matrix<double, 6, 3> x;
    for (int k = 0; k < 3; ++k) {
      nodes[k] = set.triangles[i][k];
      nodes[3 + k] = midside[i][k];
    }
    for (int a = 0; a < 6; ++a) x.row(a) = Position(nodes[a], nullptr).transpose();
    const Tri6Vector share = AreaShares<6>(x, Tri6Rule());  // integral N_a dA
    for (int a = 0; a < 6; ++a) dead_.segment<3>(3 * nodes[a]) += traction_pa * share(a);
  }
}

void ExternalLoads::AddBodyForce(const Eigen::Vector3d& force_per_volume) {
  AddBodyForceField([&](const Eigen::Vector3d&) { return force_per_volume; });
}

void ExternalLoads::AddBodyForceField(const BodyForceField& force_per_volume) {
  AddElementBodyForceField(
      [&](const Eigen::Vector3d& position, int) { return force_per_volume(position); });
}

void ExternalLoads::AddElementBodyForceField(const ElementBodyForceField& force_per_volume) {
  switch (mesh_.shape()) {
    case ElementShape::kTet4:
      AddTet4BodyForce(mesh_, force_per_volume, &dead_);
      return;
    case ElementShape::kTet10:
      AddTet10BodyForce(mesh_, force_per_volume, &dead_);
      return;
    case ElementShape::kHex8:
      AddHex8BodyForce(mesh_, force_per_volume, &dead_);
      return;
  }
}

void ExternalLoads::AddPressure(const FaceSet& set, double pressure_pa, bool follower) {
  // The tetrahedron behind each triangle tells which side is out.
  const std::vector<std::array<int, 2>> owners = FaceElements(mesh_, set);
  std::vector<std::array<int, 3>> midside;
  if (face_ == BoundaryFace::kTri6) midside = TriangleMidside(mesh_, set);
  for (std::size_t i = 0; i < set.triangles.size(); ++i) {
    std::array<int, 3> t = set.triangles[i];
    std::array<int, 3> m = midside.empty() ? std::array<int, 3>{-1, -1, -1} : midside[i];
    const auto [element, corner] = owners[i];
    if (element >= 0) {
      // The corners' plane decides, also for a curved 6-node triangle, whose
      // mid-edge nodes lie close to that plane on any usable mesh.
      const Eigen::Vector3d x0 = Position(t[0], nullptr);
      const Eigen::Vector3d normal =
          (Position(t[1], nullptr) - x0).cross(Position(t[2], nullptr) - x0);
      const int inside = mesh_.tets[element][corner];
      if (normal.dot(Position(inside, nullptr) - x0) > 0) {
        // Corners (0, 2, 1) have edges (0,2), (2,1), (1,0): the old third,
        // second and first.
        std::swap(t[1], t[2]);
        std::swap(m[0], m[2]);
      }
    }
    pressure_.push_back({t, m, pressure_pa, follower});
  }
  // The brick behind each quad tells which side is out.
  const std::vector<std::array<int, 2>> quad_owners = QuadFaceElements(mesh_, set);
  for (std::size_t i = 0; i < set.quads.size(); ++i) {
    std::array<int, 4> q = set.quads[i];
    const int element = quad_owners[i][0];
    if (element >= 0) {
      // The diagonals' cross product is the quad's mean normal (4 g1 x g2
      // at its centre), right-handed about 0-1-2-3; the brick's centroid is
      // inside even for a warped face.
      Eigen::Vector3d centre = Eigen::Vector3d::Zero(), inside = Eigen::Vector3d::Zero();
      for (int node : q) centre += Position(node, nullptr) / 4;
      for (int node : mesh_.hexes[element]) inside += Position(node, nullptr) / 8;
      const Eigen::Vector3d normal = (Position(q[2], nullptr) - Position(q[0], nullptr))
                                         .cross(Position(q[3], nullptr) - Position(q[1], nullptr));
      if (normal.dot(inside - centre) > 0) std::swap(q[1], q[3]);
    }
    quad_pressure_.push_back({q, pressure_pa, follower});
  }
}

bool ExternalLoads::follows_deformation() const {
  return std::any_of(pressure_.begin(), pressure_.end(),
                     [](const Pressure& p) { return p.follower; }) ||
         std::any_of(quad_pressure_.begin(), quad_pressure_.end(),
                     [](const QuadPressure& p) { return p.follower; });
}

Eigen::VectorXd ExternalLoads::Force(const Eigen::VectorXd& u) const {
  Eigen::VectorXd f = dead_;
  for (const QuadPressure& p : quad_pressure_) {
    const Eigen::VectorXd* state = p.follower ? &u : nullptr;
    Eigen::Matrix<double, 4, 3> x;
    for (int a = 0; a < 4; ++a) x.row(a) = Position(p.nodes[a], state).transpose();
    const Eigen::Matrix<double, 4, 3> share = VectorAreaShares<4>(x, Quad4Rule());
    for (int a = 0; a < 4; ++a) {
      f.segment<3>(3 * p.nodes[a]) -= p.pressure_pa * share.row(a).transpose();
    }
  }
  for (const Pressure& p : pressure_) {
    const Eigen::VectorXd* state = p.follower ? &u : nullptr;
    if (face_ != BoundaryFace::kTri6) {
      const Eigen::Vector3d x0 = Position(p.nodes[0], state);
      const Eigen::Vector3d area2 =
          (Position(p.nodes[1], state) - x0).cross(Position(p.nodes[2], state) - x0);
      for (int a : p.nodes) f.segment<3>(3 * a) -= p.pressure_pa / 6 * area2;
      continue;
    }
    const std::array<int, 6> nodes = {p.nodes[0],   p.nodes[1],   p.nodes[2],
                                      p.midside[0], p.midside[1], p.midside[2]};
    Eigen::Matrix<double, 6, 3> x;
    for (int a = 0; a < 6; ++a) x.row(a) = Position(nodes[a], state).transpose();
    const Eigen::Matrix<double, 6, 3> share = VectorAreaShares<6>(x, Tri6Rule());
    for (int a = 0; a < 6; ++a) {
      f.segment<3>(3 * nodes[a]) -= p.pressure_pa * share.row(a).transpose();
    }
  }
  return f;
}

SparseMatrix ExternalLoads::Stiffness(const Eigen::VectorXd& u, const DofMap& dofs,
                                      double factor) const {
  std::vector<Eigen::Triplet<double>> entries;
  const auto add_block = [&](int node_a, int node_b, const Eigen::Matrix3d& block) {
    for (int r = 0; r < 3; ++r) {
      const int i = dofs.free_index(3 * node_a + r);
      if (i < 0) continue;
      for (int c = 0; c < 3; ++c) {
        const int j = dofs.free_index(3 * node_b + c);
        if (j >= 0) entries.emplace_back(i, j, block(r, c));
      }
    }
  };
  for (const QuadPressure& p : quad_pressure_) {
    if (!p.follower) continue;
    Eigen::Matrix<double, 4, 3> x;
    for (int a = 0; a < 4; ++a) x.row(a) = Position(p.nodes[a], &u).transpose();
    SymmetricPressureStiffness<4>(x, Quad4Rule(), factor * p.pressure_pa,
                                  [&](int a, int b, const Eigen::Matrix3d& block) {
                                    add_block(p.nodes[a], p.nodes[b], block);
                                  });
  }
  for (const Pressure& p : pressure_) {
    if (!p.follower) continue;
    if (face_ != BoundaryFace::kTri6) {
      // f_a = -(p / 6) A, A = (x1 - x0) x (x2 - x0) = x0 x x1 + x1 x x2 + x2 x x0,
      // so dA/dx_b = [x_{b+2} - x_{b+1}]_x (indices mod 3) and
      // K_L(a, b) = -df_a/dx_b = (p / 6) [w_b]_x, w_b = x_{b+2} - x_{b+1};
      // its symmetric part is (p / 12)([w_b]_x - [w_a]_x) (a skew matrix's
      // transpose is its negative).
      Eigen::Vector3d x[3], w[3];
      for (int k = 0; k < 3; ++k) x[k] = Position(p.nodes[k], &u);
      for (int b = 0; b < 3; ++b) w[b] = x[(b + 2) % 3] - x[(b + 1) % 3];
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) {
          if (a == b) continue;
          add_block(p.nodes[a], p.nodes[b],
                    factor * p.pressure_pa / 12 * (Skew(w[b]) - Skew(w[a])));
        }
      }
      continue;
    }
    const std::array<int, 6> nodes = {p.nodes[0],   p.nodes[1],   p.nodes[2],
                                      p.midside[0], p.midside[1], p.midside[2]};
    Eigen::Matrix<double, 6, 3> x;
    for (int a = 0; a < 6; ++a) x.row(a) = Position(nodes[a], &u).transpose();
    SymmetricPressureStiffness<6>(
        x, Tri6Rule(), factor * p.pressure_pa,
        [&](int a, int b, const Eigen::Matrix3d& block) { add_block(nodes[a], nodes[b], block); });
  }
  SparseMatrix k(dofs.num_free(), dofs.num_free());
  k.setFromTriplets(entries.begin(), entries.end());
  return k;
}

Eigen::Vector3d ExternalLoads::ReferenceResultant() const {
  const Eigen::VectorXd f = Force(Eigen::VectorXd::Zero(dead_.size()));
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (int a = 0; a < mesh_.num_nodes(); ++a) total += f.segment<3>(3 * a);
  return total;
}

}  // namespace pba
