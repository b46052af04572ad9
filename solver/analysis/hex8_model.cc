#include "analysis/hex8_model.h"

#include "analysis/element_model.h"
#include "fem/hex8_finite_strain.h"
#include "fem/point_kinematics.h"

namespace pba {
namespace {

// Both bricks: `full_integration` picks Hex8FiniteStrainFull over the
// mean-dilatation Hex8FiniteStrain; everything else is shared.
struct Hex8Element {
  static constexpr int kNodes = 8;
  using Geometry = Hex8Geometry;
  using Result = Hex8FiniteStrainResult;
  using Unknowns = Vector24d;
  using Kernel = Hex8ElementKernel;

  bool full_integration = false;

  static bool Fits(const Mesh& mesh) { return mesh.shape() == ElementShape::kHex8; }
  static const char* Requirement() {
    return "MakeHex8Model and MakeHex8FullModel need a hexahedral mesh (Mesh::hexes)";
  }
  static Geometry ComputeGeometry(const Mesh& mesh, int e) {
    return ComputeHex8Geometry(Hex8Coordinates(mesh, e));
  }
  static std::array<int, 8> Nodes(const Mesh& mesh, int e) { return mesh.hexes[e]; }
  static Unknowns Gather(const Mesh& mesh, int e, const Eigen::VectorXd& u) {
    return GatherElementHex8(mesh, e, u);
  }
  static Status AssembleSystem(const Mesh& mesh, const DofMap& dofs,
                               const std::vector<std::vector<int>>& colours, const Kernel& kernel,
                               const AssemblyOptions& options,
                               const std::function<bool(double)>& keep_going,
                               LinearSystem* system) {
    return AssembleSystemHex8(mesh, dofs, colours, kernel, options, keep_going, system);
  }
  bool Evaluate(const Geometry& g, const Unknowns& ue, const HyperelasticMaterial& material,
                bool with_tangent, bool drop_pressure_stiffness, Result* r) const {
    return full_integration
               ? Hex8FiniteStrainFull(g, ue, material, with_tangent, r, drop_pressure_stiffness)
               : Hex8FiniteStrain(g, ue, material, with_tangent, r, drop_pressure_stiffness);
  }
  bool SplitsVolume() const { return !full_integration; }
  static constexpr int kPoints = 8;
  double Dilatation(const Geometry& g, const Unknowns& ue) const { return MeanDilatation(g, ue); }
  // The mean-dilatation brick's stress comes from F_bar = (theta / J)^(1/3)
  // F: F's isochoric part with the element's mean volume ratio.
  Eigen::Matrix3d PointF(const Geometry& g, const Unknowns& ue, int q, double theta) const {
    return full_integration ? DeformationGradientHex8(g.grad[q], ue)
                            : MeanDilatationF(DeformationGradientHex8(g.grad[q], ue), theta);
  }
  std::string Describe() const {
    return full_integration
               ? "HEX8, full 2x2x2 integration (locks when nearly incompressible), total "
                 "Lagrangian"
               : "HEX8 (2x2x2 integration, mean dilatation), total Lagrangian";
  }
};

}  // namespace

std::unique_ptr<FiniteStrainModel> MakeHex8Model(const Mesh& mesh,
                                                 const HyperelasticMaterial& material) {
  return MakeElementModel(mesh, material, Hex8Element{false});
}

std::unique_ptr<FiniteStrainModel> MakeHex8Model(const Mesh& mesh, const MaterialField& field,
                                                 const ThreadContext& threads) {
  return std::make_unique<ElementModel<Hex8Element>>(mesh, field, Hex8Element{false}, threads);
}

std::unique_ptr<FiniteStrainModel> MakeHex8FullModel(const Mesh& mesh,
                                                     const HyperelasticMaterial& material) {
  return MakeElementModel(mesh, material, Hex8Element{true});
}

std::unique_ptr<FiniteStrainModel> MakeHex8FullModel(const Mesh& mesh, const MaterialField& field,
                                                     const ThreadContext& threads) {
  return std::make_unique<ElementModel<Hex8Element>>(mesh, field, Hex8Element{true}, threads);
}

}  // namespace pba
