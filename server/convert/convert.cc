#include "convert/convert.h"

#include <google/protobuf/util/json_util.h>

#include <array>
#include <string>
#include <utility>

namespace pba {
namespace {

// A label step as JSON with the proto's field names: the form
// atlas/label_algebra.h's ParseLabelSteps reads.
std::string StepJson(const v1::LabelStep& step) {
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  std::string out;
  (void)google::protobuf::util::MessageToJsonString(step, &out, options);
  return out;
}

// Copies a list that must hold exactly three values (x, y, z); otherwise
// refuses it naming `path` and what the three are ("edge lengths (x, y, z)
// in mm").
Status CopyThree(const google::protobuf::RepeatedField<double>& given, const std::string& path,
                 const char* what, std::array<double, 3>* out) {
  if (given.size() != 3) {
    return Status::InvalidArgument(
        path, std::string("expected three ") + what + ", got " + std::to_string(given.size()));
  }
  for (int i = 0; i < 3; ++i) (*out)[i] = given[i];
  return Status::Ok();
}

// One material, wherever it stands (the scene's, a region's, an
// inclusion's); `path` is its field path, e.g. "region_materials[1].material".
Status MaterialFromProto(const v1::Material& material, const std::string& path, MaterialSpec* out) {
  *out = MaterialSpec();
  MaterialSpec& m = *out;
  m.name = material.name();
  m.density_kg_per_m3 = material.density_kg_per_m3();
  switch (material.model_case()) {
    case v1::Material::kLinearElastic:
      m.kind = MaterialSpec::Kind::kLinearElastic;
      m.linear_elastic.youngs_modulus_pa = material.linear_elastic().youngs_modulus_pa();
      m.linear_elastic.poissons_ratio = material.linear_elastic().poissons_ratio();
      break;
    case v1::Material::kNeoHookean:
      m.kind = MaterialSpec::Kind::kNeoHookean;
      m.neo_hookean.shear_modulus_pa = material.neo_hookean().shear_modulus_pa();
      m.neo_hookean.bulk_modulus_pa = material.neo_hookean().bulk_modulus_pa();
      break;
    case v1::Material::kMooneyRivlin:
      m.kind = MaterialSpec::Kind::kMooneyRivlin;
      m.mooney_rivlin.c10_pa = material.mooney_rivlin().c10_pa();
      m.mooney_rivlin.c01_pa = material.mooney_rivlin().c01_pa();
      m.mooney_rivlin.bulk_modulus_pa = material.mooney_rivlin().bulk_modulus_pa();
      break;
    case v1::Material::kPolynomial:
      m.kind = MaterialSpec::Kind::kPolynomial;
      for (const v1::PolynomialTerm& t : material.polynomial().terms()) {
        m.polynomial.terms.push_back({t.i(), t.j(), t.c_pa()});
      }
      m.polynomial.d_per_pa.assign(material.polynomial().d_per_pa().begin(),
                                   material.polynomial().d_per_pa().end());
      break;
    case v1::Material::kOgden:
      m.kind = MaterialSpec::Kind::kOgden;
      for (const v1::OgdenTerm& t : material.ogden().terms()) {
        m.ogden.terms.push_back({t.mu_pa(), t.alpha()});
      }
      m.ogden.bulk_modulus_pa = material.ogden().bulk_modulus_pa();
      break;
    case v1::Material::kOrthotropicElastic: {
      m.kind = MaterialSpec::Kind::kOrthotropicElastic;
      const v1::OrthotropicElastic& o = material.orthotropic_elastic();
      OrthotropicElasticParams& p = m.orthotropic_elastic;
      p.e1_pa = o.e1_pa();
      p.e2_pa = o.e2_pa();
      p.e3_pa = o.e3_pa();
      p.nu12 = o.nu12();
      p.nu13 = o.nu13();
      p.nu23 = o.nu23();
      p.g12_pa = o.g12_pa();
      p.g13_pa = o.g13_pa();
      p.g23_pa = o.g23_pa();
      // An absent axis keeps the spec's default (the global x or y axis).
      const std::pair<const google::protobuf::RepeatedField<double>*, std::array<double, 3>*>
          axes[] = {{&o.axis_1(), &p.axis_1}, {&o.axis_2(), &p.axis_2}};
      for (int a = 0; a < 2; ++a) {
        if (axes[a].first->empty()) continue;
        PBA_RETURN_IF_ERROR(CopyThree(*axes[a].first,
                                      path + ".orthotropic_elastic.axis_" + std::to_string(a + 1),
                                      "components (x, y, z)", axes[a].second));
      }
      break;
    }
    case v1::Material::MODEL_NOT_SET:
      break;  // ValidateScene names it
  }

  const v1::Viscoelastic& visco = material.viscoelastic();
  ViscoelasticSpec& v = m.viscoelastic;
  switch (visco.form_case()) {
    case v1::Viscoelastic::kProny:
      v.form = ViscoelasticSpec::Form::kProny;
      v.g.assign(visco.prony().g().begin(), visco.prony().g().end());
      v.tau_s.assign(visco.prony().tau_s().begin(), visco.prony().tau_s().end());
      break;
    case v1::Viscoelastic::kExponential:
      v.form = ViscoelasticSpec::Form::kExponential;
      v.long_term_ratio = visco.exponential().long_term_ratio();
      v.beta_per_s = visco.exponential().beta_per_s();
      break;
    case v1::Viscoelastic::kModuli:
      v.form = ViscoelasticSpec::Form::kModuli;
      v.long_term_modulus_pa = visco.moduli().long_term_modulus_pa();
      v.moduli_pa.assign(visco.moduli().moduli_pa().begin(), visco.moduli().moduli_pa().end());
      v.tau_s.assign(visco.moduli().tau_s().begin(), visco.moduli().tau_s().end());
      break;
    case v1::Viscoelastic::FORM_NOT_SET:
      break;  // no relaxation
  }
  return Status::Ok();
}

void ExplicitRunToProto(const ExplicitSummary& run, v1::Results* results) {
  v1::ExplicitRun* e = results->mutable_explicit_run();
  e->set_ran(run.ran);
  e->set_steps(run.steps);
  e->set_end_time_s(run.end_time_s);
  e->set_stable_step_s(run.stable_step_s);
  e->set_first_step_s(run.first_step_s);
  e->set_last_step_s(run.last_step_s);
  e->set_step_reductions(run.step_reductions);
  e->set_controlling_element(run.controlling_element);
  e->set_kinetic_j(run.kinetic_j);
  e->set_internal_j(run.internal_j);
  e->set_hourglass_j(run.hourglass_j);
  e->set_contact_j(run.contact_j);
  e->set_damping_j(run.damping_j);
  e->set_eroded_j(run.eroded_j);
  e->set_external_work_j(run.external_work_j);
  e->set_max_energy_error(run.max_energy_error);
  e->set_eroded_elements(run.eroded_elements);
  e->set_eroded_mass_kg(run.eroded_mass_kg);
  e->set_contact_stiffness_min_n_per_m(run.contact_stiffness_min_n_per_m);
  e->set_contact_stiffness_max_n_per_m(run.contact_stiffness_max_n_per_m);
  e->set_element_updates_per_s(run.element_updates_per_s);
  e->set_mass_scaled_elements(run.mass_scaled_elements);
  e->set_added_mass_kg(run.added_mass_kg);
  e->set_model_mass_kg(run.model_mass_kg);
  e->set_converged(run.converged);
  e->set_relative_residual(run.relative_residual);
}

// The shape and its named patches; `geometry` paths start with "geometry.".
Status GeometryFromProto(const v1::Geometry& geometry, GeometrySpec* geometry_spec) {
  switch (geometry.shape_case()) {
    case v1::Geometry::kBox: {
      PBA_RETURN_IF_ERROR(CopyThree(geometry.box().size_mm(), "geometry.box.size_mm",
                                    "edge lengths (x, y, z) in mm", &geometry_spec->box.size_mm));
      geometry_spec->kind = GeometrySpec::Kind::kBox;
      break;
    }
    case v1::Geometry::kCylinder:
      geometry_spec->kind = GeometrySpec::Kind::kCylinder;
      geometry_spec->cylinder.radius_mm = geometry.cylinder().radius_mm();
      geometry_spec->cylinder.height_mm = geometry.cylinder().height_mm();
      geometry_spec->cylinder.half = geometry.cylinder().half();
      break;
    case v1::Geometry::kSphericalShell:
      geometry_spec->kind = GeometrySpec::Kind::kSphericalShell;
      geometry_spec->spherical_shell.inner_radius_mm = geometry.spherical_shell().inner_radius_mm();
      geometry_spec->spherical_shell.outer_radius_mm = geometry.spherical_shell().outer_radius_mm();
      break;
    case v1::Geometry::kEllipsoid: {
      PBA_RETURN_IF_ERROR(CopyThree(geometry.ellipsoid().semi_axes_mm(),
                                    "geometry.ellipsoid.semi_axes_mm", "semi-axes (x, y, z) in mm",
                                    &geometry_spec->ellipsoid.semi_axes_mm));
      geometry_spec->kind = GeometrySpec::Kind::kEllipsoid;
      break;
    }
    case v1::Geometry::kAtlas: {
      const v1::Atlas& a = geometry.atlas();
      AtlasSpec& out = geometry_spec->atlas;
      geometry_spec->kind = GeometrySpec::Kind::kAtlas;
      out.source = a.source();
      out.colour_table = a.colour_table();
      out.structures.assign(a.structures().begin(), a.structures().end());
      out.merge_rest = a.merge_rest();
      out.voxel_size_mm = a.voxel_size_mm();
      out.facet_size_mm = a.facet_size_mm();
      if (a.roi_centre_mm_size() > 0) {
        PBA_RETURN_IF_ERROR(CopyThree(a.roi_centre_mm(), "geometry.atlas.roi_centre_mm",
                                      "coordinates (x, y, z) in mm", &out.roi_centre_mm));
      }
      out.roi_radius_mm = a.roi_radius_mm();
      out.roi_element_size_mm = a.roi_element_size_mm();
      if (a.labels_size() > 0) {
        out.label_steps_json = "[";
        for (int i = 0; i < a.labels_size(); ++i) {
          out.label_steps_json += (i > 0 ? "," : "") + StepJson(a.labels(i));
        }
        out.label_steps_json += "]";
      }
      break;
    }
    case v1::Geometry::SHAPE_NOT_SET:
      break;  // ValidateScene names it
  }
  for (int i = 0; i < geometry.patches_size(); ++i) {
    const v1::Patch& p = geometry.patches(i);
    PatchSpec& out = geometry_spec->patches.emplace_back();
    const std::string path = "geometry.patches[" + std::to_string(i) + "]";
    out.ball = p.centre_mm_size() > 0 || p.radius_mm() != 0;
    if (out.ball) {
      PBA_RETURN_IF_ERROR(CopyThree(p.centre_mm(), path + ".centre_mm",
                                    "coordinates (x, y, z) in mm", &out.centre_mm));
    }
    out.half_space = p.plane_point_mm_size() > 0 || p.plane_normal_size() > 0;
    out.invert = p.invert();
    if (out.half_space) {
      PBA_RETURN_IF_ERROR(CopyThree(p.plane_point_mm(), path + ".plane_point_mm",
                                    "coordinates (x, y, z) in mm", &out.plane_point_mm));
      PBA_RETURN_IF_ERROR(CopyThree(p.plane_normal(), path + ".plane_normal",
                                    "components (x, y, z)", &out.plane_normal));
    }
    out.name = p.name();
    out.set = p.set();
    out.radius_mm = p.radius_mm();
  }
  return Status::Ok();
}

Status MeshFromProto(const v1::MeshOptions& mesh, MeshSpec* mesh_spec) {
  switch (mesh.element()) {
    case v1::MeshOptions::ELEMENT_TYPE_UNSPECIFIED:
      mesh_spec->element = ElementType::kDefault;
      break;
    case v1::MeshOptions::TET4:
      mesh_spec->element = ElementType::kTet4;
      break;
    case v1::MeshOptions::TET4_ANP:
      mesh_spec->element = ElementType::kTet4Anp;
      break;
    case v1::MeshOptions::TET10:
      mesh_spec->element = ElementType::kTet10;
      break;
    case v1::MeshOptions::HEX8:
      mesh_spec->element = ElementType::kHex8;
      break;
    case v1::MeshOptions::HEX8_FULL:
      mesh_spec->element = ElementType::kHex8Full;
      break;
    case v1::MeshOptions::TET10_MD:
      mesh_spec->element = ElementType::kTet10Md;
      break;
    default:
      return Status::InvalidArgument("mesh.element",
                                     "unknown element type " + std::to_string(mesh.element()));
  }
  mesh_spec->element_size_mm = mesh.element_size_mm();
  mesh_spec->adapt.target_error_percent = mesh.adapt().target_error_percent();
  mesh_spec->adapt.max_elements = mesh.adapt().max_elements();
  mesh_spec->adapt.max_cycles = mesh.adapt().max_cycles();
  mesh_spec->adapt.refine_fraction = mesh.adapt().refine_fraction();
  return Status::Ok();
}

// The scene's material, library and formulation, then the region materials
// and inclusions, in that order (the first bad one is the one reported).
Status MaterialsFromProto(const v1::Scene& scene, SceneSpec* spec) {
  PBA_RETURN_IF_ERROR(MaterialFromProto(scene.material(), "material", &spec->material));
  spec->material_library = scene.material_library();
  switch (scene.formulation()) {
    case v1::Scene::FORMULATION_UNSPECIFIED:
    case v1::Scene::AS_WRITTEN:
      spec->formulation = Formulation::kAsWritten;
      break;
    case v1::Scene::AUTO:
      spec->formulation = Formulation::kAuto;
      break;
    default:
      return Status::InvalidArgument("formulation",
                                     "unknown formulation " + std::to_string(scene.formulation()));
  }
  spec->formulation_tolerance = scene.formulation_tolerance();
  for (int i = 0; i < scene.region_materials_size(); ++i) {
    const v1::RegionMaterial& r = scene.region_materials(i);
    RegionMaterialSpec& out = spec->region_materials.emplace_back();
    out.structures.assign(r.structures().begin(), r.structures().end());
    PBA_RETURN_IF_ERROR(MaterialFromProto(
        r.material(), "region_materials[" + std::to_string(i) + "].material", &out.material));
  }
  for (int i = 0; i < scene.inclusions_size(); ++i) {
    const v1::Inclusion& inclusion = scene.inclusions(i);
    const std::string path = "inclusions[" + std::to_string(i) + "]";
    InclusionSpec& out = spec->inclusions.emplace_back();
    out.name = inclusion.name();
    PBA_RETURN_IF_ERROR(CopyThree(inclusion.centre_mm(), path + ".centre_mm",
                                  "coordinates (x, y, z) in mm", &out.centre_mm));
    out.radius_mm = inclusion.radius_mm();
    PBA_RETURN_IF_ERROR(MaterialFromProto(inclusion.material(), path + ".material", &out.material));
    out.growth_strain = inclusion.growth_strain();
  }
  return Status::Ok();
}

// One boundary condition; `path` is its field path, e.g.
// "boundary_conditions[1]".
Status BoundaryConditionFromProto(const v1::BoundaryCondition& bc, const std::string& path,
                                  BoundaryConditionSpec* out) {
  out->set = bc.set();
  switch (bc.kind_case()) {
    case v1::BoundaryCondition::kFixed:
      out->kind = BoundaryConditionSpec::Kind::kFixed;
      break;
    case v1::BoundaryCondition::kSymmetry:
      out->kind = BoundaryConditionSpec::Kind::kSymmetry;
      break;
    case v1::BoundaryCondition::kDisplacement: {
      out->kind = BoundaryConditionSpec::Kind::kDisplacement;
      const auto& d = bc.displacement();
      if (d.has_x_mm()) out->displacement_mm[0] = d.x_mm();
      if (d.has_y_mm()) out->displacement_mm[1] = d.y_mm();
      if (d.has_z_mm()) out->displacement_mm[2] = d.z_mm();
      break;
    }
    case v1::BoundaryCondition::kPressure:
      out->kind = BoundaryConditionSpec::Kind::kPressure;
      out->pressure_pa = bc.pressure().pressure_pa();
      break;
    case v1::BoundaryCondition::kTraction: {
      out->kind = BoundaryConditionSpec::Kind::kTraction;
      PBA_RETURN_IF_ERROR(CopyThree(bc.traction().traction_pa(), path + ".traction.traction_pa",
                                    "components (x, y, z) in Pa", &out->traction_pa));
      break;
    }
    case v1::BoundaryCondition::kVelocity: {
      out->kind = BoundaryConditionSpec::Kind::kVelocity;
      const auto& v = bc.velocity();
      if (v.has_x_m_per_s()) out->velocity_m_per_s[0] = v.x_m_per_s();
      if (v.has_y_m_per_s()) out->velocity_m_per_s[1] = v.y_m_per_s();
      if (v.has_z_m_per_s()) out->velocity_m_per_s[2] = v.z_m_per_s();
      break;
    }
    case v1::BoundaryCondition::KIND_NOT_SET:
      break;  // ValidateScene names it
  }
  return Status::Ok();
}

// One contact body; `path` is its field path, e.g. "contacts[0]".
Status ContactFromProto(const v1::Contact& c, const std::string& path, ContactSpec* out) {
  out->name = c.name();
  out->set = c.set();
  switch (c.shape()) {
    case v1::Contact::SHAPE_UNSPECIFIED:
      out->shape = ContactSpec::Shape::kNone;  // ValidateScene names it
      break;
    case v1::Contact::FLAT_PUNCH:
      out->shape = ContactSpec::Shape::kFlatPunch;
      break;
    case v1::Contact::SPHERE:
      out->shape = ContactSpec::Shape::kSphere;
      break;
    case v1::Contact::PLANE:
      out->shape = ContactSpec::Shape::kPlane;
      break;
    case v1::Contact::CYLINDER_FLAT:
      out->shape = ContactSpec::Shape::kCylinderFlat;
      break;
    case v1::Contact::CYLINDER_ROUNDED:
      out->shape = ContactSpec::Shape::kCylinderRounded;
      break;
    default:
      return Status::InvalidArgument(path + ".shape",
                                     "unknown contact shape " + std::to_string(c.shape()));
  }
  PBA_RETURN_IF_ERROR(CopyThree(c.position_mm(), path + ".position_mm",
                                "coordinates (x, y, z) in mm", &out->position_mm));
  // An absent axis keeps the spec's default, pressing along -z.
  if (!c.axis().empty()) {
    PBA_RETURN_IF_ERROR(CopyThree(c.axis(), path + ".axis", "components (x, y, z)", &out->axis));
  }
  out->radius_mm = c.radius_mm();
  // An absent motion keeps the body where it is.
  if (!c.motion_mm().empty()) {
    PBA_RETURN_IF_ERROR(CopyThree(c.motion_mm(), path + ".motion_mm", "components (x, y, z) in mm",
                                  &out->motion_mm));
  }
  out->friction = c.friction();
  out->penalty_factor = c.penalty_factor();
  out->penetration_tolerance_mm = c.penetration_tolerance_mm();
  out->start_touching = c.start_touching();
  return Status::Ok();
}

// Called only when the scene has gravity; enables it.
Status GravityFromProto(const v1::Gravity& gravity, GravitySpec* gravity_spec) {
  PBA_RETURN_IF_ERROR(CopyThree(gravity.acceleration_m_per_s2(), "gravity.acceleration_m_per_s2",
                                "components (x, y, z) in m/s^2",
                                &gravity_spec->acceleration_m_per_s2));
  gravity_spec->enabled = true;
  gravity_spec->fluid_density_kg_per_m3 = gravity.fluid_density_kg_per_m3();
  if (gravity.has_fluid_level_mm()) {
    gravity_spec->fluid_level_mm = gravity.fluid_level_mm();
  }
  return Status::Ok();
}

// The analysis's nonlinear, time and explicit-dynamics options; these cannot
// be refused here (ValidateScene checks their ranges).
void AnalysisOptionsFromProto(const v1::Analysis& analysis, AnalysisSpec* analysis_spec) {
  const v1::NonlinearOptions& nonlinear = analysis.nonlinear();
  NonlinearOptionsSpec& n = analysis_spec->nonlinear;
  n.increments = nonlinear.increments();
  n.max_iterations = nonlinear.max_iterations();
  n.residual_tolerance = nonlinear.residual_tolerance();
  n.displacement_tolerance = nonlinear.displacement_tolerance();
  n.min_increment = nonlinear.min_increment();
  n.line_search = !nonlinear.has_line_search() || nonlinear.line_search();

  const v1::LinearSolverOptions& linear = analysis.linear_solver_options();
  LinearSolverSpec& l = analysis_spec->linear_solver_options;
  switch (linear.preconditioner()) {
    case v1::LinearSolverOptions::BOOMERAMG:
      l.preconditioner = LinearSolverSpec::Preconditioner::kBoomerAmg;
      break;
    case v1::LinearSolverOptions::PRESSURE_SCHUR:
      l.preconditioner = LinearSolverSpec::Preconditioner::kPressureSchur;
      break;
    default:
      l.preconditioner = LinearSolverSpec::Preconditioner::kGamg;
  }
  l.relative_tolerance = linear.relative_tolerance();
  l.max_iterations = linear.max_iterations();
  if (linear.has_gamg_threshold()) l.gamg_threshold = linear.gamg_threshold();
  l.boomeramg_strong_threshold = linear.boomeramg_strong_threshold();
  l.auto_direct_max_factor_mb = linear.auto_direct_max_factor_mb();
  if (linear.has_fallback_direct_max_unknowns()) {
    l.fallback_direct_max_unknowns = linear.fallback_direct_max_unknowns();
  }

  const v1::Time& time = analysis.time();
  TimeSpec& t = analysis_spec->time;
  t.end_time_s = time.end_time_s();
  t.initial_step_s = time.initial_step_s();
  t.min_step_s = time.min_step_s();
  t.max_step_s = time.max_step_s();
  for (const v1::CurvePoint& point : time.curve()) {
    t.curve.emplace_back(point.time_s(), point.amplitude());
  }

  const v1::ExplicitDynamics& explicit_dynamics = analysis.explicit_dynamics();
  ExplicitSpec& e = analysis_spec->explicit_dynamics;
  e.time_step_factor = explicit_dynamics.time_step_factor();
  if (explicit_dynamics.has_bulk_viscosity_linear()) {
    e.bulk_viscosity_linear = explicit_dynamics.bulk_viscosity_linear();
  }
  if (explicit_dynamics.has_bulk_viscosity_quadratic()) {
    e.bulk_viscosity_quadratic = explicit_dynamics.bulk_viscosity_quadratic();
  }
  e.mass_damping_per_s = explicit_dynamics.mass_damping_per_s();
  e.hourglass_coefficient = explicit_dynamics.hourglass_coefficient();
  e.output_interval_s = explicit_dynamics.output_interval_s();
  e.erosion_strain = explicit_dynamics.erosion_strain();
  e.relaxation_tolerance = explicit_dynamics.relaxation_tolerance();
  e.mass_scaling_step_s = explicit_dynamics.mass_scaling_step_s();
}

Status AnalysisFromProto(const v1::Analysis& analysis, AnalysisSpec* analysis_spec) {
  switch (analysis.type()) {
    case v1::Analysis::TYPE_UNSPECIFIED:
    case v1::Analysis::LINEAR_STATIC:
      analysis_spec->type = AnalysisSpec::Type::kLinearStatic;
      break;
    case v1::Analysis::NONLINEAR_STATIC:
      analysis_spec->type = AnalysisSpec::Type::kNonlinearStatic;
      break;
    case v1::Analysis::QUASI_STATIC:
      analysis_spec->type = AnalysisSpec::Type::kQuasiStatic;
      break;
    case v1::Analysis::EXPLICIT_DYNAMIC:
      analysis_spec->type = AnalysisSpec::Type::kExplicitDynamic;
      break;
    case v1::Analysis::DYNAMIC_RELAXATION:
      analysis_spec->type = AnalysisSpec::Type::kDynamicRelaxation;
      break;
    default:
      return Status::InvalidArgument("analysis.type",
                                     "unknown analysis type " + std::to_string(analysis.type()));
  }
  switch (analysis.linear_solver()) {
    case v1::Analysis::LINEAR_SOLVER_UNSPECIFIED:
    case v1::Analysis::AUTO:
      analysis_spec->linear_solver = AnalysisSpec::LinearSolver::kAuto;
      break;
    case v1::Analysis::CHOLMOD:
      analysis_spec->linear_solver = AnalysisSpec::LinearSolver::kCholmod;
      break;
    case v1::Analysis::AMG:
      analysis_spec->linear_solver = AnalysisSpec::LinearSolver::kAmg;
      break;
    case v1::Analysis::MUMPS:
      analysis_spec->linear_solver = AnalysisSpec::LinearSolver::kMumps;
      break;
    case v1::Analysis::EIGEN_LDLT:
      analysis_spec->linear_solver = AnalysisSpec::LinearSolver::kEigenLdlt;
      break;
    case v1::Analysis::PCG:
      analysis_spec->linear_solver = AnalysisSpec::LinearSolver::kPcg;
      break;
    default:
      return Status::InvalidArgument(
          "analysis.linear_solver",
          "unknown linear solver " + std::to_string(analysis.linear_solver()));
  }
  if (!v1::LinearSolverOptions::Preconditioner_IsValid(
          analysis.linear_solver_options().preconditioner())) {
    return Status::InvalidArgument(
        "analysis.linear_solver_options.preconditioner",
        "unknown preconditioner " +
            std::to_string(analysis.linear_solver_options().preconditioner()));
  }
  AnalysisOptionsFromProto(analysis, analysis_spec);
  return Status::Ok();
}

// A non-empty field list replaces the default set (every field on) by
// exactly the fields it names.
Status OutputFieldsFromProto(const google::protobuf::RepeatedField<int>& fields,
                             OutputSpec* outputs) {
  if (fields.empty()) return Status::Ok();
  outputs->displacement = outputs->stress = outputs->von_mises = outputs->strain =
      outputs->pk2_stress = outputs->almansi_strain = outputs->jacobian = false;
  for (int i = 0; i < fields.size(); ++i) {
    switch (fields[i]) {
      case v1::Outputs::DISPLACEMENT:
        outputs->displacement = true;
        break;
      case v1::Outputs::STRESS:
        outputs->stress = true;
        break;
      case v1::Outputs::VON_MISES:
        outputs->von_mises = true;
        break;
      case v1::Outputs::STRAIN:
        outputs->strain = true;
        break;
      case v1::Outputs::PK2_STRESS:
        outputs->pk2_stress = true;
        break;
      case v1::Outputs::ALMANSI_STRAIN:
        outputs->almansi_strain = true;
        break;
      case v1::Outputs::JACOBIAN:
        outputs->jacobian = true;
        break;
      default:
        return Status::InvalidArgument("outputs.fields[" + std::to_string(i) + "]",
                                       "unknown output field " + std::to_string(fields[i]));
    }
  }
  return Status::Ok();
}

Status OutputsFromProto(const v1::Outputs& outputs, OutputSpec* outputs_spec) {
  PBA_RETURN_IF_ERROR(OutputFieldsFromProto(outputs.fields(), outputs_spec));
  outputs_spec->reaction_sets.assign(outputs.reaction_sets().begin(),
                                     outputs.reaction_sets().end());
  outputs_spec->structure_displacements.assign(outputs.structure_displacements().begin(),
                                               outputs.structure_displacements().end());
  for (int i = 0; i < outputs.profiles_size(); ++i) {
    const v1::Profile& p = outputs.profiles(i);
    const std::string path = "outputs.profiles[" + std::to_string(i) + "]";
    ProfileSpec out;
    out.name = p.name();
    PBA_RETURN_IF_ERROR(
        CopyThree(p.from_mm(), path + ".from_mm", "coordinates (x, y, z) in mm", &out.from_mm));
    PBA_RETURN_IF_ERROR(
        CopyThree(p.to_mm(), path + ".to_mm", "coordinates (x, y, z) in mm", &out.to_mm));
    out.points = p.points();
    outputs_spec->profiles.push_back(std::move(out));
  }
  for (int i = 0; i < outputs.sensors_size(); ++i) {
    const v1::Sensor& sensor = outputs.sensors(i);
    SensorSpec out;
    out.name = sensor.name();
    PBA_RETURN_IF_ERROR(CopyThree(sensor.position_mm(),
                                  "outputs.sensors[" + std::to_string(i) + "].position_mm",
                                  "coordinates (x, y, z) in mm", &out.position_mm));
    out.radius_mm = sensor.radius_mm();
    outputs_spec->sensors.push_back(std::move(out));
  }
  outputs_spec->sensor_interval_s = outputs.sensor_interval_s();
  outputs_spec->filter_cutoff_hz = outputs.filter_cutoff_hz();
  outputs_spec->filter_order = outputs.filter_order();
  return Status::Ok();
}

}  // namespace

// Section by section in the order of the scene message; the first refusal is
// returned and names its field path.
Status SceneFromProto(const v1::Scene& scene, SceneSpec* spec) {
  *spec = SceneSpec();
  spec->name = scene.name();
  spec->description = scene.description();
  PBA_RETURN_IF_ERROR(GeometryFromProto(scene.geometry(), &spec->geometry));
  PBA_RETURN_IF_ERROR(MeshFromProto(scene.mesh(), &spec->mesh));
  PBA_RETURN_IF_ERROR(MaterialsFromProto(scene, spec));
  for (int i = 0; i < scene.boundary_conditions_size(); ++i) {
    BoundaryConditionSpec out;
    PBA_RETURN_IF_ERROR(BoundaryConditionFromProto(
        scene.boundary_conditions(i), "boundary_conditions[" + std::to_string(i) + "]", &out));
    spec->boundary_conditions.push_back(std::move(out));
  }
  for (int i = 0; i < scene.contacts_size(); ++i) {
    PBA_RETURN_IF_ERROR(ContactFromProto(scene.contacts(i), "contacts[" + std::to_string(i) + "]",
                                         &spec->contacts.emplace_back()));
  }
  if (scene.has_gravity()) {
    PBA_RETURN_IF_ERROR(GravityFromProto(scene.gravity(), &spec->gravity));
  }
  PBA_RETURN_IF_ERROR(AnalysisFromProto(scene.analysis(), &spec->analysis));
  return OutputsFromProto(scene.outputs(), &spec->outputs);
}

Status ValidateSceneProto(const v1::Scene& scene, int ranks,
                          const std::vector<std::string>& atlas_structures) {
  SceneSpec spec;
  PBA_RETURN_IF_ERROR(SceneFromProto(scene, &spec));
  spec.geometry.atlas.known_structures = atlas_structures;
  PBA_RETURN_IF_ERROR(ValidateScene(spec));
  return ValidateSceneOnRanks(spec, ranks);
}

namespace {

// mesh.adapt: the bounds, why the cycles ended, each cycle.
void AdaptationToProto(const Adaptation& a, v1::Modelled* modelled) {
  v1::Adaptation* out = modelled->mutable_adaptation();
  out->set_adapted(true);
  out->set_target_error(a.target_error);
  out->set_max_elements(a.max_elements);
  out->set_max_cycles(a.max_cycles);
  out->set_refine_fraction(a.refine_fraction);
  out->set_reached(a.reached);
  out->set_stop_reason(a.stop_reason);
  for (const AdaptCycle& c : a.cycles) {
    v1::AdaptCycle* cycle = out->add_cycles();
    cycle->set_elements(c.elements);
    cycle->set_nodes(c.nodes);
    cycle->set_dofs(c.dofs);
    cycle->set_relative_error(c.relative_error);
    cycle->set_wall_time_s(c.wall_time_s);
    cycle->set_marked(c.marked);
    cycle->set_change(c.change);
    cycle->set_changed_quantity(c.changed_quantity);
  }
}

}  // namespace

v1::Summary SummaryToProto(const Summary& summary) {
  v1::Summary out;
  out.set_scene_name(summary.scene_name);
  out.set_solver_version(SolverVersion());

  v1::Modelled* modelled = out.mutable_modelled();
  modelled->set_geometry(summary.geometry);
  modelled->set_element_type(summary.element_type);
  modelled->set_nodes(summary.nodes);
  modelled->set_elements(summary.elements);
  modelled->set_dofs(summary.dofs);
  modelled->set_constrained_dofs(summary.constrained_dofs);
  modelled->set_material(summary.material);
  modelled->set_analysis(summary.analysis);
  modelled->set_linear_solver(summary.linear_solver);
  for (const auto& note : summary.notes) modelled->add_notes(note);
  for (const auto& [name, value] : summary.options) (*modelled->mutable_options())[name] = value;
  for (const ModelDecision& d : summary.decisions) {
    v1::ModelDecision* out = modelled->add_decisions();
    out->set_aspect(d.aspect);
    out->set_decision(d.decision);
    out->set_reason(d.reason);
    out->set_reduces(d.reduces);
  }
  if (!summary.decisions.empty()) {
    v1::ReductionEstimate* r = modelled->mutable_reduction();
    r->set_estimated(summary.reduction.estimated);
    r->set_relative_difference(summary.reduction.relative_difference);
    r->set_quantity(summary.reduction.quantity);
    r->set_reduced_coarse_s(summary.reduction.reduced_coarse_s);
    r->set_full_coarse_s(summary.reduction.full_coarse_s);
    r->set_note(summary.reduction.note);
    r->set_kept(summary.reduction.kept);
    r->set_tolerance(summary.reduction.tolerance);
  }
  if (summary.adaptation.adapted) AdaptationToProto(summary.adaptation, modelled);

  v1::Results* results = out.mutable_results();
  results->set_max_displacement_mm(summary.max_displacement_mm);
  for (double x : summary.max_displacement_at_mm) results->add_max_displacement_at_mm(x);
  results->set_max_von_mises_pa(summary.max_von_mises_pa);
  results->set_strain_energy_j(summary.strain_energy_j);
  for (const auto& reaction : summary.reactions) {
    v1::Reaction* r = results->add_reactions();
    r->set_set(reaction.set);
    for (double f : reaction.force_n) r->add_force_n(f);
  }
  results->set_relative_residual(summary.relative_residual);
  if (!summary.increments.empty()) {
    v1::Convergence* convergence = results->mutable_convergence();
    for (const IncrementSummary& i : summary.increments) {
      v1::Increment* out = convergence->add_increments();
      out->set_load_factor(i.load_factor);
      out->set_iterations(i.iterations);
      out->set_relative_residual(i.relative_residual);
      out->set_negative_eigenvalues(i.negative_eigenvalues);
    }
    convergence->set_newton_iterations(summary.newton_iterations);
    convergence->set_increment_cuts(summary.increment_cuts);
    convergence->set_assembly_s(summary.newton_assembly_s);
    convergence->set_linear_solve_s(summary.newton_linear_solve_s);
    convergence->set_residual_s(summary.newton_residual_s);
    for (const TimeStepSummary& step : summary.time_steps) {
      v1::TimeStep* out = convergence->add_time_steps();
      out->set_time_s(step.time_s);
      out->set_step_s(step.step_s);
      out->set_amplitude(step.amplitude);
      out->set_iterations(step.iterations);
      out->set_relative_residual(step.relative_residual);
    }
  }
  for (const ContactSummary& contact : summary.contacts) {
    v1::ContactResult* c = results->add_contacts();
    c->set_name(contact.name);
    for (double f : contact.force_n) c->add_force_n(f);
    c->set_peak_force_n(contact.peak_force_n);
    c->set_area_mm2(contact.area_mm2);
    c->set_max_penetration_mm(contact.max_penetration_mm);
    c->set_penalty_pa_per_mm(contact.penalty_pa_per_mm);
    c->set_augmentations(contact.augmentations);
  }
  for (const StructureDisplacement& structure : summary.structure_displacements) {
    v1::StructureDisplacement* d = results->add_structure_displacements();
    d->set_name(structure.name);
    for (double u : structure.mean_mm) d->add_mean_mm(u);
    d->set_max_mm(structure.max_mm);
  }

  for (const ProfileSummary& profile : summary.profiles) {
    v1::ProfileResult* p = results->add_profiles();
    p->set_name(profile.name);
    p->set_points(profile.points);
    p->set_inside(profile.inside);
    p->set_max_stress_along_pa(profile.max_stress_along_pa);
    p->set_at_distance_mm(profile.at_distance_mm);
    for (double x : profile.at_mm) p->add_at_mm(x);
  }
  if (summary.explicit_run.ran) ExplicitRunToProto(summary.explicit_run, results);
  for (const SensorPeak& peak : summary.sensor_peaks) {
    v1::SensorPeak* p = results->add_sensor_peaks();
    p->set_sensor(peak.sensor);
    p->set_quantity(peak.quantity);
    p->set_peak_raw(peak.peak_raw);
    p->set_time_raw_s(peak.time_raw_s);
    p->set_peak_filtered(peak.peak_filtered);
    p->set_time_filtered_s(peak.time_filtered_s);
  }

  v1::Performance* performance = out.mutable_performance();
  performance->set_wall_time_s(summary.wall_time_s);
  performance->set_threads(summary.threads);
  performance->set_ranks(summary.ranks);
  for (const auto& phase : summary.phases) {
    v1::PhaseTime* p = performance->add_phases();
    p->set_phase(phase.phase);
    p->set_seconds(phase.seconds);
  }

  v1::ErrorEstimate* error = out.mutable_error_estimate();
  error->set_estimated(summary.error.estimated);
  error->set_method(summary.error.method);
  error->set_relative_error(summary.error.relative_error);
  for (const RegionErrorEstimate& r : summary.error.regions) {
    v1::RegionError* region = error->add_regions();
    region->set_name(r.name);
    region->set_elements(r.elements);
    region->set_relative_error(r.relative_error);
    region->set_share(r.share);
  }
  error->set_note(summary.error.estimated
                      ? summary.error.note
                      : (summary.error.note.empty() ? "not estimated" : summary.error.note));

  auto& units = *out.mutable_units();
  units["length"] = "mm";
  units["displacement"] = "mm";
  units["stress"] = "Pa";
  units["force"] = "N";
  units["energy"] = "J";
  units["time"] = "s";
  return out;
}

}  // namespace pba
