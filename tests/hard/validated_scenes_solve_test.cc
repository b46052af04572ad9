// Property test of the validation contract (pba/scene.h): a scene that
// ValidateScene accepts never fails later with kInvalidArgument. After
// validation a solve may still end in kFailedPrecondition (what only the
// mesh can tell: a sensor outside the body, a patch or inclusion holding no
// element) or kNumerical (a divergence), never in kInvalidArgument.
//
// Scene variants cross a small box with mutations of every part the
// validators read (scene_variants.h): analysis type x element x material
// (and relaxation form) x holds and loads x patches x gravity x inclusions
// x contacts x outputs x analysis options at their boundary values x
// formulation AUTO. A deterministic pseudo-random sample of them, plus the
// hand-written edge cases below, is validated; every accepted one is solved,
// each in a child process. The test fails on kInvalidArgument, on kInternal
// (a broken invariant) and on a crash; a solve that runs past
// kSceneTimeoutS is stopped and reported, not failed (a busy machine gets
// there too). Every outcome is counted by status code.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "hard/scene_variants.h"
#include "pba/scene.h"
#include "pba/solve.h"

namespace pba {
namespace {

using scene_variants::AddRelaxation;
using scene_variants::BaseScene;
using scene_variants::Contact;
using scene_variants::Describe;
using scene_variants::Held;
using scene_variants::Material;
using scene_variants::Pressure;
using scene_variants::Stiffer;
using scene_variants::Traction;
using scene_variants::Velocity;
using Type = AnalysisSpec::Type;
using BcKind = BoundaryConditionSpec::Kind;
using MatKind = MaterialSpec::Kind;
using Form = ViscoelasticSpec::Form;
using Shape = ContactSpec::Shape;
using Code = Status::Code;

// The sample: about 30 s of a Release build, on two cores idle or busy
// (the budget is three minutes).
constexpr uint32_t kSeed = 17;
constexpr int kSampled = 400;
// Far above any scene here on a quiet machine (most take well under a
// second): a scene that reaches it crawls or hangs, and must not hide the
// others' outcomes.
constexpr int kSceneTimeoutS = 30;

// A hand-written edge case: the base scene (or another small body)
// changed where the random sample rarely goes.
struct EdgeCase {
  const char* name;
  std::function<void(SceneSpec*)> change;
};

SceneSpec Impact() {
  SceneSpec s = BaseScene();
  s.analysis.type = Type::kExplicitDynamic;
  s.mesh.element = ElementType::kHex8;
  s.analysis.time.end_time_s = 2e-5;
  s.boundary_conditions = {Held("bottom", BcKind::kFixed)};
  s.contacts = {Contact(Shape::kCylinderRounded, "top")};
  s.outputs.sensors = {{"centre", {2, 2, 3}, 0}};
  return s;
}

SceneSpec QuasiStatic() {
  SceneSpec s = BaseScene();
  s.analysis.type = Type::kQuasiStatic;
  s.analysis.time.end_time_s = 1;
  AddRelaxation(Form::kProny, 1, &s.material);
  return s;
}

// Mesh sizes at their extremes, Newton controls at their bounds, and unusual
// holds and loads.
std::vector<EdgeCase> MeshNewtonAndHoldEdgeCases() {
  using S = SceneSpec*;
  return {
      {"default_element_size_on_a_small_box",
       [](S s) {
         s->analysis.type = Type::kLinearStatic;
         s->material = Material(MatKind::kLinearElastic, 1);
         s->geometry.box.size_mm = {0.5, 0.5, 0.75};
         s->mesh.element_size_mm = 0;
       }},
      {"element_larger_than_the_box", [](S s) { s->mesh.element_size_mm = 50; }},
      {"element_larger_than_the_box_hex8",
       [](S s) {
         s->mesh.element = ElementType::kHex8;
         s->mesh.element_size_mm = 50;
       }},
      {"ten_thousand_increments",
       [](S s) {
         s->mesh.element_size_mm = 6;
         s->analysis.nonlinear.increments = 10000;
       }},
      {"loosest_newton_controls",
       [](S s) {
         NonlinearOptionsSpec& n = s->analysis.nonlinear;
         n.increments = 1;
         n.max_iterations = 1000;
         n.residual_tolerance = n.displacement_tolerance = 0.999999;
         n.min_increment = 0.999999;
       }},
      // With max_iterations 1 and a tiny min_increment the increments
      // shrink until the numbers underflow, "converge", and creep on for
      // minutes; validation refuses anything below NonlinearOptions'
      // floor, 1e-12, which gives up in time.
      {"strictest_newton_controls",
       [](S s) {
         NonlinearOptionsSpec& n = s->analysis.nonlinear;
         n.max_iterations = 1;
         n.residual_tolerance = n.displacement_tolerance = 1e-300;
         n.min_increment = 1e-12;
         n.line_search = false;
       }},
      {"zero_pressure_only",
       [](S s) {
         s->boundary_conditions = {Held("bottom", BcKind::kFixed), Pressure("top", 0)};
       }},
      {"fixed_and_displaced_on_one_face",
       [](S s) {
         s->boundary_conditions = {Held("bottom", BcKind::kFixed), Held("top", BcKind::kFixed),
                                   Held("top", BcKind::kDisplacement, {0.0, 0.0, -0.2})};
       }},
      {"symmetry_on_patches",
       [](S s) {
         s->geometry.patches = {PatchSpec::HalfSpace("low", "x_min", {0, 0, 3}, {0, 0, -1}),
                                PatchSpec::Ball("dot", "y_min", {2, 0, 3}, 3)};
         s->boundary_conditions = {Held("low", BcKind::kSymmetry), Held("dot", BcKind::kSymmetry),
                                   Held("bottom", BcKind::kSymmetry), Pressure("top", 100)};
       }},
  };
}

// QUASI_STATIC time stepping and curves, and relaxation at its limits.
std::vector<EdgeCase> QuasiStaticEdgeCases() {
  using S = SceneSpec*;
  return {
      {"quasi_static_single_step",
       [](S s) {
         *s = QuasiStatic();
         TimeSpec& t = s->analysis.time;
         t.min_step_s = t.initial_step_s = t.max_step_s = t.end_time_s;
       }},
      {"quasi_static_step_load_and_hold",
       [](S s) {
         *s = QuasiStatic();
         s->analysis.time.curve = {{0, 1}};
       }},
      {"quasi_static_curve_past_the_end",
       [](S s) {
         *s = QuasiStatic();
         s->analysis.time.curve = {{0.5, 0}, {3, 2}};
       }},
      {"quasi_static_contact_and_growth",
       [](S s) {
         *s = QuasiStatic();
         s->contacts = {Contact(Shape::kSphere, "top")};
         s->contacts[0].start_touching = true;
         s->contacts[0].friction = 0.5;
         s->inclusions = {{"core", {2, 2, 3}, 1.6, Stiffer(s->material), 0.2}};
         s->outputs.structure_displacements = {"*"};
       }},
      {"quasi_static_relaxation_of_three_forms",
       [](S s) {
         *s = QuasiStatic();
         s->material.viscoelastic = ViscoelasticSpec();
         AddRelaxation(Form::kModuli, 1, &s->material);
         s->inclusions = {{"core", {2, 2, 3}, 1.6, Stiffer(s->material), 0}};
         AddRelaxation(Form::kExponential, 1, &s->inclusions[0].material);
       }},
      {"relaxation_that_does_not_relax",
       [](S s) {
         *s = QuasiStatic();
         ViscoelasticSpec& v = s->material.viscoelastic;
         v = ViscoelasticSpec();
         v.form = Form::kExponential;
         v.long_term_ratio = 1;
         v.beta_per_s = 1;
       }},
      {"prony_terms_of_zero_weight",
       [](S s) {
         *s = QuasiStatic();
         s->material.viscoelastic.g = {0, 0};
       }},
  };
}

// Inclusions (covering, hidden, shrinking) and rigid contacts (starting
// inside the body, never touching it, a cylinder in a static analysis).
std::vector<EdgeCase> InclusionAndContactEdgeCases() {
  using S = SceneSpec*;
  return {
      {"inclusion_over_the_whole_body",
       [](S s) {
         s->inclusions = {{"all", {2, 2, 3}, 100, Stiffer(s->material), 0}};
         s->outputs.structure_displacements = {"*"};
       }},
      {"inclusion_hidden_by_a_later_one",
       [](S s) {
         s->inclusions = {{"first", {2, 2, 3}, 1.6, Stiffer(s->material), 0},
                          {"second", {2, 2, 3}, 3, Stiffer(s->material), 0}};
         s->outputs.structure_displacements = {"first", "second"};
       }},
      {"growth_near_minus_one",
       [](S s) {
         s->boundary_conditions = {Held("bottom", BcKind::kFixed)};
         s->inclusions = {{"core", {2, 2, 3}, 1.6, Stiffer(s->material), -0.9}};
       }},
      {"contact_starting_inside_the_body",
       [](S s) {
         s->contacts = {Contact(Shape::kFlatPunch, "top")};
         s->contacts[0].position_mm = {2, 2, 5};
         s->contacts[0].start_touching = true;
       }},
      {"contact_that_never_touches",
       [](S s) {
         s->contacts = {Contact(Shape::kPlane, "bottom")};
         s->contacts[0].position_mm = {0, 0, 50};
         s->contacts[0].axis = {0, 0, 1};
       }},
      {"cylinder_punch_in_a_static_analysis",
       [](S s) {
         s->contacts = {Contact(Shape::kCylinderFlat, "top")};
         s->contacts[0].start_touching = true;
       }},
  };
}

// Gravity and buoyancy, and DYNAMIC_RELAXATION at its controls' bounds.
std::vector<EdgeCase> GravityAndRelaxationEdgeCases() {
  using S = SceneSpec*;
  return {
      {"fluid_level_through_the_body",
       [](S s) {
         s->boundary_conditions = {Held("bottom", BcKind::kFixed)};
         s->gravity = {true, {0, 0, -9.81}, 1007, 3.0};
       }},
      {"floating_in_a_denser_fluid",
       [](S s) {
         s->boundary_conditions = {Held("bottom", BcKind::kFixed)};
         s->gravity = {true, {0, 0, -9.81}, 2000, std::nullopt};
       }},
      {"gravity_in_dynamic_relaxation",
       [](S s) {
         s->analysis.type = Type::kDynamicRelaxation;
         s->boundary_conditions = {Held("bottom", BcKind::kFixed)};
         s->gravity = {true, {0, 0, -9.81}, 1007, std::nullopt};
       }},
      {"dynamic_relaxation_without_density",
       [](S s) {
         s->analysis.type = Type::kDynamicRelaxation;
         s->material.density_kg_per_m3 = 0;
         s->inclusions = {{"core", {2, 2, 3}, 1.6, Stiffer(s->material), 0}};
         s->inclusions[0].material.density_kg_per_m3 = 0;
       }},
      {"dynamic_relaxation_hex8_boundary_controls",
       [](S s) {
         s->analysis.type = Type::kDynamicRelaxation;
         s->mesh.element = ElementType::kHex8;
         s->mesh.element_size_mm = 3;
         ExplicitSpec& e = s->analysis.explicit_dynamics;
         e.hourglass_coefficient = 0.5;
         e.relaxation_tolerance = 0.0999;
         e.time_step_factor = 1;
       }},
      {"dynamic_relaxation_unstable_step",
       [](S s) {
         s->analysis.type = Type::kDynamicRelaxation;
         s->analysis.explicit_dynamics.time_step_factor = 2;
       }},
  };
}

// EXPLICIT_DYNAMIC impacts: every control, sensor filters at their bounds,
// prescribed motions.
std::vector<EdgeCase> ImpactEdgeCases() {
  using S = SceneSpec*;
  return {
      {"impact_unstable_step",
       [](S s) {
         *s = Impact();
         s->analysis.explicit_dynamics.time_step_factor = 2;
       }},
      {"impact_free_body_every_control",
       [](S s) {
         *s = Impact();
         s->boundary_conditions.clear();
         ExplicitSpec& e = s->analysis.explicit_dynamics;
         e.time_step_factor = 0.05;
         e.bulk_viscosity_linear = 10;
         e.bulk_viscosity_quadratic = 0;
         e.mass_damping_per_s = 1e4;
         e.hourglass_coefficient = 0.5;
         e.output_interval_s = 2e-5;
         e.mass_scaling_step_s = 1e-3;
         e.erosion_strain = 1e-6;
       }},
      {"impact_erodes_everything",
       [](S s) {
         *s = Impact();
         s->mesh.element = ElementType::kTet4;
         s->material.neo_hookean.bulk_modulus_pa = 1e8;
         s->analysis.explicit_dynamics.erosion_strain = 1e-9;
         s->contacts[0].motion_mm = {0, 0, -3};
       }},
      {"impact_sensor_interval_just_below_the_end",
       [](S s) {
         *s = Impact();
         s->outputs.sensor_interval_s = 1.99e-5;
       }},
      {"impact_cutoff_just_below_nyquist",
       [](S s) {
         *s = Impact();
         s->outputs.sensor_interval_s = 2e-6;
         s->outputs.filter_cutoff_hz = 2.4999e5;
         s->outputs.filter_order = 10;
       }},
      {"impact_default_cutoff_coarse_interval",
       [](S s) {
         *s = Impact();
         s->analysis.time.end_time_s = 2e-4;
         s->outputs.sensor_interval_s = 4e-5;  // Nyquist 12.5 kHz, above the default 10 kHz
       }},
      {"impact_default_cutoff_too_coarse_interval",
       [](S s) {
         *s = Impact();
         s->analysis.time.end_time_s = 2e-4;
         s->outputs.sensor_interval_s = 1e-4;  // Nyquist 5 kHz: the default cutoff does not fit
       }},
      {"impact_end_before_the_default_interval",
       [](S s) {
         *s = Impact();
         s->analysis.time.end_time_s = 5e-7;
       }},
      {"impact_low_cutoff_order_one",
       [](S s) {
         *s = Impact();
         s->outputs.filter_cutoff_hz = 100;
         s->outputs.filter_order = 1;
       }},
      {"impact_sensor_in_a_dense_inclusion",
       [](S s) {
         *s = Impact();
         s->inclusions = {{"core", {2, 2, 3}, 1.6, Stiffer(s->material), 0}};
         s->inclusions[0].material.density_kg_per_m3 = 5000;
         s->outputs.sensors.push_back({"in_core", {2, 2, 3}, 1.6});
         s->outputs.structure_displacements = {"core"};
       }},
      {"impact_piston_step_velocity",
       [](S s) {
         *s = Impact();
         s->contacts.clear();
         s->boundary_conditions = {Velocity("bottom", {0.0, std::nullopt, 2.0}),
                                   Held("top", BcKind::kDisplacement, {0.0, 0.0, 0.0})};
         s->analysis.time.curve = {{0, 1}};
       }},
      {"impact_prescribed_displacement_curve",
       [](S s) {
         *s = Impact();
         s->contacts.clear();
         s->boundary_conditions = {Held("bottom", BcKind::kFixed),
                                   Held("top", BcKind::kDisplacement, {0.0, 0.0, -0.01})};
         s->analysis.time.curve = {{0, 0}, {1e-5, 1}, {1.5e-5, -1}};
         s->gravity = {true, {0, 0, -1e4}, 0, std::nullopt};
       }},
      {"impact_relaxing_ogden",
       [](S s) {
         *s = Impact();
         s->material = Material(MatKind::kOgden, 1000);
         AddRelaxation(Form::kProny, 1e-5, &s->material);
       }},
      {"gel_half_cylinder_bolt",
       [](S s) {
         *s = Impact();
         s->mesh.element = ElementType::kTet4Anp;
         s->geometry.kind = GeometrySpec::Kind::kCylinder;
         s->geometry.cylinder = {4, 4, true};
         s->mesh.element_size_mm = 2;
         s->contacts = {Contact(Shape::kCylinderRounded, "cut")};
         s->contacts[0].position_mm = {0, 0.5, 2};
         s->contacts[0].axis = {0, -1, 0};
         s->contacts[0].motion_mm = {0, -1, 0};
         s->outputs.sensors = {{"below", {0, -2, 2}, 0}};
       }},
  };
}

// Shells, ellipsoids and cylinders: their named faces and patches.
std::vector<EdgeCase> CurvedGeometryEdgeCases() {
  using S = SceneSpec*;
  return {
      {"pressurised_shell_octant",
       [](S s) {
         s->geometry.kind = GeometrySpec::Kind::kSphericalShell;
         s->geometry.spherical_shell = {3, 5};
         s->mesh.element = ElementType::kTet10;
         s->mesh.element_size_mm = 2;
         s->boundary_conditions = {Held("x0", BcKind::kSymmetry), Held("y0", BcKind::kSymmetry),
                                   Held("z0", BcKind::kSymmetry), Pressure("inner", 100)};
         s->outputs.profiles = {{"radial", {1, 1, 1}, {4, 4, 4}, 0}};
       }},
      {"ellipsoid_held_by_a_cap",
       [](S s) {
         s->geometry.kind = GeometrySpec::Kind::kEllipsoid;
         s->geometry.ellipsoid.semi_axes_mm = {4, 3, 3};
         s->mesh.element_size_mm = 2;
         s->geometry.patches = {PatchSpec::HalfSpace("base", "surface", {0, 0, -2}, {0, 0, -1}),
                                PatchSpec::Ball("spot", "surface", {0, 0, 3}, 2)};
         s->boundary_conditions = {Held("base", BcKind::kFixed), Pressure("spot", 100)};
       }},
      {"cylinder_side_components",
       [](S s) {
         s->geometry.kind = GeometrySpec::Kind::kCylinder;
         s->geometry.cylinder = {2, 4, false};
         s->mesh.element = ElementType::kHex8;
         s->boundary_conditions = {
             Held("bottom", BcKind::kFixed),
             Held("side", BcKind::kDisplacement, {0.0, std::nullopt, std::nullopt}),
             Traction("top", {0, 50, 0})};
       }},
      {"half_cylinder_held_by_its_cut",
       [](S s) {
         s->geometry.kind = GeometrySpec::Kind::kCylinder;
         s->geometry.cylinder = {3, 4, true};
         s->mesh.element = ElementType::kTet10Md;
         s->boundary_conditions = {Held("bottom", BcKind::kFixed), Held("cut", BcKind::kSymmetry),
                                   Pressure("top", 100)};
         s->outputs.profiles = {{"down", {0, -1, 4}, {0, -1, 0}, 0}};
       }},
      {"cylinder_side_pressure_through_time",
       [](S s) {
         *s = QuasiStatic();
         s->geometry.kind = GeometrySpec::Kind::kCylinder;
         s->geometry.cylinder = {2, 4, false};
         s->boundary_conditions = {Held("bottom", BcKind::kFixed), Pressure("side", 100)};
         s->analysis.time.curve = {{0, 0}, {0.2, 1}, {1, 1}};
       }},
      {"shell_octant_struck_along_its_diagonal",
       [](S s) {
         *s = Impact();
         s->mesh.element = ElementType::kTet4Anp;
         s->geometry.kind = GeometrySpec::Kind::kSphericalShell;
         s->geometry.spherical_shell = {3, 5};
         s->boundary_conditions = {Held("x0", BcKind::kSymmetry), Held("y0", BcKind::kSymmetry),
                                   Held("z0", BcKind::kSymmetry)};
         s->contacts = {Contact(Shape::kSphere, "outer")};
         s->contacts[0].position_mm = {3.8, 3.8, 3.8};
         s->contacts[0].axis = {-1, -1, -1};
         s->contacts[0].motion_mm = {-0.3, -0.3, -0.3};
         s->outputs.sensors = {{"wall", {2.4, 2.4, 2.4}, 0}};
       }},
      {"ellipsoid_settling_under_gravity",
       [](S s) {
         s->analysis.type = Type::kDynamicRelaxation;
         s->geometry.kind = GeometrySpec::Kind::kEllipsoid;
         s->geometry.ellipsoid.semi_axes_mm = {4, 3, 3};
         s->mesh.element_size_mm = 3;
         s->geometry.patches = {PatchSpec::HalfSpace("base", "surface", {0, 0, -2}, {0, 0, -1})};
         s->boundary_conditions = {Held("base", BcKind::kFixed)};
         s->gravity = {true, {0, 0, -9.81}, 1007, 0.0};
       }},
  };
}

// Materials and linear solvers at their edges, and outputs that ask for
// little or much.
std::vector<EdgeCase> MaterialAndOutputEdgeCases() {
  using S = SceneSpec*;
  return {
      {"orthotropic_hex8_full_pcg",
       [](S s) {
         s->analysis.type = Type::kLinearStatic;
         s->mesh.element = ElementType::kHex8Full;
         s->material = Material(MatKind::kOrthotropicElastic, 1);
         s->analysis.linear_solver = AnalysisSpec::LinearSolver::kPcg;
         s->gravity = {true, {0, 0, -9.81}, 1007, 2.0};
       }},
      {"linear_nearly_incompressible_ldlt",
       [](S s) {
         s->analysis.type = Type::kLinearStatic;
         s->material = Material(MatKind::kLinearElastic, 1);
         s->material.linear_elastic.poissons_ratio = 0.4999999;
         s->analysis.linear_solver = AnalysisSpec::LinearSolver::kEigenLdlt;
       }},
      {"linear_negative_poisson",
       [](S s) {
         s->analysis.type = Type::kLinearStatic;
         s->material = Material(MatKind::kLinearElastic, 1);
         s->material.linear_elastic.poissons_ratio = -0.999;
       }},
      {"linear_viscoelastic_hyperelastic",
       [](S s) {
         s->analysis.type = Type::kLinearStatic;
         AddRelaxation(Form::kModuli, 1, &s->material);
         s->inclusions = {{"core", {2, 2, 3}, 1.6, Stiffer(s->material), 0}};
       }},
      {"polynomial_of_order_three",
       [](S s) {
         s->material = Material(MatKind::kPolynomial, 100);
         s->material.polynomial.terms = {
             {1, 0, 400}, {0, 1, 100}, {1, 1, 10}, {3, 0, 5}, {0, 3, 1}};
         s->material.polynomial.d_per_pa = {2e-5, 1e-6, 0};
       }},
      {"mooney_rivlin_negative_c01",
       [](S s) {
         s->material = Material(MatKind::kMooneyRivlin, 100);
         s->material.mooney_rivlin.c01_pa = -100;
       }},
      {"ogden_three_terms_bulk_equal_shear",
       [](S s) {
         s->material = Material(MatKind::kOgden, 1);
         s->material.ogden.terms = {{1500, -4.7}, {-600, 2}, {100, 8}};
         s->material.ogden.bulk_modulus_pa = 1000;
       }},
      {"profiles_of_every_length",
       [](S s) {
         s->outputs.profiles = {{"long", {2, 2, 0}, {2, 2, 6}, 1000},
                                {"short", {0, 0, 0}, {4, 4, 6}, 2},
                                {"out", {-5, -5, -5}, {-1, -1, -1}, 0}};
       }},
      {"reactions_of_an_unloaded_set",
       [](S s) {
         s->outputs.reaction_sets = {"x_min", "y_max", "top"};
       }},
      {"no_output_fields",
       [](S s) {
         OutputSpec& o = s->outputs;
         o.displacement = o.stress = o.strain = o.von_mises = false;
         o.pk2_stress = o.almansi_strain = o.jacobian = false;
       }},
  };
}

// Formulation AUTO on small strains, relaxation and contact.
std::vector<EdgeCase> AutoFormulationEdgeCases() {
  using S = SceneSpec*;
  return {
      {"auto_small_strain_tet4",
       [](S s) {
         s->mesh.element = ElementType::kTet4;
         s->formulation = Formulation::kAuto;
         s->boundary_conditions[1].displacement_mm[2] = -0.01;
       }},
      {"auto_small_strain_hex8_tight_tolerance",
       [](S s) {
         s->mesh.element = ElementType::kHex8;
         s->formulation = Formulation::kAuto;
         s->formulation_tolerance = 1e-9;
         s->boundary_conditions[1].displacement_mm[2] = -0.01;
         s->outputs.reaction_sets = {"top"};
       }},
      {"auto_small_strain_tet10_loose_tolerance",
       [](S s) {
         s->mesh.element = ElementType::kTet10;
         s->formulation = Formulation::kAuto;
         s->formulation_tolerance = 0.999999;
         s->boundary_conditions = {Held("bottom", BcKind::kFixed), Pressure("top", 1)};
         AddRelaxation(Form::kProny, 1, &s->material);
         s->inclusions = {{"core", {2, 2, 3}, 1.6, Stiffer(s->material), 0}};
         s->outputs.structure_displacements = {"*"};
       }},
      {"auto_default_element_one_increment",
       [](S s) {
         s->formulation = Formulation::kAuto;
         s->formulation_tolerance = 0.5;
         s->analysis.nonlinear.increments = 7;
         s->boundary_conditions[1].displacement_mm[2] = -0.001;
       }},
      {"auto_quasi_static_fast_relaxation",
       [](S s) {
         *s = QuasiStatic();
         s->formulation = Formulation::kAuto;
         s->formulation_tolerance = 0.5;
         s->material.viscoelastic.tau_s = {1e-4, 1e4};
       }},
      {"auto_quasi_static_tet10_fast_relaxation",
       [](S s) {
         *s = QuasiStatic();
         s->mesh.element = ElementType::kTet10;
         s->formulation = Formulation::kAuto;
         s->formulation_tolerance = 0.999999;
         s->material.viscoelastic.tau_s = {1e-5, 1e-4};
       }},
      {"auto_linear_static",
       [](S s) {
         s->analysis.type = Type::kLinearStatic;
         s->mesh.element = ElementType::kTet10;
         s->formulation = Formulation::kAuto;
         AddRelaxation(Form::kExponential, 1, &s->material);
       }},
      {"auto_with_contact",
       [](S s) {
         s->formulation = Formulation::kAuto;
         s->mesh.element = ElementType::kHex8;
         s->boundary_conditions = {Held("bottom", BcKind::kFixed)};
         s->contacts = {Contact(Shape::kSphere, "top")};
       }},
  };
}

// Every edge case, in a fixed order.
std::vector<EdgeCase> EdgeCases() {
  std::vector<EdgeCase> cases;
  for (std::vector<EdgeCase> (*group)() :
       {MeshNewtonAndHoldEdgeCases, QuasiStaticEdgeCases, InclusionAndContactEdgeCases,
        GravityAndRelaxationEdgeCases, ImpactEdgeCases, CurvedGeometryEdgeCases,
        MaterialAndOutputEdgeCases, AutoFormulationEdgeCases}) {
    for (EdgeCase& edge : group()) cases.push_back(std::move(edge));
  }
  return cases;
}

const char* CodeName(Code code) {
  switch (code) {
    case Code::kOk:
      return "OK";
    case Code::kInvalidArgument:
      return "INVALID_ARGUMENT";
    case Code::kFailedPrecondition:
      return "FAILED_PRECONDITION";
    case Code::kNumerical:
      return "NUMERICAL";
    case Code::kIo:
      return "IO";
    case Code::kCancelled:
      return "CANCELLED";
    case Code::kInternal:
      return "INTERNAL";
    default:
      return "OTHER";
  }
}

// A solve in a child process, so that a crash or a hang on one scene does
// not hide the outcomes of the others. The parent never solves (it only
// validates), so the child starts with no OpenMP threads to lose across
// fork().
struct Outcome {
  enum class End { kReturned, kCrashed, kTimedOut } end = End::kReturned;
  Code code = Code::kOk;
  std::string field;
  std::string message;
  int signal = 0;
  double seconds = 0;
};

void WriteString(int fd, const std::string& text) {
  const uint32_t size = static_cast<uint32_t>(text.size());
  if (write(fd, &size, sizeof size) != sizeof size) return;
  if (size > 0 && write(fd, text.data(), size) != static_cast<ssize_t>(size)) return;
}

bool ReadAll(int fd, void* data, std::size_t size) {
  auto* at = static_cast<char*>(data);
  while (size > 0) {
    const ssize_t got = read(fd, at, size);
    if (got <= 0) return false;
    at += got;
    size -= static_cast<std::size_t>(got);
  }
  return true;
}

bool ReadString(int fd, std::string* text) {
  uint32_t size = 0;
  if (!ReadAll(fd, &size, sizeof size)) return false;
  text->resize(size);
  return size == 0 || ReadAll(fd, text->data(), size);
}

Outcome SolveIsolated(const SceneSpec& scene) {
  const auto start = std::chrono::steady_clock::now();
  Outcome outcome;
  int fds[2];
  if (pipe(fds) != 0) {
    outcome.end = Outcome::End::kCrashed;
    outcome.message = "pipe() failed";
    return outcome;
  }
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    outcome.end = Outcome::End::kCrashed;
    outcome.message = "fork() failed";
    return outcome;
  }
  if (pid == 0) {
    close(fds[0]);
    alarm(kSceneTimeoutS);
    // One thread: the meshes hold a few dozen elements, and a team of two,
    // whose explicit steps meet at a barrier up to 200000 times, runs many
    // times slower while another process holds a core (the whole sample:
    // 30 s on one thread, 4.5 min on two, with one core busy).
    SolveOptions options;
    options.threads = 1;
    Solution solution;
    const Status status = SolveScene(scene, options, &solution);
    const int32_t code = static_cast<int32_t>(status.code());
    if (write(fds[1], &code, sizeof code) == sizeof code) {
      WriteString(fds[1], status.field());
      WriteString(fds[1], status.message());
    }
    close(fds[1]);
    _exit(0);
  }
  close(fds[1]);
  int32_t code = 0;
  const bool got = ReadAll(fds[0], &code, sizeof code) && ReadString(fds[0], &outcome.field) &&
                   ReadString(fds[0], &outcome.message);
  close(fds[0]);
  int wait_status = 0;
  waitpid(pid, &wait_status, 0);
  outcome.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (WIFSIGNALED(wait_status)) {
    outcome.signal = WTERMSIG(wait_status);
    outcome.end = outcome.signal == SIGALRM ? Outcome::End::kTimedOut : Outcome::End::kCrashed;
  } else if (!got) {
    outcome.end = Outcome::End::kCrashed;
  } else {
    outcome.code = static_cast<Code>(code);
  }
  return outcome;
}

struct Variant {
  std::string label;
  SceneSpec scene;
};

std::vector<Variant> AllVariants() {
  std::vector<Variant> variants;
  const std::vector<SceneSpec> sampled = scene_variants::SampledScenes(kSeed, kSampled);
  for (std::size_t i = 0; i < sampled.size(); ++i) {
    variants.push_back({"sample " + std::to_string(i), sampled[i]});
  }
  for (const EdgeCase& edge : EdgeCases()) {
    SceneSpec scene = BaseScene();
    edge.change(&scene);
    variants.push_back({std::string("edge ") + edge.name, scene});
  }
  return variants;
}

TEST(ValidatedScenesSolveTest, NoValidatedSceneFailsWithInvalidArgument) {
  const std::vector<Variant> variants = AllVariants();
  std::vector<const Variant*> valid;
  std::map<std::string, int> refused_by;  // field of the refusal
  for (const Variant& v : variants) {
    const Status status = ValidateScene(v.scene);
    if (status.ok()) {
      valid.push_back(&v);
    } else {
      ++refused_by[status.field()];
    }
  }
  std::printf("generated %zu scenes (%d sampled, %zu edge cases), %zu validated\n", variants.size(),
              kSampled, variants.size() - kSampled, valid.size());
  std::printf("refusals by field:\n");
  for (const auto& [field, count] : refused_by) std::printf("  %4d %s\n", count, field.c_str());
  // A generator that drifts into mostly refused scenes tests little.
  EXPECT_GE(valid.size(), 100u);

  std::map<std::string, int> ended;
  std::map<std::string, double> seconds;
  double slowest = 0;
  std::string slowest_label;
  for (const Variant* v : valid) {
    const Outcome outcome = SolveIsolated(v->scene);
    std::string end = CodeName(outcome.code);
    if (outcome.end == Outcome::End::kCrashed) end = "CRASHED";
    if (outcome.end == Outcome::End::kTimedOut) end = "TIMED_OUT";
    ++ended[end];
    seconds[end] += outcome.seconds;
    if (outcome.seconds > slowest) slowest = outcome.seconds, slowest_label = v->label;
    const std::string where = v->label + ": " + Describe(v->scene);
    if (outcome.end == Outcome::End::kCrashed) {
      ADD_FAILURE() << "the solve of a validated scene crashed (signal " << outcome.signal
                    << ")\n  " << where;
    } else if (outcome.end == Outcome::End::kTimedOut) {
      // Not the contract's business, and a busy machine can get here: said,
      // not failed, so that the test does not flake.
      std::printf("%s -> stopped after %d s: %s\n", v->label.c_str(), kSceneTimeoutS,
                  Describe(v->scene).c_str());
    } else if (outcome.code == Code::kInvalidArgument) {
      ADD_FAILURE() << "a validated scene failed with kInvalidArgument\n  " << where
                    << "\n  field: " << outcome.field << "\n  message: " << outcome.message;
    } else if (outcome.code == Code::kInternal) {
      // A broken invariant (status.h), such as an engine handed what
      // validation should have refused.
      ADD_FAILURE() << "a validated scene failed with kInternal\n  " << where
                    << "\n  field: " << outcome.field << "\n  message: " << outcome.message;
    } else if (outcome.code != Code::kOk) {
      std::printf("%s -> %s (%.2f s) %s: %s\n", v->label.c_str(), end.c_str(), outcome.seconds,
                  outcome.field.c_str(), outcome.message.c_str());
    } else if (outcome.seconds > 2) {
      // What to shrink when the test grows slow.
      std::printf("%s -> OK in %.2f s: %s\n", v->label.c_str(), outcome.seconds,
                  Describe(v->scene).c_str());
    }
  }
  std::printf("outcomes of the %zu validated scenes:\n", valid.size());
  for (const auto& [end, count] : ended) {
    std::printf("  %4d %-20s (%.1f s)\n", count, end.c_str(), seconds[end]);
  }
  std::printf("slowest: %s, %.2f s\n", slowest_label.c_str(), slowest);
}

}  // namespace
}  // namespace pba
