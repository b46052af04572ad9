// Parallel assembly of the small-strain stiffness on the free unknowns.
//
// Elements are greedily coloured so that no two of one colour share a node;
// the elements of a colour are then assembled by all threads at once straight
// into a compressed matrix whose pattern was built beforehand — no global
// lock, no triplet list.
#pragma once

#include <Eigen/SparseCore>
#include <functional>
#include <vector>

#include "assembly/dof_map.h"
#include "core/thread_context.h"
#include "fem/hex8.h"
#include "fem/tet10.h"
#include "fem/tet4.h"
#include "linear/linear_solver.h"
#include "material/linear_elastic.h"
#include "mesh/mesh.h"
#include "pba/status.h"

namespace pba {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

// Element indices by colour; elements of one colour share no node. Made
// from the corners (Mesh::tets), it serves quadratic meshes too: elements
// that share no corner share no edge, hence no mid-edge node. For a
// hexahedral mesh, from the eight nodes of Mesh::hexes.
std::vector<std::vector<int>> ColourElements(const Mesh& mesh);

// What the pattern of LinearSystem::k was built from. A Newton solve
// reassembles the same mesh with the same free unknowns many times; the
// pattern (which entries of K_ff exist) is then the same each time, and
// rebuilding it, and holding a second matrix while the new one is made,
// cost time and memory (about three times the matrix at the end of each
// assembly).
struct PatternSource {
  const Mesh* mesh = nullptr;  // compared, never dereferenced
  int num_elements = 0;
  int nodes_per_element = 0;
  std::vector<int> free_index;                   // DofMap::free_index of every dof
  Eigen::Index non_zeros = 0;                    // of k when the pattern was built
  const std::vector<char>* own_nodes = nullptr;  // AssemblyOptions::own_nodes; compared only
};

struct LinearSystem {
  SparseMatrix k;       // K_ff, symmetric, both triangles stored
  Eigen::VectorXd rhs;  // f_f - K_fp u_p
  // The elements' volume constraints apart, when AssemblyOptions::
  // volumetric_split asks and the model has them (the mean-dilatation
  // elements); else empty. Whatever is later added to k belongs to the
  // split's A (VolumetricSplit), which is k less the constraints' term.
  VolumetricSplit split;
  // Set by the assemblies below. The next one into this system keeps k's
  // pattern and overwrites its values when the mesh, the element kind and
  // every dof's free index are the same and k still has its size and number
  // of entries; otherwise k is released and rebuilt. Code that writes k by
  // other means need not clear it (see AssembleSystem).
  PatternSource pattern_source;
  // Set by an assembly partitioned between MPI ranks (AssemblyOptions::
  // own_nodes): k then holds only the columns of these nodes, so it is a
  // whole matrix to no one but a solver that reads only those
  // (LinearSolver::OwnNodes). Null: k is whole.
  const std::vector<char>* own_nodes = nullptr;
};

// Whether any of an element's `nodes` is flagged in `own` (a rank's nodes,
// AssemblyOptions::own_nodes).
template <typename Nodes>
bool TouchesAny(const Nodes& nodes, const std::vector<char>& own) {
  for (int a : nodes) {
    if (own[a]) return true;
  }
  return false;
}

// Computes one element's stiffness `k` and force `f` (both in the element's
// 12 unknowns); returns false to stop the assembly (for example an inverted
// element). Called concurrently for elements of one colour.
using ElementKernel = std::function<bool(int element, Matrix12d* k, Vector12d* f)>;
// The same for a 10-node element, in its 30 unknowns (node order of
// fem/tet10.h: corners, then Mesh::midside).
using Tet10ElementKernel = std::function<bool(int element, Matrix30d* k, Vector30d* f)>;
// The same for an 8-node hexahedron (Mesh::hexes, node order of
// fem/hex8.h), in its 24 unknowns.
using Hex8ElementKernel = std::function<bool(int element, Matrix24d* k, Vector24d* f)>;

struct AssemblyOptions {
  // Subtract K_fp u_p (the prescribed values' pull on the free unknowns) from
  // the right-hand side: for a linear solve, where u_p is not yet in the
  // element's state. A Newton iteration, whose state already holds u_p,
  // leaves it off.
  bool lift_prescribed = false;
  // Finite-strain models: leave out the initial-stress stiffness of the
  // volumetric pressure (p d2v/dx2), which a nearly incompressible body far
  // from equilibrium (K (J - 1) >> mu) makes indefinite. What remains is
  // positive definite for a stable material and still carries the full
  // volumetric stiffness K; Newton falls back on it when the consistent
  // tangent cannot be factorised. Models without such a term ignore it.
  bool drop_pressure_stiffness = false;
  // Also give the tangent's volume constraints apart (LinearSystem::split),
  // for a solver that WantsVolumetricSplit; models without one per element
  // leave the split empty.
  bool volumetric_split = false;
  // The threads a colour is assembled by; a colour under kMinParallelWork
  // elements is assembled by the calling thread.
  ThreadContext threads;
  // Across the ranks of an MPI job, each rank's share of the tangent (null,
  // the default: the whole of it): one flag per mesh node, set for the
  // nodes whose columns this rank assembles, with every element that
  // touches one (so an element on the border between two ranks is
  // evaluated by both). K then holds only those columns, exactly the whole
  // matrix's; the right-hand side is assembled on those nodes' rows and
  // added up over the ranks (SumOverRanks: one term per entry, so it is
  // exact), so every rank ends with the whole of it, as in one process.
  // The element work is split between the ranks and K's memory with it.
  // Every rank must assemble at the same point (collective calls), and a
  // failure on one rank (an inverted element) is every rank's. Models
  // without a volumetric split honour it (AssembleSystem*, TET4_ANP); the
  // split is not partitioned.
  const std::vector<char>* own_nodes = nullptr;
};

// Assembles K_ff = sum k and rhs_f = sum f (minus K_fp u_p when lifting).
// `keep_going(fraction)` is called between colours; returning false stops
// with Status::Cancelled. A kernel returning false stops with
// Status::Numerical naming the element. After an error, k's values and rhs
// are unspecified.
//
// Into a system assembled before on the same mesh and free unknowns (see
// LinearSystem::pattern_source) the matrix is filled in place: the values
// are zeroed and each element's entries added at their row in k's column.
// Every entry an element touches must be found there, else k is rebuilt;
// as k also has the pattern's number of entries, its pattern is then
// exactly the one a fresh assembly builds, and so is the matrix. A fresh
// LinearSystem always gets a newly built pattern.
Status AssembleSystem(const Mesh& mesh, const DofMap& dofs,
                      const std::vector<std::vector<int>>& colours, const ElementKernel& kernel,
                      const AssemblyOptions& options, const std::function<bool(double)>& keep_going,
                      LinearSystem* system);

// AssembleSystem for a quadratic mesh (Mesh::shape() kTet10): 10-node elements.
Status AssembleSystemTet10(const Mesh& mesh, const DofMap& dofs,
                           const std::vector<std::vector<int>>& colours,
                           const Tet10ElementKernel& kernel, const AssemblyOptions& options,
                           const std::function<bool(double)>& keep_going, LinearSystem* system);

// AssembleSystem for a hexahedral mesh (Mesh::shape() kHex8): 8-node elements.
Status AssembleSystemHex8(const Mesh& mesh, const DofMap& dofs,
                          const std::vector<std::vector<int>>& colours,
                          const Hex8ElementKernel& kernel, const AssemblyOptions& options,
                          const std::function<bool(double)>& keep_going, LinearSystem* system);

// Assembles K_ff and the right-hand side for the elasticity of each element,
// `elasticity.D(e)`.
// `threads`: the solve's (the default, every thread OpenMP gives).
// `keep_going(fraction)` is called between colours; returning false stops
// the assembly with Status::Cancelled.
Status AssembleLinearSystem(const Mesh& mesh, const ElasticityField& elasticity, const DofMap& dofs,
                            const std::vector<std::vector<int>>& colours,
                            const std::function<bool(double)>& keep_going, LinearSystem* system,
                            const ThreadContext& threads);

// AssembleLinearSystem for a quadratic mesh: small-strain 10-node elements
// (Tet10Stiffness), prescribed values lifted to the right-hand side.
Status AssembleLinearSystemTet10(const Mesh& mesh, const ElasticityField& elasticity,
                                 const DofMap& dofs, const std::vector<std::vector<int>>& colours,
                                 const std::function<bool(double)>& keep_going,
                                 LinearSystem* system, const ThreadContext& threads);

// AssembleLinearSystem for a hexahedral mesh: small-strain 8-node elements
// with B-bar mean dilatation (Hex8Stiffness), prescribed values lifted to
// the right-hand side.
Status AssembleLinearSystemHex8(const Mesh& mesh, const ElasticityField& elasticity,
                                const DofMap& dofs, const std::vector<std::vector<int>>& colours,
                                const std::function<bool(double)>& keep_going, LinearSystem* system,
                                const ThreadContext& threads);

// The same with the plain, fully integrated brick (Hex8StiffnessFull, C3D8
// of Abaqus and CalculiX), which locks as nu -> 1/2.
Status AssembleLinearSystemHex8Full(const Mesh& mesh, const ElasticityField& elasticity,
                                    const DofMap& dofs,
                                    const std::vector<std::vector<int>>& colours,
                                    const std::function<bool(double)>& keep_going,
                                    LinearSystem* system, const ThreadContext& threads);

// Gathers the 12 element unknowns of tet `e` from the full vector `u`.
Vector12d GatherElement(const Mesh& mesh, int e, const Eigen::VectorXd& u);

// Gathers the 30 element unknowns of 10-node tet `e` of a quadratic mesh.
Vector30d GatherElementTet10(const Mesh& mesh, int e, const Eigen::VectorXd& u);

// Gathers the 24 element unknowns of hexahedron `e` (Mesh::hexes).
Vector24d GatherElementHex8(const Mesh& mesh, int e, const Eigen::VectorXd& u);

// Reference coordinates of hexahedron `e`, one row per node [m].
Hex8Nodes Hex8Coordinates(const Mesh& mesh, int e);

}  // namespace pba
