#include "explicit/explicit_setup.h"

#include "core/format.h"
#include "material/factory.h"

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
  options.bulk_viscosity_linear = spec.bulk_viscosity_linear.value_or(0.06);
  options.bulk_viscosity_quadratic = spec.bulk_viscosity_quadratic.value_or(1.5);
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
    t.relaxation = RelaxationOf(ms.viscoelastic);
    t.density = ms.density_kg_per_m3;
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

}  // namespace pba
