#include "assembly/assembler.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bitset>

#include "mesh/quadratic.h"

namespace pba {
namespace {

constexpr int kMaxColours = 256;

// Compressed-column pattern of K_ff: the free unknowns of every node pair that
// shares an element.
struct Pattern {
  std::vector<int> outer;  // num_free + 1
  std::vector<int> inner;  // row (free index) of each stored entry, sorted per column

  int Find(int row, int col) const {
    const auto begin = inner.begin() + outer[col], end = inner.begin() + outer[col + 1];
    return static_cast<int>(std::lower_bound(begin, end, row) - inner.begin());
  }
};

// `nodes_of(e)` gives element e's node indices (a std::array).
template <typename NodesOf>
Pattern BuildPattern(const Mesh& mesh, const NodesOf& nodes_of, const DofMap& dofs) {
  const int n = mesh.num_nodes();
  std::vector<std::vector<int>> neighbours(n);
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto t = nodes_of(e);
    for (int a : t) neighbours[a].insert(neighbours[a].end(), t.begin(), t.end());
  }
  Pattern p;
  p.outer.assign(dofs.num_free() + 1, 0);
  for (int b = 0; b < n; ++b) {
    auto& list = neighbours[b];
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    for (int j = 0; j < 3; ++j) {
      const int col = dofs.free_index(3 * b + j);
      if (col < 0) continue;
      for (int a : list) {
        for (int i = 0; i < 3; ++i) {
          const int row = dofs.free_index(3 * a + i);
          if (row >= 0) p.inner.push_back(row);
        }
      }
      p.outer[col + 1] = static_cast<int>(p.inner.size());
    }
    std::vector<int>().swap(list);
  }
  return p;
}

// Greedy colouring of `elements` (node index arrays) on `num_nodes` nodes.
template <std::size_t N>
std::vector<std::vector<int>> Colour(int num_nodes,
                                     const std::vector<std::array<int, N>>& elements) {
  std::vector<std::bitset<kMaxColours>> used(num_nodes);
  std::vector<std::vector<int>> colours;
  for (int e = 0; e < static_cast<int>(elements.size()); ++e) {
    std::bitset<kMaxColours> taken;
    for (int a : elements[e]) taken |= used[a];
    int c = 0;
    while (c < kMaxColours && taken[c]) ++c;
    // Structured tetrahedral meshes need a few dozen colours; running out
    // would mean a node in hundreds of elements, a broken mesh.
    if (c == kMaxColours) c = kMaxColours - 1;
    if (c >= static_cast<int>(colours.size())) colours.resize(c + 1);
    colours[c].push_back(e);
    for (int a : elements[e]) used[a].set(c);
  }
  return colours;
}

}  // namespace

std::vector<std::vector<int>> ColourElements(const Mesh& mesh) {
  if (mesh.hexahedral()) return Colour(mesh.num_nodes(), mesh.hexes);
  return Colour(mesh.num_nodes(), mesh.tets);
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
// Smallest colour assembled by a team of threads.
constexpr int kParallelColourFrom = 64;

template <int N, typename NodesOf, typename Kernel>
Status AssembleElements(const Mesh& mesh, const NodesOf& nodes_of, const DofMap& dofs,
                        const std::vector<std::vector<int>>& colours, const Kernel& kernel,
                        const AssemblyOptions& options,
                        const std::function<bool(double)>& keep_going, LinearSystem* system) {
  constexpr int kUnknowns = 3 * N;
  const Pattern pattern = BuildPattern(mesh, nodes_of, dofs);
  std::vector<double> values(pattern.inner.size(), 0.0);
  system->rhs = Eigen::VectorXd::Zero(dofs.num_free());
  double* rhs = system->rhs.data();
  std::atomic<int> failed{-1};

  std::size_t done = 0;
  const std::size_t total = static_cast<std::size_t>(mesh.num_elements());
  // Elements of the last colour may share nodes (see ColourElements), so it
  // is assembled by one thread; so is a colour too small to repay starting
  // a team (a Newton solve on a small mesh assembles thousands of times,
  // and oversubscribed threads make each parallel region cost milliseconds).
  for (std::size_t c = 0; c < colours.size() && failed.load() < 0; ++c) {
    const std::vector<int>& elements = colours[c];
    const bool serial = c + 1 == static_cast<std::size_t>(kMaxColours) ||
                        elements.size() < static_cast<std::size_t>(kParallelColourFrom);
#pragma omp parallel for schedule(static) if (!serial)
    for (std::size_t k = 0; k < elements.size(); ++k) {
      if (failed.load(std::memory_order_relaxed) >= 0) continue;
      const int e = elements[k];
      Eigen::Matrix<double, kUnknowns, kUnknowns> ke;
      Eigen::Matrix<double, kUnknowns, 1> fe;
      if (!kernel(e, &ke, &fe)) {
        failed.store(e);
        continue;
      }
      int free[kUnknowns];
      double up[kUnknowns];
      const auto nodes = nodes_of(e);
      for (int a = 0; a < N; ++a) {
        for (int i = 0; i < 3; ++i) {
          const int dof = 3 * nodes[a] + i;
          free[3 * a + i] = dofs.free_index(dof);
          up[3 * a + i] =
              options.lift_prescribed && dofs.prescribed(dof) ? dofs.prescribed_value(dof) : 0.0;
        }
      }
      for (int p = 0; p < kUnknowns; ++p) {
        if (free[p] >= 0) rhs[free[p]] += fe(p);
      }
      for (int q = 0; q < kUnknowns; ++q) {
        if (free[q] < 0) {
          if (up[q] == 0.0) continue;
          for (int p = 0; p < kUnknowns; ++p) {
            if (free[p] >= 0) rhs[free[p]] -= ke(p, q) * up[q];
          }
          continue;
        }
        for (int p = 0; p < kUnknowns; ++p) {
          if (free[p] >= 0) values[pattern.Find(free[p], free[q])] += ke(p, q);
        }
      }
    }
    done += elements.size();
    if (failed.load() < 0 && !keep_going(static_cast<double>(done) / static_cast<double>(total))) {
      return Status::Cancelled("cancelled during assembly");
    }
  }
  if (failed.load() >= 0) {
    return Status::Numerical("element " + std::to_string(failed.load()) +
                             " could not be evaluated (inverted: det F <= 0)");
  }
  const int n = dofs.num_free();
  system->k =
      Eigen::Map<const SparseMatrix>(n, n, static_cast<int>(values.size()), pattern.outer.data(),
                                     pattern.inner.data(), values.data());
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

Status AssembleLinearSystem(const Mesh& mesh, const Matrix6d& d, const DofMap& dofs,
                            const std::vector<std::vector<int>>& colours,
                            const std::function<bool(double)>& keep_going, LinearSystem* system) {
  const ElementKernel kernel = [&](int e, Matrix12d* k, Vector12d* f) {
    *k = Tet4Stiffness(ComputeTet4Geometry(TetCorners(mesh, e)), d);
    f->setZero();
    return true;
  };
  AssemblyOptions options;
  options.lift_prescribed = true;
  return AssembleSystem(mesh, dofs, colours, kernel, options, keep_going, system);
}

Status AssembleLinearSystemTet10(const Mesh& mesh, const Matrix6d& d, const DofMap& dofs,
                                 const std::vector<std::vector<int>>& colours,
                                 const std::function<bool(double)>& keep_going,
                                 LinearSystem* system) {
  const Tet10ElementKernel kernel = [&](int e, Matrix30d* k, Vector30d* f) {
    *k = Tet10Stiffness(Tet10Coordinates(mesh, e), d);
    f->setZero();
    return true;
  };
  AssemblyOptions options;
  options.lift_prescribed = true;
  return AssembleSystemTet10(mesh, dofs, colours, kernel, options, keep_going, system);
}

namespace {

// The small-strain hexahedral assembly with element stiffness `stiffness`
// (Hex8Stiffness or Hex8StiffnessFull), prescribed values lifted.
Status AssembleLinearHex8(const Mesh& mesh, const Matrix6d& d,
                          Matrix24d (*stiffness)(const Hex8Nodes&, const Matrix6d&),
                          const DofMap& dofs, const std::vector<std::vector<int>>& colours,
                          const std::function<bool(double)>& keep_going, LinearSystem* system) {
  const Hex8ElementKernel kernel = [&](int e, Matrix24d* k, Vector24d* f) {
    *k = stiffness(Hex8Coordinates(mesh, e), d);
    f->setZero();
    return true;
  };
  AssemblyOptions options;
  options.lift_prescribed = true;
  return AssembleSystemHex8(mesh, dofs, colours, kernel, options, keep_going, system);
}

}  // namespace

Status AssembleLinearSystemHex8(const Mesh& mesh, const Matrix6d& d, const DofMap& dofs,
                                const std::vector<std::vector<int>>& colours,
                                const std::function<bool(double)>& keep_going,
                                LinearSystem* system) {
  return AssembleLinearHex8(mesh, d, Hex8Stiffness, dofs, colours, keep_going, system);
}

Status AssembleLinearSystemHex8Full(const Mesh& mesh, const Matrix6d& d, const DofMap& dofs,
                                    const std::vector<std::vector<int>>& colours,
                                    const std::function<bool(double)>& keep_going,
                                    LinearSystem* system) {
  return AssembleLinearHex8(mesh, d, Hex8StiffnessFull, dofs, colours, keep_going, system);
}

}  // namespace pba
