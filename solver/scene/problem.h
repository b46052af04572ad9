// The resolved problem: what every analysis, error estimator, writer and
// the explicit engine read instead of the scene (docs/design.md, "Scene ->
// Problem -> analysis").
//
// A validated SceneSpec is turned into a Problem once: SI units (m, s, Pa,
// N), every default applied (the option structs below declare each default
// once, and the validator's messages quote them from here), the mesh with
// its regions and the material of every element, the loads, the rigid
// bodies and the outputs. Resolving without meshing is how a scene is
// validated, so a scene that validates fails later only for what the mesh
// alone can tell (kFailedPrecondition, naming the field) or for a numerical
// reason (kNumerical), never with kInvalidArgument.
//
// The enums of pba/scene.h (element types, analysis types, contact shapes)
// are the vocabulary of both; a Problem never holds a scene's raw values.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/thread_context.h"
#include "linear/linear_solver.h"
#include "pba/scene.h"
#include "pba/status.h"
#include "scene/model_builder.h"
#include "scene/rigid_body.h"

namespace pba {

// Load stepping and Newton-Raphson controls of the finite-strain analyses
// (analysis.nonlinear), defaults applied.
struct NonlinearOptions {
  int increments = 5;                    // initial number of load increments, 1..10000
  int max_iterations = 20;               // Newton iterations per increment, 1..1000
  double residual_tolerance = 1e-8;      // relative force residual, (0, 1)
  double displacement_tolerance = 1e-8;  // relative displacement correction, (0, 1)
  double min_increment = 1e-4;           // smallest load-factor increment, [1e-12, 1)
  // Below this a cut-back increment would shrink until the arithmetic
  // underflows and then creep on for minutes instead of giving up.
  static constexpr double kMinIncrementFloor = 1e-12;
  bool line_search = true;

  // From analysis.nonlinear (0: the default); Validate names the field.
  static NonlinearOptions FromSpec(const NonlinearOptionsSpec& spec);
  Status Validate() const;
};

// analysis.linear_solver_options with the defaults of LinearSolverSettings
// where a field is 0 (unset); the validation names the field.
LinearSolverSettings LinearSolverSettingsFromSpec(const LinearSolverSpec& spec);
Status ValidateLinearSolverSettings(const LinearSolverSettings& settings);

// Time of QUASI_STATIC and EXPLICIT_DYNAMIC (analysis.time) [s], defaults
// applied. The curve is a(t) through (time, amplitude) points; empty: a
// ramp t / end_s.
struct TimeOptions {
  double end_s = 0;
  double initial_step_s = 0;  // default end_s / 20
  double min_step_s = 0;      // default end_s * 1e-6
  double max_step_s = 0;      // default end_s / 5
  std::vector<std::pair<double, double>> curve;

  static constexpr double kInitialStepFraction = 1.0 / 20;
  static constexpr double kMinStepFraction = 1e-6;
  static constexpr double kMaxStepFraction = 1.0 / 5;
  // Floors of the given steps, as fractions of end_s (validation refuses
  // less, naming the field): a max_step_s below a millionth of the run
  // means over a million Newton solves (1e-300 s ran until killed); an
  // initial or min step below a billionth means over 1e9 increments, more
  // than the stepper counts.
  static constexpr double kMaxStepFloorFraction = 1e-6;
  static constexpr double kStepFloorFraction = 1e-9;
  // From analysis.time, the steps' defaults taken from end_time_s.
  static TimeOptions FromSpec(const TimeSpec& spec);
};

// Controls of the explicit engine (analysis.explicit_dynamics), defaults
// applied for the analysis that runs (EXPLICIT_DYNAMIC or
// DYNAMIC_RELAXATION).
struct ExplicitOptions {
  static constexpr double kTimeStepFactor = 0.7;            // EXPLICIT_DYNAMIC
  static constexpr double kRelaxationTimeStepFactor = 0.9;  // DYNAMIC_RELAXATION
  static constexpr double kBulkViscosityLinear = 0.06;
  static constexpr double kBulkViscosityQuadratic = 1.5;
  static constexpr double kHourglassCoefficient = 0.05;
  static constexpr double kOutputIntervalFraction = 1.0 / 100;  // of end_s
  static constexpr double kRelaxationTolerance = 1e-4;

  double time_step_factor = kTimeStepFactor;  // of the stable step
  // Bulk viscosity, linear and quadratic terms (0 for DYNAMIC_RELAXATION,
  // which damps on its own).
  double bulk_viscosity_linear = kBulkViscosityLinear;
  double bulk_viscosity_quadratic = kBulkViscosityQuadratic;
  double mass_damping_per_s = 0;                         // C = alpha M [1/s]
  double hourglass_coefficient = kHourglassCoefficient;  // HEX8
  double output_interval_s = 0;                          // history rows and frames [s]
  double mass_scaling_step_s = 0;                        // 0: no mass scaling
  double erosion_strain = 0;                             // 0: no erosion
  double relaxation_tolerance = kRelaxationTolerance;    // DYNAMIC_RELAXATION

  // From analysis.explicit_dynamics for `type`, with `end_s` the analysis's
  // end time (the output interval's default).
  static ExplicitOptions FromSpec(const ExplicitSpec& spec, AnalysisSpec::Type type, double end_s);
};

// The sensors of EXPLICIT_DYNAMIC and their filter, defaults applied.
struct SensorOptions {
  static constexpr double kIntervalS = 1e-6;
  static constexpr int kFilterOrder = 4;
  static constexpr double kFilterCutoffHz = 1e4;

  std::vector<SensorSpec> sensors;  // positions and radii in mm, as reported
  double interval_s = kIntervalS;   // resampling interval of sensors.csv [s]
  int filter_order = kFilterOrder;  // zero-phase Butterworth low-pass
  double filter_cutoff_hz = kFilterCutoffHz;
  // Names outputs.filter_cutoff_hz when the filter does not fit the
  // sampling rate (the cutoff must lie below half of it).
  Status Validate() const;
};

// What the analysis reports and writes.
struct OutputOptions {
  static constexpr int kProfilePoints = 50;

  bool displacement = true, stress = true, von_mises = true, strain = true;
  bool pk2_stress = true, almansi_strain = true, jacobian = true;
  // Sets whose total reaction is reported: outputs.reaction_sets, or every
  // set a fixed, displacement or symmetry condition names, in order.
  std::vector<std::string> reaction_sets;
  // Structures (regions) whose displacement is reported; "*": all.
  std::vector<std::string> structure_displacements;
  // Lines sampled at the end (points and ends in mm, as reported; points
  // resolved, never 0).
  std::vector<ProfileSpec> profiles;
  SensorOptions sensors;
};

// A pressure or traction on a face set [Pa]; pressure pushes into the body
// when positive and, when `follower`, acts on the deformed surface.
struct SurfaceLoad {
  enum class Kind { kPressure, kTraction };
  Kind kind = Kind::kPressure;
  std::string set;
  double pressure_pa = 0;
  Eigen::Vector3d traction_pa = Eigen::Vector3d::Zero();
  bool follower = false;
};

// Gravity on every element's density, less the buoyancy of a surrounding
// fluid below its level.
struct GravityLoad {
  bool enabled = false;
  Eigen::Vector3d acceleration_m_per_s2 = Eigen::Vector3d::Zero();
  double fluid_density_kg_per_m3 = 0;   // 0: no fluid
  std::optional<double> fluid_level_m;  // height along -g; unset: fluid everywhere
};

// How a face set's nodes are held or moved, in the order the scene gives
// (a later condition on the same node and component wins); the implicit
// analyses read them resolved per unknown from Model::dofs, the explicit
// engine from here.
struct Motion {
  enum class Kind { kFixed, kDisplacement, kSymmetry, kVelocity };
  Kind kind = Kind::kFixed;
  std::string set;
  // kDisplacement [m] or kVelocity [m/s] per component at a(t) = 1; unset: free.
  std::array<std::optional<double>, 3> value{};
  int normal_axis = -1;  // kSymmetry: the axis normal to the plane (0, 1, 2)
};

struct Contact {
  std::string name;  // names its force and area in the summary and history
  std::string set;   // the face set it may touch
  RigidBody body;
  double friction = 0;
  // Scales the penalty: implicit, 100 by default (times the tissue's shear
  // modulus over the finest element size); explicit, 1 by default (times
  // each node's mass over the step squared).
  double penalty_factor = 0;
  double penetration_tolerance_m = 0;  // implicit: 1 % of the finest element size by default
  bool start_touching = false;

  static constexpr double kToleranceFraction = 0.01;  // of the finest element size
};

struct Problem {
  std::string name;      // the scene's, for files and summaries
  std::string geometry;  // what was meshed, e.g. "box 20 x 20 x 30 mm"
  AnalysisSpec::Type analysis = AnalysisSpec::Type::kLinearStatic;
  // The element of every analysis: the scene's, its default resolved
  // (TET4 for LINEAR_STATIC, TET4_ANP otherwise).
  ElementType element = ElementType::kTet4;
  double element_size_m = 0;  // the mesh's target edge length
  // The finest target size (an atlas's region of interest): the scale of
  // contact penalties and tolerances.
  double finest_element_size_m = 0;

  Model model;  // mesh [m], constraints, every element's material

  std::vector<SurfaceLoad> surface_loads;
  GravityLoad gravity;
  std::vector<Motion> motions;
  std::vector<Contact> contacts;

  LinearSolverOptions linear_solver;
  NonlinearOptions nonlinear;
  TimeOptions time;  // QUASI_STATIC, EXPLICIT_DYNAMIC
  ExplicitOptions explicit_dynamics;
  // Relaxation terms faster than the first are taken as relaxed, slower
  // than the second (when > 0) as never relaxing (formulation: AUTO).
  double relaxed_below_s = 0;
  double frozen_above_s = 0;
  OutputOptions outputs;
  // The threads the solve may use: SolveOptions::threads, set by
  // SolveScene (not by ResolveProblem, which sees only the scene).
  ThreadContext threads;
};

// Resolves everything but the mesh (Problem::model stays empty): the scene
// must validate (ValidateScene), then every option is resolved and checked.
// This is ValidateScene's second half: it fails naming the field.
Status ResolveProblem(const SceneSpec& scene, Problem* problem);

// The mesh, its regions, constraints and materials of a resolved problem
// (BuildModel of the scene it was resolved from). What fails here the
// scene's validation could not tell: what only the geometry's files and the
// mesh show (a structure a label volume lacks, a patch or inclusion that
// holds no element, a sensor outside the meshed body). It fails with
// kFailedPrecondition naming the field, never kInvalidArgument.
Status BuildProblemModel(const SceneSpec& scene, const BuildModelOptions& options,
                         Problem* problem);

// BuildProblemModel in its two halves (model_builder.h), for a solve that
// builds the model on a base mesh it refines (mesh.adapt); the same
// failures.
Status BuildProblemBaseMesh(const SceneSpec& scene, const BuildModelOptions& options,
                            BaseMesh* base);
Status BuildProblemModelOn(const SceneSpec& scene, BaseMesh base, Problem* problem);

// ResolveProblem, then BuildProblemModel.
Status BuildProblem(const SceneSpec& scene, const BuildModelOptions& options, Problem* problem);

// The outputs of a scene, resolved (no other check): what WriteResultFiles
// needs of a scene.
OutputOptions ResolveOutputs(const SceneSpec& scene);

// The loads of the problem's pressures, tractions and gravity at full
// value (SI). `problem` must outlive the result.
ExternalLoads BuildLoads(const Problem& problem);

// Every option the problem's analysis runs with, defaults included, as
// (scene field path, value with its unit): what the summary echoes.
std::vector<std::pair<std::string, std::string>> EffectiveOptions(const Problem& problem);

}  // namespace pba
