#include "explicit/explicit_setup.h"

#include "core/format.h"
#include "fem/element_kind.h"
#include "material/factory.h"
#include "material/linear_elastic.h"
#include "material/material_field.h"

namespace pba {

Status MakeExplicitSetup(const Problem& problem, ExplicitSetup* out) {
  const Model& model = problem.model;
  const Mesh& mesh = model.mesh;
  const bool relaxation = problem.analysis == AnalysisSpec::Type::kDynamicRelaxation;
  // ValidateScene refuses the elements and materials the engine does not
  // take (scene_checks::ValidateExplicit).
  if (!KindOf(problem.element).explicit_engine) {
    return Status::Internal(std::string("the explicit engine was given ") +
                            ElementName(problem.element) + " elements");
  }
  const ExplicitOptions& spec = problem.explicit_dynamics;
  TledOptions& options = out->options;
  options.average_nodal_pressure = problem.element != ElementType::kTet4;
  options.bulk_viscosity_linear = spec.bulk_viscosity_linear;
  options.bulk_viscosity_quadratic = spec.bulk_viscosity_quadratic;
  options.hourglass = spec.hourglass_coefficient;
  options.threads = problem.threads;
  out->time_step_factor = spec.time_step_factor;

  const SceneMaterials& materials = model.materials;
  std::vector<TledMaterial> tled_materials;
  for (std::size_t m = 0; m < materials.specs.size(); ++m) {
    const MaterialSpec& ms = materials.specs[m];
    if (!ms.hyperelastic() || materials.growth_strain[m] != 0) {
      return Status::Internal("the explicit engine was given " + materials.labels[m] +
                              ", which is not a hyperelastic material without growth");
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
  for (const Motion& motion : problem.motions) {
    for (int node : mesh.face_sets.at(motion.set).nodes) {
      for (int c = 0; c < 3; ++c) {
        PrescribedDof& p = out->prescribed[3 * node + c];
        switch (motion.kind) {
          case Motion::Kind::kFixed:
            p = {PrescribedDof::kDisplacement, 0.0};
            break;
          case Motion::Kind::kSymmetry:
            if (c == motion.normal_axis) p = {PrescribedDof::kDisplacement, 0.0};
            break;
          case Motion::Kind::kDisplacement:
            if (motion.value[c]) p = {PrescribedDof::kDisplacement, *motion.value[c]};
            break;
          case Motion::Kind::kVelocity:
            if (motion.value[c]) p = {PrescribedDof::kVelocity, *motion.value[c]};
            break;
        }
      }
    }
  }
  out->loads = std::make_unique<ExternalLoads>(BuildLoads(problem));
  out->has_loads = !out->loads->empty();
  return Status::Ok();
}

}  // namespace pba
