#include "assembly/assembler.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bitset>

#include "linear/petsc_runtime.h"
#include "mesh/quadratic.h"

namespace pba {
namespace {

constexpr int kMaxColours = 256;

// Builds in `k` (released beforehand by the caller) the compressed-column
// pattern of K_ff, all values zero: the free unknowns of every node pair
// that shares an element. `nodes_of(e)` gives element e's node indices (a
// std::array). Free unknowns are numbered in dof order (DofMap::Finalize),
// so walking nodes and components in ascending order gives sorted columns
// with sorted rows. The exact size is counted first and the row indices
// written straight into k, so that no growing vector or second copy of the
// pattern coexists with the matrix. With `own` (AssemblyOptions::own_nodes;
// may be null) only those nodes' columns have entries.
template <typename NodesOf>
void BuildPattern(const Mesh& mesh, const NodesOf& nodes_of, const DofMap& dofs,
                  const std::vector<char>* own, SparseMatrix* k) {
  const int n = mesh.num_nodes();
  std::vector<std::vector<int>> neighbours(n);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto t = nodes_of(e);
    for (int a : t) {
      if (own == nullptr || (*own)[a])
        neighbours[a].insert(neighbours[a].end(), t.begin(), t.end());
    }
  }
  std::vector<int> free_of_node(n, 0);
  for (int a = 0; a < n; ++a) {
    for (int i = 0; i < 3; ++i) free_of_node[a] += dofs.free_index(3 * a + i) >= 0;
  }
  const int num_free = dofs.num_free();
  k->resize(num_free, num_free);
  int* outer = k->outerIndexPtr();
  outer[0] = 0;
  Eigen::Index total = 0;
  for (int b = 0; b < n; ++b) {
    auto& list = neighbours[b];
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    list.shrink_to_fit();
    int rows = 0;
    for (int a : list) rows += free_of_node[a];
    for (int j = 0; j < 3; ++j) {
      const int col = dofs.free_index(3 * b + j);
      if (col < 0) continue;
      total += rows;
      outer[col + 1] = static_cast<int>(total);
    }
  }
  k->resizeNonZeros(total);
  int* inner = k->innerIndexPtr();
  for (int b = 0; b < n; ++b) {
    const auto& list = neighbours[b];
    for (int j = 0; j < 3; ++j) {
      const int col = dofs.free_index(3 * b + j);
      if (col < 0) continue;
      int at = outer[col];
      for (int a : list) {
        for (int i = 0; i < 3; ++i) {
          const int row = dofs.free_index(3 * a + i);
          if (row >= 0) inner[at++] = row;
        }
      }
    }
    std::vector<int>().swap(neighbours[b]);
  }
  std::fill(k->valuePtr(), k->valuePtr() + total, 0.0);
}

// True when `system->k` has the pattern that BuildPattern would build for
// elements of `nodes_per_element` nodes of `mesh` under `dofs` (see
// LinearSystem::pattern_source).
bool SamePattern(const LinearSystem& system, const Mesh& mesh, int nodes_per_element,
                 const DofMap& dofs, const std::vector<char>* own) {
  const PatternSource& source = system.pattern_source;
  const int n = dofs.num_free();
  if (source.mesh != &mesh || source.own_nodes != own ||
      source.num_elements != mesh.num_elements() || source.nodes_per_element != nodes_per_element ||
      system.k.rows() != n || system.k.cols() != n || !system.k.isCompressed() ||
      system.k.nonZeros() != source.non_zeros ||
      static_cast<int>(source.free_index.size()) != dofs.num_dofs()) {
    return false;
  }
  for (int dof = 0; dof < dofs.num_dofs(); ++dof) {
    if (source.free_index[dof] != dofs.free_index(dof)) return false;
  }
  return true;
}

}  // namespace

// Greedy, on the corners (see assembler.h for why they suffice).
std::vector<std::vector<int>> ColourElements(const Mesh& mesh) {
  std::vector<std::bitset<kMaxColours>> used(mesh.num_nodes());
  std::vector<std::vector<int>> colours;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const NodeList corners = mesh.ElementCorners(e);
    std::bitset<kMaxColours> taken;
    for (int a : corners) taken |= used[a];
    int c = 0;
    while (c < kMaxColours && taken[c]) ++c;
    // Structured tetrahedral meshes need a few dozen colours; running out
    // would mean a node in hundreds of elements, a broken mesh.
    if (c == kMaxColours) c = kMaxColours - 1;
    if (c >= static_cast<int>(colours.size())) colours.resize(c + 1);
    colours[c].push_back(e);
    for (int a : corners) used[a].set(c);
  }
  return colours;
}

Vector12d GatherElement(const Mesh& mesh, int e, const Eigen::VectorXd& u) {
  Vector12d ue;
  for (int a = 0; a < 4; ++a) ue.segment<3>(3 * a) = u.segment<3>(3 * mesh.tets[e][a]);
  return ue;
}

Vector30d GatherElementTet10(const Mesh& mesh, int e, const Eigen::VectorXd& u) {
  Vector30d ue;
  const std::array<int, 10> nodes = Tet10NodeIndices(mesh, e);
  for (int a = 0; a < 10; ++a) ue.segment<3>(3 * a) = u.segment<3>(3 * nodes[a]);
  return ue;
}

Vector24d GatherElementHex8(const Mesh& mesh, int e, const Eigen::VectorXd& u) {
  Vector24d ue;
  for (int a = 0; a < 8; ++a) ue.segment<3>(3 * a) = u.segment<3>(3 * mesh.hexes[e][a]);
  return ue;
}

Hex8Nodes Hex8Coordinates(const Mesh& mesh, int e) {
  Hex8Nodes x;
  for (int a = 0; a < 8; ++a) x.row(a) = mesh.nodes.row(mesh.hexes[e][a]);
  return x;
}

namespace {

// The assembly of AssembleSystem for elements of N nodes: `nodes_of(e)`
// gives their indices, `kernel` their 3N x 3N stiffness and 3N force.
template <int N, typename NodesOf, typename Kernel>
Status AssembleElements(const Mesh& mesh, const NodesOf& nodes_of, const DofMap& dofs,
                        const std::vector<std::vector<int>>& colours, const Kernel& kernel,
                        const AssemblyOptions& options,
                        const std::function<bool(double)>& keep_going, LinearSystem* system) {
  constexpr int kUnknowns = 3 * N;
  SparseMatrix& matrix = system->k;
  const std::vector<char>* own = options.own_nodes;
  const bool reused = SamePattern(*system, mesh, N, dofs, own);
  if (reused) {
    std::fill(matrix.valuePtr(), matrix.valuePtr() + matrix.nonZeros(), 0.0);
  } else {
    // The old matrix goes first, so that it never coexists with the new one.
    system->pattern_source = PatternSource();
    matrix = SparseMatrix();
    BuildPattern(mesh, nodes_of, dofs, own, &matrix);
    PatternSource& source = system->pattern_source;
    source.mesh = &mesh;
    source.own_nodes = own;
    source.num_elements = mesh.num_elements();
    source.nodes_per_element = N;
    source.free_index.resize(dofs.num_dofs());
    for (int dof = 0; dof < dofs.num_dofs(); ++dof) source.free_index[dof] = dofs.free_index(dof);
    source.non_zeros = matrix.nonZeros();
  }
  const int* outer = matrix.outerIndexPtr();
  const int* inner = matrix.innerIndexPtr();
  double* values = matrix.valuePtr();
  // Position of entry (row, col) in k, or -1 when the pattern lacks it.
  const auto find = [&](int row, int col) {
    const int* begin = inner + outer[col];
    const int* end = inner + outer[col + 1];
    const int* at = std::lower_bound(begin, end, row);
    return at != end && *at == row ? static_cast<int>(at - inner) : -1;
  };
  system->rhs.setZero(dofs.num_free());
  system->own_nodes = own;
  double* rhs = system->rhs.data();
  std::atomic<int> failed{-1};
  std::atomic<bool> missing{false};  // an element entry not in k's pattern
  bool cancelled = false;

  std::size_t done = 0;
  const std::size_t total = static_cast<std::size_t>(mesh.num_elements());
  // Elements of the last colour may share nodes (see ColourElements), so it
  // is assembled by one thread; so is a colour too small to repay starting
  // a team (a Newton solve on a small mesh assembles thousands of times,
  // and oversubscribed threads make each parallel region cost milliseconds).
  for (std::size_t c = 0; c < colours.size() && failed.load() < 0 && !missing.load() && !cancelled;
       ++c) {
    const std::vector<int>& elements = colours[c];
    const bool serial = c + 1 == static_cast<std::size_t>(kMaxColours) ||
                        !options.threads.Parallel(elements.size());
#pragma omp parallel for schedule(static) num_threads(options.threads.threads()) if (!serial)
    for (std::size_t k = 0; k < elements.size(); ++k) {
      if (failed.load(std::memory_order_relaxed) >= 0 || missing.load(std::memory_order_relaxed)) {
        continue;
      }
      const int e = elements[k];
      const auto nodes = nodes_of(e);
      // A partitioned assembly: the elements that touch this rank's nodes,
      // into those nodes' columns of K and rows of the right-hand side.
      bool mine[N];
      bool any = false;
      for (int a = 0; a < N; ++a) {
        mine[a] = own == nullptr || (*own)[nodes[a]];
        any = any || mine[a];
      }
      if (!any) continue;
      Eigen::Matrix<double, kUnknowns, kUnknowns> ke;
      Eigen::Matrix<double, kUnknowns, 1> fe;
      if (!kernel(e, &ke, &fe)) {
        failed.store(e);
        continue;
      }
      // free: the unknown's index in K (-1: prescribed); row: the same
      // where this rank assembles the unknown's row and column, else -1.
      int free[kUnknowns], row[kUnknowns];
      double up[kUnknowns];
      for (int a = 0; a < N; ++a) {
        for (int i = 0; i < 3; ++i) {
          const int dof = 3 * nodes[a] + i;
          free[3 * a + i] = dofs.free_index(dof);
          row[3 * a + i] = mine[a] ? free[3 * a + i] : -1;
          up[3 * a + i] =
              options.lift_prescribed && dofs.prescribed(dof) ? dofs.prescribed_value(dof) : 0.0;
        }
      }
      for (int p = 0; p < kUnknowns; ++p) {
        if (row[p] >= 0) rhs[row[p]] += fe(p);
      }
      for (int q = 0; q < kUnknowns; ++q) {
        if (free[q] >= 0 && row[q] < 0) continue;  // another rank's column
        if (free[q] < 0) {
          if (up[q] == 0.0) continue;
          for (int p = 0; p < kUnknowns; ++p) {
            if (row[p] >= 0) rhs[row[p]] -= ke(p, q) * up[q];
          }
          continue;
        }
        for (int p = 0; p < kUnknowns; ++p) {
          if (free[p] < 0) continue;
          const int at = find(free[p], free[q]);
          if (at < 0) {
            missing.store(true);
            break;
          }
          values[at] += ke(p, q);
        }
      }
    }
    done += elements.size();
    if (failed.load() < 0 && !missing.load() &&
        !keep_going(static_cast<double>(done) / static_cast<double>(total))) {
      cancelled = true;
    }
  }
  // What one rank of a partitioned assembly met, every rank acts on: an
  // error on one, a return on the others, would leave them waiting.
  int outcome[4] = {failed.load(), missing.load() ? 1 : 0, missing.load() && !reused ? 1 : 0,
                    cancelled ? 1 : 0};
  if (own != nullptr) PBA_RETURN_IF_ERROR(MaxOverRanks(outcome, 4));
  if (outcome[3] != 0) return Status::Cancelled("cancelled during assembly");
  if (outcome[0] >= 0) {
    return Status::Numerical("element " + std::to_string(outcome[0]) +
                             " could not be evaluated (inverted: det F <= 0)");
  }
  if (outcome[2] != 0) {
    return Status::Internal("assembly: an element entry is missing from the pattern");
  }
  if (outcome[1] != 0) {
    // A reused pattern that lacks an entry: k was changed since it was
    // assembled (or the mesh was), so the pattern is built anew. A pattern
    // just built holds every element entry by construction.
    system->pattern_source = PatternSource();
    return AssembleElements<N>(mesh, nodes_of, dofs, colours, kernel, options, keep_going, system);
  }
  if (own != nullptr) PBA_RETURN_IF_ERROR(SumOverRanks(system->rhs.data(), dofs.num_free()));
  return Status::Ok();
}

}  // namespace

Status AssembleSystem(const Mesh& mesh, const DofMap& dofs,
                      const std::vector<std::vector<int>>& colours, const ElementKernel& kernel,
                      const AssemblyOptions& options, const std::function<bool(double)>& keep_going,
                      LinearSystem* system) {
  return AssembleElements<4>(
      mesh, [&](int e) { return mesh.tets[e]; }, dofs, colours, kernel, options, keep_going,
      system);
}

Status AssembleSystemTet10(const Mesh& mesh, const DofMap& dofs,
                           const std::vector<std::vector<int>>& colours,
                           const Tet10ElementKernel& kernel, const AssemblyOptions& options,
                           const std::function<bool(double)>& keep_going, LinearSystem* system) {
  return AssembleElements<10>(
      mesh, [&](int e) { return Tet10NodeIndices(mesh, e); }, dofs, colours, kernel, options,
      keep_going, system);
}

Status AssembleSystemHex8(const Mesh& mesh, const DofMap& dofs,
                          const std::vector<std::vector<int>>& colours,
                          const Hex8ElementKernel& kernel, const AssemblyOptions& options,
                          const std::function<bool(double)>& keep_going, LinearSystem* system) {
  return AssembleElements<8>(
      mesh, [&](int e) { return mesh.hexes[e]; }, dofs, colours, kernel, options, keep_going,
      system);
}

Status AssembleLinearSystem(const Mesh& mesh, const ElasticityField& elasticity, const DofMap& dofs,
                            const std::vector<std::vector<int>>& colours,
                            const std::function<bool(double)>& keep_going, LinearSystem* system,
                            const ThreadContext& threads) {
  const ElementKernel kernel = [&](int e, Matrix12d* k, Vector12d* f) {
    *k = Tet4Stiffness(ComputeTet4Geometry(TetCorners(mesh, e)), elasticity.D(e));
    f->setZero();
    return true;
  };
  AssemblyOptions options;
  options.lift_prescribed = true;
  options.threads = threads;
  return AssembleSystem(mesh, dofs, colours, kernel, options, keep_going, system);
}

Status AssembleLinearSystemTet10(const Mesh& mesh, const ElasticityField& elasticity,
                                 const DofMap& dofs, const std::vector<std::vector<int>>& colours,
                                 const std::function<bool(double)>& keep_going,
                                 LinearSystem* system, const ThreadContext& threads) {
  const Tet10ElementKernel kernel = [&](int e, Matrix30d* k, Vector30d* f) {
    *k = Tet10Stiffness(Tet10Coordinates(mesh, e), elasticity.D(e));
    f->setZero();
    return true;
  };
  AssemblyOptions options;
  options.lift_prescribed = true;
  options.threads = threads;
  return AssembleSystemTet10(mesh, dofs, colours, kernel, options, keep_going, system);
}

namespace {

// The small-strain hexahedral assembly with element stiffness `stiffness`
// (Hex8Stiffness or Hex8StiffnessFull), prescribed values lifted.
Status AssembleLinearHex8(const Mesh& mesh, const ElasticityField& elasticity,
                          Matrix24d (*stiffness)(const Hex8Nodes&, const Matrix6d&),
                          const DofMap& dofs, const std::vector<std::vector<int>>& colours,
                          const std::function<bool(double)>& keep_going, LinearSystem* system,
                          const ThreadContext& threads) {
  const Hex8ElementKernel kernel = [&](int e, Matrix24d* k, Vector24d* f) {
    *k = stiffness(Hex8Coordinates(mesh, e), elasticity.D(e));
    f->setZero();
    return true;
  };
  AssemblyOptions options;
  options.lift_prescribed = true;
  options.threads = threads;
  return AssembleSystemHex8(mesh, dofs, colours, kernel, options, keep_going, system);
}

}  // namespace

Status AssembleLinearSystemHex8(const Mesh& mesh, const ElasticityField& elasticity,
                                const DofMap& dofs, const std::vector<std::vector<int>>& colours,
                                const std::function<bool(double)>& keep_going, LinearSystem* system,
                                const ThreadContext& threads) {
  return AssembleLinearHex8(mesh, elasticity, Hex8Stiffness, dofs, colours, keep_going, system,
                            threads);
}

Status AssembleLinearSystemHex8Full(const Mesh& mesh, const ElasticityField& elasticity,
                                    const DofMap& dofs,
                                    const std::vector<std::vector<int>>& colours,
                                    const std::function<bool(double)>& keep_going,
                                    LinearSystem* system, const ThreadContext& threads) {
  return AssembleLinearHex8(mesh, elasticity, Hex8StiffnessFull, dofs, colours, keep_going, system,
                            threads);
}

}  // namespace pba
