#include "scene/problem.h"

#include <algorithm>
#include <cmath>

#include "atlas/structure_set.h"
#include "core/format.h"
#include "fem/element_kind.h"
#include "mesh/primitive_mesher.h"
#include "signal/butterworth.h"

namespace pba {
namespace {

constexpr double kMm = 1e-3;

Eigen::Vector3d Metres(const std::array<double, 3>& mm) {
  return Eigen::Vector3d(mm[0], mm[1], mm[2]) * kMm;
}

std::string DescribeGeometry(const GeometrySpec& g) {
  switch (g.kind) {
    case GeometrySpec::Kind::kBox:
      return Format("box %g x %g x %g mm", g.box.size_mm[0], g.box.size_mm[1], g.box.size_mm[2]);
    case GeometrySpec::Kind::kSphericalShell:
      return Format("spherical shell octant, radii %g and %g mm", g.spherical_shell.inner_radius_mm,
                    g.spherical_shell.outer_radius_mm);
    case GeometrySpec::Kind::kAtlas: {
      const std::string& source = g.atlas.source;
      if (source.empty() || source == "synthetic") return "synthetic atlas";
      // A snapshot of the atlas store (staged by the server, or exported) is
      // named as such: the staging path means nothing to the reader.
      StructureSet set;
      if (IsStructureSetDir(source) && ReadStructureSet(source, &set).ok() &&
          !set.project.empty() && set.snapshot > 0) {
        return Format("atlas of snapshot %lld of project %s (%zu structures)",
                      static_cast<long long>(set.snapshot), set.project.c_str(),
                      set.structures.size());
      }
      return "atlas from " + source;
    }
    case GeometrySpec::Kind::kEllipsoid:
      return Format("ellipsoid, semi-axes %g, %g and %g mm", g.ellipsoid.semi_axes_mm[0],
                    g.ellipsoid.semi_axes_mm[1], g.ellipsoid.semi_axes_mm[2]);
    case GeometrySpec::Kind::kCylinder:
      return Format("cylinder r = %g mm, h = %g mm", g.cylinder.radius_mm, g.cylinder.height_mm);
    case GeometrySpec::Kind::kNone:
      break;
  }
  return "no geometry";
}

LinearSolverOptions::Kind SolverKind(AnalysisSpec::LinearSolver kind) {
  using Kind = LinearSolverOptions::Kind;
  switch (kind) {
    case AnalysisSpec::LinearSolver::kCholmod:
      return Kind::kCholmod;
    case AnalysisSpec::LinearSolver::kEigenLdlt:
      return Kind::kEigenLdlt;
    case AnalysisSpec::LinearSolver::kPcg:
      return Kind::kPcg;
    case AnalysisSpec::LinearSolver::kAmg:
      return Kind::kAmg;
    case AnalysisSpec::LinearSolver::kMumps:
      return Kind::kMumps;
    case AnalysisSpec::LinearSolver::kAuto:
      break;
  }
  return Kind::kAuto;
}

std::vector<Motion> ResolveMotions(const SceneSpec& scene) {
  std::vector<Motion> motions;
  for (const BoundaryConditionSpec& bc : scene.boundary_conditions) {
    Motion m;
    m.set = bc.set;
    switch (bc.kind) {
      case BoundaryConditionSpec::Kind::kFixed:
        m.kind = Motion::Kind::kFixed;
        break;
      case BoundaryConditionSpec::Kind::kDisplacement:
        m.kind = Motion::Kind::kDisplacement;
        for (int c = 0; c < 3; ++c) {
          if (bc.displacement_mm[c]) m.value[c] = *bc.displacement_mm[c] * kMm;
        }
        break;
      case BoundaryConditionSpec::Kind::kSymmetry:
        m.kind = Motion::Kind::kSymmetry;
        m.normal_axis = PlaneNormalAxis(scene.geometry, bc.set);
        break;
      case BoundaryConditionSpec::Kind::kVelocity:
        m.kind = Motion::Kind::kVelocity;
        m.value = bc.velocity_m_per_s;
        break;
      default:
        continue;  // loads: SurfaceLoad
    }
    motions.push_back(std::move(m));
  }
  return motions;
}

std::vector<Contact> ResolveContacts(const SceneSpec& scene, double finest_element_size_m) {
  const bool impactors = scene.analysis.type == AnalysisSpec::Type::kExplicitDynamic;
  std::vector<Contact> contacts;
  for (const ContactSpec& c : scene.contacts) {
    Contact out;
    out.name = c.name;
    out.set = c.set;
    out.body.shape = c.shape;
    out.body.position = Metres(c.position_mm);
    const Eigen::Vector3d axis(c.axis[0], c.axis[1], c.axis[2]);
    out.body.axis = axis.norm() > 0 ? Eigen::Vector3d(axis.normalized()) : axis;
    out.body.radius = c.radius_mm * kMm;
    out.body.motion = Metres(c.motion_mm);
    out.friction = c.friction;
    out.penalty_factor = c.penalty_factor > 0 ? c.penalty_factor
                         : impactors          ? kExplicitPenaltyFactor
                                              : kImplicitPenaltyFactor;
    out.penetration_tolerance_m = c.penetration_tolerance_mm > 0
                                      ? c.penetration_tolerance_mm * kMm
                                      : Contact::kToleranceFraction * finest_element_size_m;
    out.start_touching = c.start_touching;
    contacts.push_back(std::move(out));
  }
  return contacts;
}

}  // namespace

OutputOptions ResolveOutputs(const SceneSpec& scene) {
  const OutputSpec& o = scene.outputs;
  OutputOptions out;
  out.displacement = o.displacement;
  out.stress = o.stress;
  out.von_mises = o.von_mises;
  out.strain = o.strain;
  out.pk2_stress = o.pk2_stress;
  out.almansi_strain = o.almansi_strain;
  out.jacobian = o.jacobian;
  out.reaction_sets = ReactionSetNames(scene);
  out.structure_displacements = o.structure_displacements;
  out.profiles = o.profiles;
  for (ProfileSpec& p : out.profiles) {
    if (p.points == 0) p.points = OutputOptions::kProfilePoints;
  }
  out.sensors.sensors = o.sensors;
  if (o.sensor_interval_s > 0) out.sensors.interval_s = o.sensor_interval_s;
  if (o.filter_order > 0) out.sensors.filter_order = o.filter_order;
  if (o.filter_cutoff_hz > 0) out.sensors.filter_cutoff_hz = o.filter_cutoff_hz;
  return out;
}

NonlinearOptions NonlinearOptions::FromSpec(const NonlinearOptionsSpec& spec) {
  NonlinearOptions o;
  if (spec.increments != 0) o.increments = spec.increments;
  if (spec.max_iterations != 0) o.max_iterations = spec.max_iterations;
  if (spec.residual_tolerance != 0) o.residual_tolerance = spec.residual_tolerance;
  if (spec.displacement_tolerance != 0) o.displacement_tolerance = spec.displacement_tolerance;
  if (spec.min_increment != 0) o.min_increment = spec.min_increment;
  o.line_search = spec.line_search;
  return o;
}

Status NonlinearOptions::Validate() const {
  const NonlinearOptions defaults;
  if (increments < 1 || increments > 10000) {
    return Status::InvalidArgument("analysis.nonlinear.increments",
                                   Format("must lie in 1..10000 (0 for the default %d), got %d",
                                          defaults.increments, increments));
  }
  if (max_iterations < 1 || max_iterations > 1000) {
    return Status::InvalidArgument("analysis.nonlinear.max_iterations",
                                   Format("must lie in 1..1000 (0 for the default %d), got %d",
                                          defaults.max_iterations, max_iterations));
  }
  const struct {
    const char* name;
    double value, fallback;
  } fractions[] = {
      {"residual_tolerance", residual_tolerance, defaults.residual_tolerance},
      {"displacement_tolerance", displacement_tolerance, defaults.displacement_tolerance},
      {"min_increment", min_increment, defaults.min_increment}};
  for (const auto& f : fractions) {
    if (!(std::isfinite(f.value) && f.value > 0 && f.value < 1)) {
      return Status::InvalidArgument(
          std::string("analysis.nonlinear.") + f.name,
          Format("must lie in [0, 1) (0 for the default %g), got %g", f.fallback, f.value));
    }
  }
  if (min_increment < kMinIncrementFloor) {
    return Status::InvalidArgument(
        "analysis.nonlinear.min_increment",
        Format("must be at least %g (0 for the default %g): a smaller increment underflows "
               "before it can give up, got %g",
               kMinIncrementFloor, defaults.min_increment, min_increment));
  }
  return Status::Ok();
}

LinearSolverSettings LinearSolverSettingsFromSpec(const LinearSolverSpec& spec) {
  LinearSolverSettings o;
  switch (spec.preconditioner) {
    case LinearSolverSpec::Preconditioner::kBoomerAmg:
      o.preconditioner = LinearSolverSettings::Preconditioner::kBoomerAmg;
      break;
    case LinearSolverSpec::Preconditioner::kPressureSchur:
      o.preconditioner = LinearSolverSettings::Preconditioner::kPressureSchur;
      break;
    case LinearSolverSpec::Preconditioner::kGamg:
      o.preconditioner = LinearSolverSettings::Preconditioner::kGamg;
  }
  if (spec.relative_tolerance != 0) o.relative_tolerance = spec.relative_tolerance;
  if (spec.max_iterations != 0) o.max_iterations = spec.max_iterations;
  if (spec.gamg_threshold) o.gamg_threshold = *spec.gamg_threshold;
  if (spec.boomeramg_strong_threshold != 0) {
    o.boomeramg_strong_threshold = spec.boomeramg_strong_threshold;
  }
  if (spec.auto_direct_max_factor_mb != 0)
    o.auto_direct_max_factor_mb = spec.auto_direct_max_factor_mb;
  if (spec.fallback_direct_max_unknowns) {
    o.fallback_direct_max_unknowns = *spec.fallback_direct_max_unknowns;
  }
  return o;
}

Status ValidateLinearSolverSettings(const LinearSolverSettings& s) {
  const LinearSolverSettings defaults;
  const std::string path = "analysis.linear_solver_options.";
  if (!(s.relative_tolerance >= 1e-14 && s.relative_tolerance <= 1e-2)) {
    return Status::InvalidArgument(
        path + "relative_tolerance",
        Format("must lie in [1e-14, 1e-2] (0 for the default %g), got %g",
               defaults.relative_tolerance, s.relative_tolerance));
  }
  if (s.max_iterations < 1 || s.max_iterations > 100000) {
    return Status::InvalidArgument(path + "max_iterations",
                                   Format("must lie in 1..100000 (0 for the default %d), got %d",
                                          defaults.max_iterations, s.max_iterations));
  }
  if (!(s.gamg_threshold >= 0 && s.gamg_threshold <= 0.5)) {
    return Status::InvalidArgument(path + "gamg_threshold",
                                   Format("must lie in [0, 0.5] (unset for the default %g), got %g",
                                          defaults.gamg_threshold, s.gamg_threshold));
  }
  if (!(s.boomeramg_strong_threshold > 0 && s.boomeramg_strong_threshold < 1)) {
    return Status::InvalidArgument(
        path + "boomeramg_strong_threshold",
        Format("must lie in (0, 1) (0 for the default %g), got %g",
               defaults.boomeramg_strong_threshold, s.boomeramg_strong_threshold));
  }
  if (s.auto_direct_max_factor_mb < 0) {
    return Status::InvalidArgument(
        path + "auto_direct_max_factor_mb",
        Format("must not be negative (MB), got %d", s.auto_direct_max_factor_mb));
  }
  if (s.fallback_direct_max_unknowns < 0) {
    return Status::InvalidArgument(
        path + "fallback_direct_max_unknowns",
        Format("must not be negative (0: never), got %d", s.fallback_direct_max_unknowns));
  }
  return Status::Ok();
}

TimeOptions TimeOptions::FromSpec(const TimeSpec& spec) {
  TimeOptions t;
  t.end_s = spec.end_time_s;
  t.initial_step_s =
      spec.initial_step_s > 0 ? spec.initial_step_s : spec.end_time_s * kInitialStepFraction;
  t.min_step_s = spec.min_step_s > 0 ? spec.min_step_s : spec.end_time_s * kMinStepFraction;
  t.max_step_s = spec.max_step_s > 0 ? spec.max_step_s : spec.end_time_s * kMaxStepFraction;
  t.curve = spec.curve;
  return t;
}

ExplicitOptions ExplicitOptions::FromSpec(const ExplicitSpec& spec, AnalysisSpec::Type type,
                                          double end_s) {
  ExplicitOptions o;
  const bool relaxation = type == AnalysisSpec::Type::kDynamicRelaxation;
  o.time_step_factor = spec.time_step_factor > 0 ? spec.time_step_factor
                       : relaxation              ? kRelaxationTimeStepFactor
                                                 : kTimeStepFactor;
  // Dynamic relaxation damps on its own and wants the elastic answer.
  o.bulk_viscosity_linear =
      relaxation ? 0 : spec.bulk_viscosity_linear.value_or(kBulkViscosityLinear);
  o.bulk_viscosity_quadratic =
      relaxation ? 0 : spec.bulk_viscosity_quadratic.value_or(kBulkViscosityQuadratic);
  o.mass_damping_per_s = spec.mass_damping_per_s;
  o.hourglass_coefficient =
      spec.hourglass_coefficient > 0 ? spec.hourglass_coefficient : kHourglassCoefficient;
  o.output_interval_s =
      spec.output_interval_s > 0 ? spec.output_interval_s : end_s * kOutputIntervalFraction;
  o.mass_scaling_step_s = spec.mass_scaling_step_s;
  o.erosion_strain = spec.erosion_strain;
  o.relaxation_tolerance =
      spec.relaxation_tolerance > 0 ? spec.relaxation_tolerance : kRelaxationTolerance;
  return o;
}

Status SensorOptions::Validate() const {
  ButterworthLowPass filter;
  if (!ButterworthLowPass::Design(filter_order, filter_cutoff_hz, 1 / interval_s, &filter).ok()) {
    return Status::InvalidArgument(
        "outputs.filter_cutoff_hz",
        Format("the sensors' filter (order %d, cutoff %g Hz%s) does not fit the sampling interval "
               "%g s: the cutoff must lie below half the sampling rate, %g Hz",
               filter_order, filter_cutoff_hz,
               filter_cutoff_hz == kFilterCutoffHz ? ", the default" : "", interval_s,
               0.5 / interval_s));
  }
  return Status::Ok();
}

Status RigidBody::Validate(const std::string& path) const {
  using Shape = ContactSpec::Shape;
  if (shape != Shape::kFlatPunch && shape != Shape::kSphere && shape != Shape::kPlane) {
    return Status::InvalidArgument(
        path + ".shape", shape == Shape::kCylinderFlat || shape == Shape::kCylinderRounded
                             ? "CYLINDER_FLAT and CYLINDER_ROUNDED are impactors of an "
                               "EXPLICIT_DYNAMIC analysis; a static one takes FLAT_PUNCH, SPHERE "
                               "or PLANE"
                             : "no rigid body shape given");
  }
  if (!position.allFinite()) return Status::InvalidArgument(path + ".position", "not finite");
  if (!motion.allFinite()) return Status::InvalidArgument(path + ".motion", "not finite");
  if (shape != Shape::kSphere && !(axis.allFinite() && axis.norm() > 0)) {
    return Status::InvalidArgument(path + ".axis",
                                   "must be a non-zero direction (into the tissue)");
  }
  if (shape != Shape::kPlane && !(std::isfinite(radius) && radius > 0)) {
    return Status::InvalidArgument(path + ".radius", Format("must be positive (got %g m)", radius));
  }
  return Status::Ok();
}

std::vector<std::pair<std::string, std::string>> EffectiveOptions(const Problem& problem) {
  using Type = AnalysisSpec::Type;
  std::vector<std::pair<std::string, std::string>> out;
  const auto add = [&out](const std::string& name, const std::string& value) {
    out.emplace_back(name, value);
  };
  const auto number = [](double v, const char* unit) {
    return Format("%g", v) + (*unit ? std::string(" ") + unit : std::string());
  };
  const Type type = problem.analysis;
  const bool explicit_engine = type == Type::kExplicitDynamic || type == Type::kDynamicRelaxation;
  add("mesh.element", ElementName(problem.element));
  add("mesh.element_size_mm", number(problem.element_size_m / kMm, "mm"));
  if (!explicit_engine) {
    using Kind = LinearSolverOptions::Kind;
    const LinearSolverOptions& l = problem.linear_solver;
    const LinearSolverSettings& ls = l.settings;
    add("analysis.linear_solver", l.KindName());
    const std::string o = "analysis.linear_solver_options.";
    if (l.kind == Kind::kAuto) {
      add(o + "auto_direct_max_factor_mb",
          ls.auto_direct_max_factor_mb > 0
              ? std::to_string(ls.auto_direct_max_factor_mb)
              : "0 (a quarter of the memory the solve may take; the solver line gives it)");
    }
    if (l.kind == Kind::kAuto || l.kind == Kind::kAmg) {
      const bool boomeramg = ls.preconditioner == LinearSolverSettings::Preconditioner::kBoomerAmg;
      const bool gamg = !boomeramg;  // PRESSURE_SCHUR's displacements too
      add(o + "preconditioner",
          ls.preconditioner == LinearSolverSettings::Preconditioner::kPressureSchur
              ? "PRESSURE_SCHUR"
          : boomeramg ? "BOOMERAMG"
                      : "GAMG");
      add(o + "relative_tolerance", number(ls.relative_tolerance, ""));
      add(o + "max_iterations", std::to_string(ls.max_iterations));
      if (gamg) {
        add(o + "gamg_threshold", number(ls.gamg_threshold, ""));
      } else {
        add(o + "boomeramg_strong_threshold", number(ls.boomeramg_strong_threshold, ""));
      }
      add(o + "fallback_direct_max_unknowns", std::to_string(ls.fallback_direct_max_unknowns));
    }
  }
  if (type == Type::kNonlinearStatic || type == Type::kQuasiStatic) {
    const NonlinearOptions& n = problem.nonlinear;
    if (type == Type::kNonlinearStatic) {
      add("analysis.nonlinear.increments", std::to_string(n.increments));
    }
    add("analysis.nonlinear.max_iterations", std::to_string(n.max_iterations));
    add("analysis.nonlinear.residual_tolerance", number(n.residual_tolerance, ""));
    add("analysis.nonlinear.displacement_tolerance", number(n.displacement_tolerance, ""));
    if (type == Type::kNonlinearStatic) {
      add("analysis.nonlinear.min_increment", number(n.min_increment, ""));
    }
    add("analysis.nonlinear.line_search", n.line_search ? "true" : "false");
  }
  if (type == Type::kQuasiStatic || type == Type::kExplicitDynamic) {
    add("analysis.time.end_time_s", number(problem.time.end_s, "s"));
  }
  if (type == Type::kQuasiStatic) {
    add("analysis.time.initial_step_s", number(problem.time.initial_step_s, "s"));
    add("analysis.time.min_step_s", number(problem.time.min_step_s, "s"));
    add("analysis.time.max_step_s", number(problem.time.max_step_s, "s"));
  }
  if (explicit_engine) {
    const ExplicitOptions& e = problem.explicit_dynamics;
    const std::string path = "analysis.explicit_dynamics.";
    add(path + "time_step_factor", number(e.time_step_factor, ""));
    if (problem.element == ElementType::kHex8) {
      add(path + "hourglass_coefficient", number(e.hourglass_coefficient, ""));
    }
    if (type == Type::kDynamicRelaxation) {
      add(path + "relaxation_tolerance", number(e.relaxation_tolerance, ""));
    } else {
      add(path + "bulk_viscosity_linear", number(e.bulk_viscosity_linear, ""));
      add(path + "bulk_viscosity_quadratic", number(e.bulk_viscosity_quadratic, ""));
      add(path + "mass_damping_per_s", number(e.mass_damping_per_s, "1/s"));
      add(path + "output_interval_s", number(e.output_interval_s, "s"));
      add(path + "mass_scaling_step_s", number(e.mass_scaling_step_s, "s"));
      add(path + "erosion_strain", number(e.erosion_strain, ""));
      if (!problem.outputs.sensors.sensors.empty()) {
        const SensorOptions& s = problem.outputs.sensors;
        add("outputs.sensor_interval_s", number(s.interval_s, "s"));
        add("outputs.filter_order", std::to_string(s.filter_order));
        add("outputs.filter_cutoff_hz", number(s.filter_cutoff_hz, "Hz"));
      }
    }
  }
  for (std::size_t i = 0; i < problem.contacts.size(); ++i) {
    const Contact& c = problem.contacts[i];
    const std::string path = Format("contacts[%zu].", i);
    add(path + "penalty_factor", number(c.penalty_factor, ""));
    if (!explicit_engine) {
      add(path + "penetration_tolerance_mm", number(c.penetration_tolerance_m / kMm, "mm"));
    }
  }
  for (std::size_t i = 0; i < problem.outputs.profiles.size(); ++i) {
    add(Format("outputs.profiles[%zu].points", i),
        std::to_string(problem.outputs.profiles[i].points));
  }
  return out;
}

Status ResolveProblem(const SceneSpec& scene, Problem* problem) {
  PBA_RETURN_IF_ERROR(ValidateScene(scene));
  Problem& p = *problem;
  p = Problem();
  p.name = scene.name;
  p.geometry = DescribeGeometry(scene.geometry);
  p.analysis = scene.analysis.type;
  p.element = ResolveElement(scene.mesh.element, scene.analysis.type);
  p.element_size_m = EffectiveElementSize(scene.geometry, scene.mesh) * kMm;
  const AtlasSpec& atlas = scene.geometry.atlas;
  p.finest_element_size_m =
      scene.geometry.kind == GeometrySpec::Kind::kAtlas && atlas.roi_radius_mm > 0
          ? std::min(atlas.roi_element_size_mm * kMm, p.element_size_m)
          : p.element_size_m;

  const bool follower = scene.analysis.type != AnalysisSpec::Type::kLinearStatic;
  for (const BoundaryConditionSpec& bc : scene.boundary_conditions) {
    if (bc.kind == BoundaryConditionSpec::Kind::kPressure && bc.pressure_pa != 0) {
      SurfaceLoad load;
      load.kind = SurfaceLoad::Kind::kPressure;
      load.set = bc.set;
      load.pressure_pa = bc.pressure_pa;
      load.follower = follower;
      p.surface_loads.push_back(std::move(load));
    } else if (bc.kind == BoundaryConditionSpec::Kind::kTraction) {
      SurfaceLoad load;
      load.kind = SurfaceLoad::Kind::kTraction;
      load.set = bc.set;
      load.traction_pa = Eigen::Vector3d(bc.traction_pa[0], bc.traction_pa[1], bc.traction_pa[2]);
      p.surface_loads.push_back(std::move(load));
    }
  }
  const GravitySpec& g = scene.gravity;
  p.gravity.enabled = g.enabled;
  p.gravity.acceleration_m_per_s2 = Eigen::Vector3d(
      g.acceleration_m_per_s2[0], g.acceleration_m_per_s2[1], g.acceleration_m_per_s2[2]);
  p.gravity.fluid_density_kg_per_m3 = g.fluid_density_kg_per_m3;
  if (g.fluid_level_mm) p.gravity.fluid_level_m = *g.fluid_level_mm * kMm;
  p.motions = ResolveMotions(scene);
  p.contacts = ResolveContacts(scene, p.finest_element_size_m);

  p.linear_solver.kind = SolverKind(scene.analysis.linear_solver);
  p.linear_solver.settings = LinearSolverSettingsFromSpec(scene.analysis.linear_solver_options);
  p.nonlinear = NonlinearOptions::FromSpec(scene.analysis.nonlinear);
  p.time = TimeOptions::FromSpec(scene.analysis.time);
  p.explicit_dynamics = ExplicitOptions::FromSpec(scene.analysis.explicit_dynamics,
                                                  scene.analysis.type, p.time.end_s);
  p.relaxed_below_s = scene.analysis.relaxed_below_s;
  p.frozen_above_s = scene.analysis.frozen_above_s;
  p.outputs = ResolveOutputs(scene);
  return Status::Ok();
}

namespace {

// What the mesh shows of a scene is a failed precondition, not a bad field.
Status AsPrecondition(const Status& built) {
  if (built.code() != Status::Code::kInvalidArgument) return built;
  return Status::FailedPrecondition(built.field(), built.message());
}

}  // namespace

Status BuildProblemModel(const SceneSpec& scene, const BuildModelOptions& options,
                         Problem* problem) {
  return AsPrecondition(BuildModel(scene, &problem->model, options));
}

Status BuildProblemBaseMesh(const SceneSpec& scene, const BuildModelOptions& options,
                            BaseMesh* base) {
  return AsPrecondition(BuildBaseMesh(scene, options, base));
}

Status BuildProblemModelOn(const SceneSpec& scene, BaseMesh base, Problem* problem) {
  return AsPrecondition(BuildModelOn(scene, std::move(base), &problem->model));
}

Status BuildProblem(const SceneSpec& scene, const BuildModelOptions& options, Problem* problem) {
  PBA_RETURN_IF_ERROR(ResolveProblem(scene, problem));
  return BuildProblemModel(scene, options, problem);
}

ExternalLoads BuildLoads(const Problem& problem) {
  const Model& model = problem.model;
  const Mesh& mesh = model.mesh;
  ExternalLoads loads(mesh);
  for (const SurfaceLoad& load : problem.surface_loads) {
    const FaceSet& set = mesh.face_sets.at(load.set);
    if (load.kind == SurfaceLoad::Kind::kPressure) {
      loads.AddPressure(set, load.pressure_pa, load.follower);
    } else {
      loads.AddTraction(set, load.traction_pa);
    }
  }
  const GravityLoad& gravity = problem.gravity;
  if (gravity.enabled) {
    const Eigen::Vector3d g = gravity.acceleration_m_per_s2;
    const SceneMaterials& materials = model.materials;
    if (materials.uniform() && gravity.fluid_density_kg_per_m3 == 0) {
      loads.AddBodyForce(materials.specs[0].density_kg_per_m3 * g);
    } else {
      // Buoyancy: the fluid's weight pushes up on whatever it surrounds,
      // below its level (a height along -g).
      const Eigen::Vector3d up =
          g.norm() > 0 ? Eigen::Vector3d(-g.normalized()) : Eigen::Vector3d::Zero();
      loads.AddElementBodyForceField(
          [&materials, &gravity, up, g](const Eigen::Vector3d& x, int e) -> Eigen::Vector3d {
            double density = materials.density(e);
            if (!gravity.fluid_level_m || up.dot(x) <= *gravity.fluid_level_m) {
              density -= gravity.fluid_density_kg_per_m3;
            }
            return density * g;
          });
    }
  }
  return loads;
}

}  // namespace pba
