#include "analysis/hex8_model.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "fem/hex8_finite_strain.h"
#include "material/hyperelastic.h"

namespace pba {
namespace {

// Below this many elements the passes run on one thread: a Newton solve on a
// small mesh makes many passes, and starting a team would cost more than the
// work.
constexpr int kParallelFrom = 256;

// Both bricks: `full_integration` picks Hex8FiniteStrainFull over the
// mean-dilatation Hex8FiniteStrain; everything else is shared.
class Hex8Model final : public FiniteStrainModel {
 public:
  Hex8Model(const Mesh& mesh, const HyperelasticMaterial& material, bool full_integration)
      : mesh_(mesh),
        material_(material),
        full_integration_(full_integration),
        parallel_(mesh.num_elements() >= kParallelFrom),
        colours_(ColourElements(mesh)) {
    if (mesh.num_elements() > 0 && !mesh.hexahedral()) {
      std::fprintf(stderr, "pba: %s needs a hexahedral mesh (Mesh::hexes)\n",
                   full_integration ? "MakeHex8FullModel" : "MakeHex8Model");
      std::abort();
    }
    geometry_.resize(mesh.num_elements());
#pragma omp parallel for schedule(static) if (parallel_)
    for (int e = 0; e < mesh.num_elements(); ++e) {
      geometry_[e] = ComputeHex8Geometry(Hex8Coordinates(mesh, e));
    }
  }

  bool InternalForce(const Eigen::VectorXd& u, Eigen::VectorXd* force,
                     double* energy) const override {
    *force = Eigen::VectorXd::Zero(u.size());
    bool ok = true;
    double total = 0;
    // Elements of one colour share no node, so their scatters never collide.
    for (const auto& colour : colours_) {
#pragma omp parallel for schedule(static) if (parallel_) reduction(&& : ok) reduction(+ : total)
      for (std::size_t k = 0; k < colour.size(); ++k) {
        const int e = colour[k];
        Hex8FiniteStrainResult r;
        if (!Evaluate(e, u, false, false, &r)) {
          ok = false;
          continue;
        }
        total += r.energy;
        const std::array<int, 8>& nodes = mesh_.hexes[e];
        for (int a = 0; a < 8; ++a) force->segment<3>(3 * nodes[a]) += r.force.segment<3>(3 * a);
      }
    }
    if (energy) *energy = total;
    return ok && force->allFinite() && std::isfinite(total);
  }

  Status Assemble(const Eigen::VectorXd& u, const DofMap& dofs, const AssemblyOptions& options,
                  LinearSystem* system) const override {
    const Hex8ElementKernel kernel = [&](int e, Matrix24d* k, Vector24d* f) {
      Hex8FiniteStrainResult r;
      if (!Evaluate(e, u, true, options.drop_pressure_stiffness, &r)) return false;
      *k = r.tangent;
      *f = -r.force;
      return true;
    };
    const Status status = AssembleSystemHex8(
        mesh_, dofs, colours_, kernel, options, [](double) { return true; }, system);
    if (status.code() != Status::Code::kNumerical) return status;
    // The assembly stops at whichever failing element a thread met first;
    // the message names the lowest one, the same on any number of threads.
    const int e = LowestInverted(u);
    if (e >= 0 && !(geometry_[e].min_jacobian > 0)) {
      return Status::Numerical("element " + std::to_string(e) +
                               " is inverted in the reference configuration (det J <= 0)");
    }
    if (e >= 0) {
      return Status::Numerical("element " + std::to_string(e) +
                               " could not be evaluated (inverted: det F <= 0)");
    }
    return status;
  }

  std::string Describe() const override {
    return full_integration_
               ? "HEX8, full 2x2x2 integration (locks when nearly incompressible), total "
                 "Lagrangian"
               : "HEX8 (2x2x2 integration, mean dilatation), total Lagrangian";
  }

 private:
  // Element `e` at the global displacement `u`, by this model's kernel.
  bool Evaluate(int e, const Eigen::VectorXd& u, bool with_tangent, bool drop_pressure_stiffness,
                Hex8FiniteStrainResult* r) const {
    const Vector24d ue = GatherElementHex8(mesh_, e, u);
    return full_integration_ ? Hex8FiniteStrainFull(geometry_[e], ue, material_, with_tangent, r,
                                                    drop_pressure_stiffness)
                             : Hex8FiniteStrain(geometry_[e], ue, material_, with_tangent, r,
                                                drop_pressure_stiffness);
  }

  // The lowest element whose reference det J or whose F at an integration
  // point at `u` is not admissible; -1 when there is none.
  int LowestInverted(const Eigen::VectorXd& u) const {
    const int ne = mesh_.num_elements();
    int lowest = ne;
#pragma omp parallel for schedule(static) if (parallel_) reduction(min : lowest)
    for (int e = 0; e < ne; ++e) {
      const Hex8Geometry& g = geometry_[e];
      bool bad = !(g.min_jacobian > 0);
      const Vector24d ue = GatherElementHex8(mesh_, e, u);
      for (int q = 0; q < 8 && !bad; ++q) {
        Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
        for (int a = 0; a < 8; ++a) f += ue.segment<3>(3 * a) * g.grad[q].row(a);
        bad = !IsAdmissible(f);
      }
      if (bad) lowest = std::min(lowest, e);
    }
    return lowest < ne ? lowest : -1;
  }

  const Mesh& mesh_;
  const HyperelasticMaterial& material_;
  const bool full_integration_;  // Hex8FiniteStrainFull, not mean dilatation
  const bool parallel_;          // use OpenMP threads
  std::vector<std::vector<int>> colours_;
  std::vector<Hex8Geometry> geometry_;
};

}  // namespace

std::unique_ptr<FiniteStrainModel> MakeHex8Model(const Mesh& mesh,
                                                 const HyperelasticMaterial& material) {
  return std::make_unique<Hex8Model>(mesh, material, false);
}

std::unique_ptr<FiniteStrainModel> MakeHex8FullModel(const Mesh& mesh,
                                                     const HyperelasticMaterial& material) {
  return std::make_unique<Hex8Model>(mesh, material, true);
}

}  // namespace pba
