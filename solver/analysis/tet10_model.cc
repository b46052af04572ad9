#include "analysis/tet10_model.h"

#include "analysis/element_model.h"
#include "fem/point_kinematics.h"
#include "fem/tet10_finite_strain.h"
#include "mesh/quadratic.h"

namespace pba {
namespace {

// Both 10-node elements: `mean_dilatation` picks
// Tet10FiniteStrainMeanDilatation (TET10_MD) over the plain Tet10FiniteStrain;
// everything else is shared.
struct Tet10Element {
  static constexpr int kNodes = 10;
  using Geometry = Tet10Geometry;
  using Result = Tet10FiniteStrainResult;
  using Unknowns = Vector30d;
  using Kernel = Tet10ElementKernel;

  bool mean_dilatation = false;

  static bool Fits(const Mesh& mesh) { return mesh.shape() == ElementShape::kTet10; }
  static const char* Requirement() {
    return "MakeTet10Model and MakeTet10MdModel need a quadratic mesh (see MakeQuadratic)";
  }
  static Geometry ComputeGeometry(const Mesh& mesh, int e) {
    return ComputeTet10Geometry(Tet10Coordinates(mesh, e));
  }
  static std::array<int, 10> Nodes(const Mesh& mesh, int e) { return Tet10NodeIndices(mesh, e); }
  static Unknowns Gather(const Mesh& mesh, int e, const Eigen::VectorXd& u) {
    return GatherElementTet10(mesh, e, u);
  }
  static Status AssembleSystem(const Mesh& mesh, const DofMap& dofs,
                               const std::vector<std::vector<int>>& colours, const Kernel& kernel,
                               const AssemblyOptions& options,
                               const std::function<bool(double)>& keep_going,
                               LinearSystem* system) {
    return AssembleSystemTet10(mesh, dofs, colours, kernel, options, keep_going, system);
  }
  bool Evaluate(const Geometry& g, const Unknowns& ue, const HyperelasticMaterial& material,
                bool with_tangent, bool drop_pressure_stiffness, Result* r) const {
    return mean_dilatation
               ? Tet10FiniteStrainMeanDilatation(g, ue, material, with_tangent, r,
                                                 drop_pressure_stiffness)
               : Tet10FiniteStrain(g, ue, material, with_tangent, r, drop_pressure_stiffness);
  }
  bool SplitsVolume() const { return mean_dilatation; }
  static constexpr int kPoints = 4;
  double Dilatation(const Geometry& g, const Unknowns& ue) const {
    return mean_dilatation ? MeanDilatation(g, ue) : 0;
  }
  // TET10_MD: F_bar, as for the mean-dilatation brick.
  Eigen::Matrix3d PointF(const Geometry& g, const Unknowns& ue, int q, double theta) const {
    const Eigen::Matrix3d f = DeformationGradientTet10(g.grad[q], ue);
    return mean_dilatation ? MeanDilatationF(f, theta) : f;
  }
  std::string Describe() const {
    return mean_dilatation
               ? "TET10_MD (quadratic, 4-point integration, mean dilatation), total Lagrangian"
               : "TET10 (quadratic, 4-point integration), total Lagrangian";
  }
};

}  // namespace

std::unique_ptr<FiniteStrainModel> MakeTet10Model(const Mesh& mesh,
                                                  const HyperelasticMaterial& material) {
  return MakeElementModel(mesh, material, Tet10Element{false});
}

std::unique_ptr<FiniteStrainModel> MakeTet10Model(const Mesh& mesh, const MaterialField& field,
                                                  const ThreadContext& threads) {
  return std::make_unique<ElementModel<Tet10Element>>(mesh, field, Tet10Element{false}, threads);
}

std::unique_ptr<FiniteStrainModel> MakeTet10MdModel(const Mesh& mesh,
                                                    const HyperelasticMaterial& material) {
  return MakeElementModel(mesh, material, Tet10Element{true});
}

std::unique_ptr<FiniteStrainModel> MakeTet10MdModel(const Mesh& mesh, const MaterialField& field,
                                                    const ThreadContext& threads) {
  return std::make_unique<ElementModel<Tet10Element>>(mesh, field, Tet10Element{true}, threads);
}

}  // namespace pba
