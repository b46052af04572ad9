#include "analysis/average_nodal_pressure_model.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "analysis/element_fields.h"
#include "fem/tet4_finite_strain.h"
#include "linear/petsc_runtime.h"
#include "material/hyperelastic.h"

namespace pba {
namespace {

// Derivation (Pi as in the header; x the current positions, G_b = grad_X N_b,
// F_e = sum_b x_b (x) G_b, v_e = V_e det F_e):
//
//   dv_e/dx_b = V_e cof(F_e) G_b, cof F = d(det F)/dF = (det F) F^-T
//     (Jacobi's formula for the derivative of a determinant). It is the
//     cofactor form of the tet: 1/6 of the cross product of two edges of the
//     face opposite b, normal to that face and pointing towards b;
//   d2v_e/dx_b,i dx_c,j = V_e eps_ijm eps_kln F_mn G_bk G_cl
//                       = -V_e [F_e (G_b x G_c)]_x,
//     with [w]_x y = w x y; the second derivative of det F is
//     eps_ijm eps_kln F_mn because det F = (1/6) eps_ijm eps_kln F_ik F_jl F_mn.
//     It is linear in x (through F) and skew in the node pair:
//     block (c, b) = block (b, c)^T = -block (b, c), blocks (b, b) = 0. Since
//     F (G_b x G_c) = det F (g_b x g_c) with g = grad_x N, it is also
//     v_e (g_b g_c^T - g_c g_b^T), the current-configuration form.
//
//   f = sum_e [V_e B_e^T S_iso,e + pbar_e dv_e/dx],
//     p_a = U'(J_a), pbar_e = (1/4) sum_{a in e} p_a,
//     because dPi_vol/dx = sum_a V_a U'(J_a) (1/V_a) dv_a/dx and
//     dv_a/dx = sum_{e ∋ a} (1/4) dv_e/dx; regrouping by element gives pbar_e.
//   K = sum_e [K_iso,e + pbar_e d2v_e/dx2] + sum_a (U''(J_a) / V_a) g_a g_a^T,
//     g_a = dv_a/dx = sum_{e ∋ a} (1/4) dv_e/dx, nonzero on the nodes of a's
//     patch; K_iso,e is the usual total-Lagrangian material plus geometric
//     stiffness of W_iso (fem/tet4_finite_strain.h).
//
// The isochoric split W = W_iso(C_bar) + U(J) is that of
// material/hyperelastic.h; on a homogeneous deformation J_a = J_e everywhere
// and the model is the plain tetrahedron.

// Compressed rows of ints: row i holds index[offset[i] .. offset[i + 1]).
struct Csr {
  std::vector<int> offset;
  std::vector<int> index;

  int begin(int i) const { return offset[i]; }
  int end(int i) const { return offset[i + 1]; }
  // Position in `index` of `value` within sorted row i (must be present).
  int Find(int i, int value) const {
    const auto first = index.begin() + offset[i], last = index.begin() + offset[i + 1];
    return static_cast<int>(std::lower_bound(first, last, value) - index.begin());
  }
};

Csr Flatten(const std::vector<std::vector<int>>& rows) {
  Csr csr;
  csr.offset.assign(rows.size() + 1, 0);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    csr.offset[i + 1] = csr.offset[i] + static_cast<int>(rows[i].size());
  }
  csr.index.reserve(csr.offset.back());
  for (const auto& row : rows) csr.index.insert(csr.index.end(), row.begin(), row.end());
  return csr;
}

// [w]_x, the matrix of y -> w x y.
Eigen::Matrix3d Skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d s;
  s << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return s;
}

// One element at a state.
struct ElementState {
  Eigen::Matrix3d f;
  Vector12d force;            // isochoric, then with pbar dv/dx added
  Vector12d volume_gradient;  // dv_e/dx
  double iso_energy = 0;      // V_e W_iso
  double volume = 0;          // v_e
};

struct State {
  std::vector<ElementState> elements;
  std::vector<Matrix12d> tangents;       // element-local part of K, when asked for
  std::vector<ScalarDerivatives> nodal;  // U, U', U'' at J_a
  double energy = 0;
};

// The volumetric constraints: one per node and material around it (a
// group), so that a node on an interface between materials keeps each
// side's volume change apart, as the pressure jumps there: a growing
// inclusion's nodes are not held to the volume of the incompressible tissue
// around them. Group g of node a holds the elements of a of one material
// entry, reference volume V_g = sum V_e / 4 over them; with one material a
// node has one group and the model is the plain average-nodal-pressure one.
struct NodalGroups {
  Csr of_node;                     // node -> its groups
  std::vector<int> first_element;  // group -> one of its elements (its material)
  std::vector<double> volume;      // group -> V_g [m^3]
  std::vector<int> of_incidence;   // incidence t of incidence Csr -> its group

  NodalGroups(const Csr& incidence, const std::vector<double>& reference_volume,
              const MaterialField& field, int nodes) {
    std::vector<std::vector<int>> rows(nodes);
    of_incidence.resize(incidence.index.size());
    for (int a = 0; a < nodes; ++a) {
      const int first = static_cast<int>(first_element.size());
      for (int t = incidence.begin(a); t < incidence.end(a); ++t) {
        const int e = incidence.index[t], entry = field.entry_of(e);
        int g = first;
        while (g < static_cast<int>(first_element.size()) &&
               field.entry_of(first_element[g]) != entry) {
          ++g;
        }
        if (g == static_cast<int>(first_element.size())) {
          first_element.push_back(e);
          volume.push_back(0);
          rows[a].push_back(g);
        }
        volume[g] += reference_volume[e] / 4;
        of_incidence[t] = g;
      }
    }
    of_node = Flatten(rows);
  }
  int size() const { return static_cast<int>(first_element.size()); }
};

// U_g and its derivatives at the group's volume ratio j.
ScalarDerivatives GroupVolumetric(const MaterialField& field, const NodalGroups& groups, int g,
                                  double j) {
  if (field.uniform()) return field.Base(0).Volumetric(j);
  return field.At(groups.first_element[g]).Volumetric(j);
}

class NodalPressureModel final : public FiniteStrainModel {
 public:
  // The passes run on `threads`, and on the calling thread below
  // kMinParallelWork elements.
  NodalPressureModel(const Mesh& mesh, const MaterialField& field, const ThreadContext& threads,
                     std::unique_ptr<MaterialField> owned = nullptr)
      : mesh_(mesh),
        owned_(std::move(owned)),
        field_(owned_ ? *owned_ : field),
        threads_(threads),
        parallel_(threads.Parallel(mesh.num_elements())) {
    const int ne = mesh.num_elements(), nn = mesh.num_nodes();
    geometry_.reserve(ne);
    reference_volume_.reserve(ne);
    std::vector<std::vector<int>> elements_of(nn);
    for (int e = 0; e < ne; ++e) {
      geometry_.push_back(ComputeTet4Geometry(TetCorners(mesh, e)));
      reference_volume_.push_back(std::abs(geometry_[e].volume));
      for (int a : mesh.tets[e]) {
        elements_of[a].push_back(e);
      }
    }
    incidence_ = Flatten(elements_of);
    incidence_corner_.resize(incidence_.index.size());
    for (int a = 0; a < nn; ++a) {
      for (int t = incidence_.begin(a); t < incidence_.end(a); ++t) {
        const auto& tet = mesh.tets[incidence_.index[t]];
        incidence_corner_[t] = static_cast<int>(std::find(tet.begin(), tet.end(), a) - tet.begin());
      }
    }

    groups_ = std::make_unique<NodalGroups>(incidence_, reference_volume_, field_, nn);
    element_group_.resize(4 * static_cast<std::size_t>(ne));
    for (int a = 0; a < nn; ++a) {
      for (int t = incidence_.begin(a); t < incidence_.end(a); ++t) {
        element_group_[4 * incidence_.index[t] + incidence_corner_[t]] = groups_->of_incidence[t];
      }
    }

    // Patch of a: the nodes of the elements around a (a included), sorted.
    std::vector<std::vector<int>> rows(nn);
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (parallel_)
    for (int a = 0; a < nn; ++a) {
      for (int e : elements_of[a]) {
        rows[a].insert(rows[a].end(), mesh.tets[e].begin(), mesh.tets[e].end());
      }
      std::sort(rows[a].begin(), rows[a].end());
      rows[a].erase(std::unique(rows[a].begin(), rows[a].end()), rows[a].end());
    }
    patch_ = Flatten(rows);
    group_patch_.assign(groups_->size() + 1, 0);
    for (int a = 0; a < nn; ++a) {
      for (int q = groups_->of_node.begin(a); q < groups_->of_node.end(a); ++q) {
        const int group = groups_->of_node.index[q];
        group_patch_[group + 1] = patch_.end(a) - patch_.begin(a);
      }
    }
    for (int group = 0; group < groups_->size(); ++group) {
      group_patch_[group + 1] += group_patch_[group];
    }

    // Column c of K couples with every node of the patch of every node in
    // c's patch (the support of the g_a g_a^T terms that involve c).
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (parallel_)
    for (int c = 0; c < nn; ++c) {
      std::vector<int> wide;
      for (int m = patch_.begin(c); m < patch_.end(c); ++m) {
        const int a = patch_.index[m];
        wide.insert(wide.end(), patch_.index.begin() + patch_.begin(a),
                    patch_.index.begin() + patch_.end(a));
      }
      std::sort(wide.begin(), wide.end());
      wide.erase(std::unique(wide.begin(), wide.end()), wide.end());
      rows[c] = std::move(wide);
    }
    wide_ = Flatten(rows);

    // Lookups for the numeric passes, so they need no searching.
    patch_transpose_.resize(patch_.index.size());
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (parallel_)
    for (int c = 0; c < nn; ++c) {
      for (int m = patch_.begin(c); m < patch_.end(c); ++m) {
        patch_transpose_[m] = patch_.Find(patch_.index[m], c);
      }
    }
    incidence_patch_.resize(4 * incidence_.index.size());
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (parallel_)
    for (int a = 0; a < nn; ++a) {
      for (int t = incidence_.begin(a); t < incidence_.end(a); ++t) {
        const auto& tet = mesh.tets[incidence_.index[t]];
        for (int j = 0; j < 4; ++j) incidence_patch_[4 * t + j] = patch_.Find(a, tet[j]);
      }
    }
    element_block_.resize(16 * static_cast<std::size_t>(ne));
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (parallel_)
    for (int e = 0; e < ne; ++e) {
      const auto& tet = mesh.tets[e];
      for (int i = 0; i < 4; ++i) {
        for (int j = 0; j < 4; ++j) element_block_[16 * e + 4 * i + j] = wide_.Find(tet[j], tet[i]);
      }
    }
  }

  bool InternalForce(const Eigen::VectorXd& u, Eigen::VectorXd* force,
                     double* energy) const override {
    *force = Eigen::VectorXd::Zero(u.size());
    State state;
    if (Evaluate(u, false, false, nullptr, &state) >= 0) return false;
    GatherForce(state, nullptr, force);
    if (energy) *energy = state.energy;
    return force->allFinite() && std::isfinite(state.energy);
  }

  // As Assemble's share: every element's volume, the stress of those that
  // touch `own`'s nodes.
  bool InternalForceShare(const Eigen::VectorXd& u, const std::vector<char>& own,
                          Eigen::VectorXd* force) const override {
    *force = Eigen::VectorXd::Zero(u.size());
    const std::vector<char> touches = Touching(own);
    State state;
    if (Evaluate(u, false, false, &touches, &state) >= 0) return false;
    GatherForce(state, &own, force);
    return force->allFinite();
  }

  // Partitioned between ranks (options.own_nodes), a rank evaluates the
  // stress and tangent of the elements that touch its nodes, and the
  // volumes and their gradients of every element (cheap, and the nodal
  // pressures of those elements' corners need their whole patches); every
  // rank finds the same inverted element, as all see every det F.
  Status Assemble(const Eigen::VectorXd& u, const DofMap& dofs, const AssemblyOptions& options,
                  LinearSystem* system) const override {
    const std::vector<char>* own = options.own_nodes;
    const std::vector<char> touches = own != nullptr ? Touching(*own) : std::vector<char>();
    State state;
    const int bad = Evaluate(u, true, options.drop_pressure_stiffness,
                             own != nullptr ? &touches : nullptr, &state);
    if (bad >= 0) {
      return Status::Numerical("element " + std::to_string(bad) +
                               " could not be evaluated (inverted: det F <= 0)");
    }
    Eigen::VectorXd force = Eigen::VectorXd::Zero(u.size());
    GatherForce(state, own, &force);
    const std::vector<Eigen::Matrix3d> blocks = NodeBlocks(state, own);
    FillSystem(force, blocks, dofs, options, system);
    if (own != nullptr) PBA_RETURN_IF_ERROR(SumOverRanks(system->rhs.data(), dofs.num_free()));
    return Status::Ok();
  }

  std::string Describe() const override {
    return "TET4 with average nodal pressure (nodal volumetric energy), total Lagrangian";
  }

  // Each element's pressure and volume ratio are the means over its corners
  // of U'(J_a) and J_a, the nodal volume ratios its volumetric energy is
  // written in (its own det F carries the volumetric noise the element
  // would lock on).
  double RecoverFields(const Eigen::VectorXd& u, Solution* solution) const override {
    std::vector<double> pressure, volume_ratio;
    AverageNodalPressures(mesh_, field_, u, &pressure, &volume_ratio);
    return RecoverFiniteStrainFields(
        mesh_.num_elements(), threads_, solution, [&](int e, ElementFieldSum* sum) {
          const Tet4Geometry& g = geometry_[e];
          sum->Add(g.volume,
                   FieldsAt(field_.At(e), DeformationGradient(g, GatherElement(mesh_, e, u)),
                            pressure[e], volume_ratio[e]));
        });
  }

 private:
  // Per element: whether it touches one of `own`'s nodes.
  std::vector<char> Touching(const std::vector<char>& own) const {
    std::vector<char> touches(mesh_.num_elements());
    for (int e = 0; e < mesh_.num_elements(); ++e) touches[e] = TouchesAny(mesh_.tets[e], own);
    return touches;
  }

  // Elements and nodes at `u`. Returns the lowest index of an element that is
  // inverted or not finite, -1 when all are fine. With `evaluated` (one flag
  // per element; may be null), the elements not flagged get only their
  // volume and its gradient, which the nodal pressures need (no stress, no
  // force, no tangent), and the energy is not the body's.
  int Evaluate(const Eigen::VectorXd& u, bool with_tangent, bool drop_pressure_stiffness,
               const std::vector<char>* evaluated, State* state) const {
    const int ne = mesh_.num_elements(), nn = mesh_.num_nodes();
    state->elements.resize(ne);
    if (with_tangent) state->tangents.resize(ne);
    int bad = ne;
    // clang-format splits "min : bad" across the continuation.
    // clang-format off
#pragma omp parallel for schedule(static) reduction(min : bad) \
    num_threads(threads_.threads()) if (parallel_)
    // clang-format on
    for (int e = 0; e < ne; ++e) {
      const Tet4Geometry& g = geometry_[e];
      ElementState& s = state->elements[e];
      s.f = DeformationGradient(g, GatherElement(mesh_, e, u));
      const double j = s.f.determinant();
      // Checked here because the material aborts on det F <= 0.
      if (!(j > 0) || !s.f.allFinite()) {
        bad = std::min(bad, e);
        continue;
      }
      const double v0 = reference_volume_[e];
      s.volume = v0 * j;
      // cof F by columns: (f2 x f3, f3 x f1, f1 x f2), no inverse needed.
      Eigen::Matrix3d cof;
      cof.col(0) = s.f.col(1).cross(s.f.col(2));
      cof.col(1) = s.f.col(2).cross(s.f.col(0));
      cof.col(2) = s.f.col(0).cross(s.f.col(1));
      for (int a = 0; a < 4; ++a) {
        s.volume_gradient.segment<3>(3 * a) = v0 * cof * g.grad.row(a).transpose();
      }
      if (evaluated != nullptr && !(*evaluated)[e]) {
        s.force.setZero();
        s.iso_energy = 0;
        continue;
      }
      Vector6d stress;
      Matrix6d tangent;
      field_.At(e).Isochoric(s.f, &s.iso_energy, &stress, with_tangent ? &tangent : nullptr);
      s.iso_energy *= v0;
      const BMatrix b = GreenLagrangeVariation(g, s.f);
      s.force = v0 * b.transpose() * stress;
      if (with_tangent) {
        Matrix12d& k = state->tangents[e];
        k = v0 * b.transpose() * tangent * b;
        // Geometric stiffness of S_iso: (G_a . S_iso G_c) I.
        const Eigen::Matrix<double, 4, 4> geo =
            g.grad * VoigtToSymmetric(stress) * g.grad.transpose();
        for (int a = 0; a < 4; ++a) {
          for (int c = 0; c < 4; ++c)
            k.block<3, 3>(3 * a, 3 * c).diagonal().array() += v0 * geo(a, c);
        }
      }
    }
    if (bad < ne) return bad;

    const NodalGroups& groups = *groups_;
    state->nodal.assign(groups.size(), ScalarDerivatives());
    double energy = 0;
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (parallel_) reduction(+ : energy)
    for (int a = 0; a < nn; ++a) {
      for (int g = groups.of_node.begin(a); g < groups.of_node.end(a); ++g) {
        const int group = groups.of_node.index[g];
        double v = 0;
        for (int t = incidence_.begin(a); t < incidence_.end(a); ++t) {
          if (groups.of_incidence[t] == group) v += state->elements[incidence_.index[t]].volume / 4;
        }
        state->nodal[group] = GroupVolumetric(field_, groups, group, v / groups.volume[group]);
        energy += groups.volume[group] * state->nodal[group].value;
      }
    }

#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (parallel_) reduction(+ : energy)
    for (int e = 0; e < ne; ++e) {
      if (evaluated != nullptr && !(*evaluated)[e]) continue;
      ElementState& s = state->elements[e];
      energy += s.iso_energy;
      double pbar = 0;
      for (int i = 0; i < 4; ++i) pbar += state->nodal[element_group_[4 * e + i]].first / 4;
      s.force += pbar * s.volume_gradient;
      if (!with_tangent || drop_pressure_stiffness) continue;
      Matrix12d& k = state->tangents[e];
      const Tet4Geometry& g = geometry_[e];
      for (int b = 0; b < 4; ++b) {
        for (int c = b + 1; c < 4; ++c) {
          const Eigen::Vector3d gb = g.grad.row(b).transpose(), gc = g.grad.row(c).transpose();
          const Eigen::Matrix3d block = -pbar * reference_volume_[e] * Skew(s.f * gb.cross(gc));
          k.block<3, 3>(3 * b, 3 * c) += block;
          k.block<3, 3>(3 * c, 3 * b) += block.transpose();
        }
      }
    }
    state->energy = energy;
    return -1;
  }

  // Full internal force, node by node (a gather: no two threads write one
  // entry); with `own` (may be null), on those nodes only, zero elsewhere.
  void GatherForce(const State& state, const std::vector<char>* own, Eigen::VectorXd* force) const {
    const int nn = mesh_.num_nodes();
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (parallel_)
    for (int a = 0; a < nn; ++a) {
      if (own != nullptr && !(*own)[a]) continue;
      Eigen::Vector3d f = Eigen::Vector3d::Zero();
      for (int t = incidence_.begin(a); t < incidence_.end(a); ++t) {
        f += state.elements[incidence_.index[t]].force.segment<3>(3 * incidence_corner_[t]);
      }
      force->segment<3>(3 * a) = f;
    }
  }

  // The 3 x 3 blocks of K on the wide node pattern: blocks[k] is K_bc for
  // column node c and row node b = wide_.index[k], k in c's row of wide_.
  // Each column is gathered by one thread from the element tangents and the
  // nodal g_a g_a^T terms, so the pass needs neither colouring nor locks.
  // With `own` (may be null), the columns of those nodes only (the others'
  // blocks are left unset).
  std::vector<Eigen::Matrix3d> NodeBlocks(const State& state, const std::vector<char>* own) const {
    const int nn = mesh_.num_nodes();
    const NodalGroups& groups = *groups_;
    // g_g = dv_g/dx on the patch of the group's node, one vector per patch
    // entry: group g's vectors start at group_patch_[g], entry m of node a's
    // patch at group_patch_[g] + m - patch_.begin(a).
    std::vector<Eigen::Vector3d> g(group_patch_.back());
    std::vector<double> weight(groups.size(), 0.0);
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (parallel_)
    for (int a = 0; a < nn; ++a) {
      for (int q = groups.of_node.begin(a); q < groups.of_node.end(a); ++q) {
        const int group = groups.of_node.index[q];
        for (int m = 0; m < patch_.end(a) - patch_.begin(a); ++m)
          g[group_patch_[group] + m].setZero();
        weight[group] = state.nodal[group].second / groups.volume[group];
      }
      for (int t = incidence_.begin(a); t < incidence_.end(a); ++t) {
        const ElementState& s = state.elements[incidence_.index[t]];
        const int base = group_patch_[groups.of_incidence[t]] - patch_.begin(a);
        for (int j = 0; j < 4; ++j) {
          g[base + incidence_patch_[4 * t + j]] += s.volume_gradient.segment<3>(3 * j) / 4;
        }
      }
    }

    std::vector<Eigen::Matrix3d> blocks(wide_.index.size());
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (parallel_)
    for (int c = 0; c < nn; ++c) {
      if (own != nullptr && !(*own)[c]) continue;
      for (int k = wide_.begin(c); k < wide_.end(c); ++k) blocks[k].setZero();
      for (int t = incidence_.begin(c); t < incidence_.end(c); ++t) {
        const int e = incidence_.index[t], j = incidence_corner_[t];
        for (int i = 0; i < 4; ++i) {
          blocks[element_block_[16 * e + 4 * i + j]] += state.tangents[e].block<3, 3>(3 * i, 3 * j);
        }
      }
      for (int m = patch_.begin(c); m < patch_.end(c); ++m) {
        const int a = patch_.index[m];
        for (int q = groups.of_node.begin(a); q < groups.of_node.end(a); ++q) {
          const int group = groups.of_node.index[q];
          const int base = group_patch_[group] - patch_.begin(a);
          const Eigen::Vector3d gc = weight[group] * g[base + patch_transpose_[m]];
          if (gc.isZero(0)) continue;  // c is not in the group's elements
          // a's patch is sorted and contained in c's sorted wide row: a
          // merge walk.
          int k = wide_.begin(c);
          for (int n = patch_.begin(a); n < patch_.end(a); ++n) {
            while (wide_.index[k] != patch_.index[n]) ++k;
            blocks[k] += g[base + n] * gc.transpose();
          }
        }
      }
    }
    return blocks;
  }

  // K_ff (compressed columns, both triangles) and rhs = -f_f (- K_fp u_p).
  void FillSystem(const Eigen::VectorXd& force, const std::vector<Eigen::Matrix3d>& blocks,
                  const DofMap& dofs, const AssemblyOptions& options, LinearSystem* system) const {
    const int nn = mesh_.num_nodes(), nf = dofs.num_free();
    std::vector<int> free_of_node(nn, 0);
    for (int b = 0; b < nn; ++b) {
      for (int r = 0; r < 3; ++r) free_of_node[b] += dofs.free_index(3 * b + r) >= 0;
    }
    // Free unknowns are numbered in dof order, so walking nodes and rows in
    // ascending order yields sorted columns with sorted row indices.
    // A partitioned assembly fills its own nodes' columns and rows only.
    const std::vector<char>* own = options.own_nodes;
    system->own_nodes = own;
    std::vector<int> outer(nf + 1, 0);
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (parallel_)
    for (int c = 0; c < nn; ++c) {
      if (own != nullptr && !(*own)[c]) continue;
      int count = 0;
      for (int k = wide_.begin(c); k < wide_.end(c); ++k) count += free_of_node[wide_.index[k]];
      for (int q = 0; q < 3; ++q) {
        const int j = dofs.free_index(3 * c + q);
        if (j >= 0) outer[j + 1] = count;
      }
    }
    for (int j = 0; j < nf; ++j) outer[j + 1] += outer[j];

    SparseMatrix& k = system->k;
    k.resize(nf, nf);
    k.resizeNonZeros(outer[nf]);
    std::copy(outer.begin(), outer.end(), k.outerIndexPtr());
    int* inner = k.innerIndexPtr();
    double* values = k.valuePtr();
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (parallel_)
    for (int c = 0; c < nn; ++c) {
      if (own != nullptr && !(*own)[c]) continue;
      for (int q = 0; q < 3; ++q) {
        const int j = dofs.free_index(3 * c + q);
        if (j < 0) continue;
        int at = outer[j];
        for (int w = wide_.begin(c); w < wide_.end(c); ++w) {
          const int b = wide_.index[w];
          for (int r = 0; r < 3; ++r) {
            const int i = dofs.free_index(3 * b + r);
            if (i < 0) continue;
            inner[at] = i;
            values[at] = blocks[w](r, q);
            ++at;
          }
        }
      }
    }

    system->rhs.setZero(nf);
#pragma omp parallel for schedule(static) num_threads(threads_.threads()) if (parallel_)
    for (int b = 0; b < nn; ++b) {
      if (own != nullptr && !(*own)[b]) continue;
      for (int r = 0; r < 3; ++r) {
        const int i = dofs.free_index(3 * b + r);
        if (i < 0) continue;
        double rhs = -force(3 * b + r);
        if (options.lift_prescribed) {
          // K(b r, c q) = K(c q, b r) = blocks[w](q, r) with w in b's column:
          // K is symmetric, and reading b's own column keeps the row private.
          for (int w = wide_.begin(b); w < wide_.end(b); ++w) {
            const int c = wide_.index[w];
            for (int q = 0; q < 3; ++q) {
              const int dof = 3 * c + q;
              if (dofs.prescribed(dof) && dofs.prescribed_value(dof) != 0.0) {
                rhs -= blocks[w](q, r) * dofs.prescribed_value(dof);
              }
            }
          }
        }
        system->rhs(i) = rhs;
      }
    }
  }

  const Mesh& mesh_;
  std::unique_ptr<MaterialField> owned_;  // a uniform field made for one material
  const MaterialField& field_;
  const ThreadContext threads_;
  const bool parallel_;  // threads_.Parallel(elements)
  std::vector<Tet4Geometry> geometry_;
  std::vector<double> reference_volume_;  // V_e
  std::unique_ptr<NodalGroups> groups_;   // the nodal volumetric constraints
  std::vector<int> element_group_;        // group of corner i of element e, 4 e + i
  std::vector<int> group_patch_;          // offsets of the groups' patch vectors
  Csr incidence_;                         // elements around each node
  std::vector<int> incidence_corner_;     // which corner of the element the node is
  Csr patch_;                             // nodes of those elements, sorted
  Csr wide_;                              // node pattern of K, sorted
  // For patch entry m (row c, node a): the entry of c in a's patch.
  std::vector<int> patch_transpose_;
  // For incidence t (node a, element e) and corner j: the entry of
  // tets[e][j] in a's patch.
  std::vector<int> incidence_patch_;
  // For element e, corners i (row) and j (column): the entry of block
  // (tets[e][i], tets[e][j]) in wide_.
  std::vector<int> element_block_;
};

}  // namespace

std::unique_ptr<FiniteStrainModel> MakeAverageNodalPressureTet4Model(
    const Mesh& mesh, const HyperelasticMaterial& material) {
  auto field = MaterialField::Uniform(material, mesh.num_elements());
  const MaterialField& view = *field;
  return std::make_unique<NodalPressureModel>(mesh, view, ThreadContext(), std::move(field));
}

std::unique_ptr<FiniteStrainModel> MakeAverageNodalPressureTet4Model(const Mesh& mesh,
                                                                     const MaterialField& field,
                                                                     const ThreadContext& threads) {
  return std::make_unique<NodalPressureModel>(mesh, field, threads);
}

void AverageNodalPressures(const Mesh& mesh, const MaterialField& field, const Eigen::VectorXd& u,
                           std::vector<double>* pressure, std::vector<double>* volume_ratio) {
  const int ne = mesh.num_elements(), nn = mesh.num_nodes();
  std::vector<double> reference_volume(ne), jacobian(ne);
  std::vector<std::vector<int>> elements_of(nn);
  for (int e = 0; e < ne; ++e) {
    const Tet4Geometry g = ComputeTet4Geometry(TetCorners(mesh, e));
    reference_volume[e] = std::abs(g.volume);
    jacobian[e] = DeformationGradient(g, GatherElement(mesh, e, u)).determinant();
    for (int a : mesh.tets[e]) elements_of[a].push_back(e);
  }
  const Csr incidence = Flatten(elements_of);
  const NodalGroups groups(incidence, reference_volume, field, nn);
  std::vector<double> v(groups.size(), 0.0);
  for (std::size_t t = 0; t < incidence.index.size(); ++t) {
    const int e = incidence.index[t];
    v[groups.of_incidence[t]] += jacobian[e] * reference_volume[e] / 4;
  }
  pressure->assign(ne, 0.0);
  volume_ratio->assign(ne, 0.0);
  for (std::size_t t = 0; t < incidence.index.size(); ++t) {
    const int e = incidence.index[t], group = groups.of_incidence[t];
    const double j = v[group] / groups.volume[group];
    (*pressure)[e] += GroupVolumetric(field, groups, group, j).first / 4;
    (*volume_ratio)[e] += j / 4;
  }
}

}  // namespace pba
