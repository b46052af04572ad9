#include "explicit/explicit_setup.h"

#include <Eigen/LU>

#include "analysis/material_field.h"
#include "core/format.h"
#include "material/factory.h"
#include "material/linear_elastic.h"

namespace pba {

Status MakeExplicitSetup(const SceneSpec& scene, const Model& model, ExplicitSetup* out) {
  const Mesh& mesh = model.mesh;
  if (mesh.quadratic() || scene.mesh.element == ElementType::kHex8Full) {
    return Status::InvalidArgument(
        "mesh.element",
        "the explicit engine takes TET4_ANP, TET4 or HEX8 (one point with "
        "hourglass control), not 10-node tetrahedra or fully integrated bricks");
  }
  for (std::size_t i = 0; i < scene.inclusions.size(); ++i) {
    if (scene.inclusions[i].growth_strain != 0) {
      return Status::InvalidArgument(Format("inclusions[%zu].growth_strain", i),
                                     "growth is not modelled by the explicit engine; use "
                                     "QUASI_STATIC for a growing inclusion");
    }
  }
  const ExplicitSpec& spec = scene.analysis.explicit_dynamics;
  TledOptions& options = out->options;
  options.average_nodal_pressure = scene.mesh.element != ElementType::kTet4;
  // Dynamic relaxation damps on its own and wants the elastic answer.
  const bool relaxation = scene.analysis.type == AnalysisSpec::Type::kDynamicRelaxation;
  options.bulk_viscosity_linear = relaxation ? 0 : spec.bulk_viscosity_linear.value_or(0.06);
  options.bulk_viscosity_quadratic = relaxation ? 0 : spec.bulk_viscosity_quadratic.value_or(1.5);
  options.hourglass = spec.hourglass_coefficient > 0 ? spec.hourglass_coefficient : 0.05;
  out->time_step_factor = spec.time_step_factor > 0 ? spec.time_step_factor : 0.7;

  const SceneMaterials& materials = model.materials;
  std::vector<TledMaterial> tled_materials;
  for (std::size_t m = 0; m < materials.specs.size(); ++m) {
    const MaterialSpec& ms = materials.specs[m];
    if (!ms.hyperelastic()) {
      return Status::InvalidArgument("material",
                                     "the explicit engine needs hyperelastic "
                                     "materials; " +
                                         materials.labels[m] + " is not");
    }
    TledMaterial t;
    t.model = MakeHyperelasticMaterial(ms);
    if (!relaxation) t.relaxation = RelaxationOf(ms.viscoelastic);
    // Dynamic relaxation sets its own masses.
    t.density = relaxation && !(ms.density_kg_per_m3 > 0) ? 1000 : ms.density_kg_per_m3;
    t.mu = t.model->ShearModulus();
    t.bulk = t.model->BulkModulus();
    t.neo_hookean = ms.kind == MaterialSpec::Kind::kNeoHookean && t.relaxation.g.empty();
    t.name = materials.labels.empty() ? ms.name : materials.labels[m];
    tled_materials.push_back(std::move(t));
  }
  PBA_RETURN_IF_ERROR(
      TledModel::Build(mesh, std::move(tled_materials), materials.of_element, options, &out->tled));

  // Prescribed motion, the conditions in order (a later one wins).
  out->prescribed.assign(3 * static_cast<std::size_t>(mesh.num_nodes()), PrescribedDof());
  for (const BoundaryConditionSpec& bc : scene.boundary_conditions) {
    if (bc.is_load()) continue;
    const int normal = bc.kind == BoundaryConditionSpec::Kind::kSymmetry
                           ? PlaneNormalAxis(scene.geometry, bc.set)
                           : -1;
    for (int node : mesh.face_sets.at(bc.set).nodes) {
      for (int c = 0; c < 3; ++c) {
        PrescribedDof& p = out->prescribed[3 * node + c];
        switch (bc.kind) {
          case BoundaryConditionSpec::Kind::kFixed:
            p = {PrescribedDof::kDisplacement, 0.0};
            break;
          case BoundaryConditionSpec::Kind::kSymmetry:
            if (c == normal) p = {PrescribedDof::kDisplacement, 0.0};
            break;
          case BoundaryConditionSpec::Kind::kDisplacement:
            if (bc.displacement_mm[c]) {
              p = {PrescribedDof::kDisplacement, *bc.displacement_mm[c] * 1e-3};
            }
            break;
          case BoundaryConditionSpec::Kind::kVelocity:
            if (bc.velocity_m_per_s[c]) p = {PrescribedDof::kVelocity, *bc.velocity_m_per_s[c]};
            break;
          default:
            break;
        }
      }
    }
  }
  out->loads = std::make_unique<ExternalLoads>(BuildLoads(scene, model));
  out->has_loads = !out->loads->empty();
  return Status::Ok();
}

void FillExplicitFields(const TledModel& tled, Solution* solution, double* max_strain) {
  const int ne = tled.num_elements();
  solution->strain.assign(6 * static_cast<std::size_t>(ne), 0.0);
  solution->almansi_strain.assign(6 * static_cast<std::size_t>(ne), 0.0);
  solution->stress_pa.assign(6 * static_cast<std::size_t>(ne), 0.0);
  solution->pk2_stress_pa.assign(6 * static_cast<std::size_t>(ne), 0.0);
  solution->von_mises_pa.assign(ne, 0.0);
  solution->jacobian.assign(ne, 1.0);
  double largest = 0;
  for (int e = 0; e < ne; ++e) {
    if (tled.eroded(e)) continue;
    const Eigen::Matrix3d f = tled.DeformationGradient(e);
    const double j = f.determinant();
    const Vector6d green = GreenLagrangeVoigt(f);
    const Vector6d almansi = AlmansiVoigt(f);
    const Vector6d cauchy = tled.CauchyStress(e);
    const Eigen::Matrix3d finv = f.inverse();
    const Vector6d pk2 = SymmetricToVoigt(j * finv * VoigtToSymmetric(cauchy) * finv.transpose());
    Eigen::Map<Vector6d>(&solution->strain[6 * e]) = green;
    Eigen::Map<Vector6d>(&solution->almansi_strain[6 * e]) = almansi;
    Eigen::Map<Vector6d>(&solution->stress_pa[6 * e]) = cauchy;
    Eigen::Map<Vector6d>(&solution->pk2_stress_pa[6 * e]) = pk2;
    solution->von_mises_pa[e] = VonMises(cauchy);
    solution->jacobian[e] = j;
    largest = std::max(largest, green.cwiseAbs().maxCoeff());
  }
  *max_strain = largest;
}

}  // namespace pba
