// Scene variants for validated_scenes_solve_test.cc (scene_variants.h).
#include "hard/scene_variants.h"

#include <cstdio>
#include <initializer_list>
#include <random>
#include <string>
#include <vector>

namespace pba::scene_variants {
namespace {

using Type = AnalysisSpec::Type;
using BcKind = BoundaryConditionSpec::Kind;
using MatKind = MaterialSpec::Kind;
using Form = ViscoelasticSpec::Form;
using Shape = ContactSpec::Shape;

// std::mt19937's output is fixed by the standard, the distributions' are
// not: drawing by remainder keeps the sample the same on every library.
class Dice {
 public:
  explicit Dice(uint32_t seed) : rng_(seed) {}
  int Below(int n) { return static_cast<int>(rng_() % static_cast<uint32_t>(n)); }
  bool Chance(double p) { return rng_() < p * 4294967296.0; }
  template <typename T>
  T Of(std::initializer_list<T> values) {
    return values.begin()[Below(static_cast<int>(values.size()))];
  }

 private:
  std::mt19937 rng_;
};

}  // namespace

BoundaryConditionSpec Held(const std::string& set, BcKind kind, Components mm) {
  BoundaryConditionSpec bc;
  bc.set = set;
  bc.kind = kind;
  bc.displacement_mm = mm;
  return bc;
}

BoundaryConditionSpec Pressure(const std::string& set, double pa) {
  BoundaryConditionSpec bc = Held(set, BcKind::kPressure);
  bc.pressure_pa = pa;
  return bc;
}

BoundaryConditionSpec Traction(const std::string& set, std::array<double, 3> pa) {
  BoundaryConditionSpec bc = Held(set, BcKind::kTraction);
  bc.traction_pa = pa;
  return bc;
}

BoundaryConditionSpec Velocity(const std::string& set, Components m_per_s) {
  BoundaryConditionSpec bc = Held(set, BcKind::kVelocity);
  bc.velocity_m_per_s = m_per_s;
  return bc;
}

MaterialSpec Material(MatKind kind, double bulk_ratio) {
  MaterialSpec m;
  m.name = "tissue";
  m.kind = kind;
  m.density_kg_per_m3 = 1040;
  const double mu = 1000, bulk = bulk_ratio * mu;
  switch (kind) {
    case MatKind::kLinearElastic:
      m.linear_elastic = {3000, 0.45};
      break;
    case MatKind::kOrthotropicElastic:
      m.orthotropic_elastic = {6000, 3000, 1500, 0.3, 0.35, 0.4, 1500, 900, 600};
      m.orthotropic_elastic.axis_1 = {1, 1, 0};
      m.orthotropic_elastic.axis_2 = {0, 1, 1};
      break;
    case MatKind::kNeoHookean:
      m.neo_hookean = {mu, bulk};
      break;
    case MatKind::kMooneyRivlin:
      m.mooney_rivlin = {300, 200, bulk};
      break;
    case MatKind::kPolynomial:
      m.polynomial.terms = {{1, 0, 300}, {0, 1, 200}, {2, 0, 50}};
      m.polynomial.d_per_pa = {2 / bulk, 0};
      break;
    case MatKind::kOgden:
      m.ogden.terms = {{842, -4.7}, {158, 2}};
      m.ogden.bulk_modulus_pa = bulk;
      break;
    case MatKind::kNone:
      break;
  }
  return m;
}

void AddRelaxation(Form form, double time_scale, MaterialSpec* m) {
  ViscoelasticSpec& v = m->viscoelastic;
  v.form = form;
  switch (form) {
    case Form::kProny:
      v.g = {0.4, 0.2};
      v.tau_s = {0.3 * time_scale, 3 * time_scale};
      break;
    case Form::kExponential:
      v.long_term_ratio = 0.3;
      v.beta_per_s = 2 / time_scale;
      break;
    case Form::kModuli:
      v.long_term_modulus_pa = 300;
      v.moduli_pa = {500, 0, 200};
      v.tau_s = {0.2 * time_scale, time_scale, 10 * time_scale};
      break;
    case Form::kNone:
      break;
  }
}

MaterialSpec Stiffer(const MaterialSpec& scene) {
  MaterialSpec m = scene;
  m.name = "stiff";
  m.viscoelastic = ViscoelasticSpec();
  if (!scene.hyperelastic()) {
    m.kind = MatKind::kLinearElastic;
    m.linear_elastic = {15000, 0.4};
    return m;
  }
  m.kind = MatKind::kNeoHookean;
  m.neo_hookean = {5000, 5e5};
  return m;
}

ContactSpec Contact(Shape shape, const std::string& set) {
  ContactSpec c;
  c.name = "tool";
  c.set = set;
  c.shape = shape;
  c.axis = {0, 0, -1};
  c.radius_mm = 1;
  c.position_mm = {2, 2, shape == Shape::kSphere ? 7.1 : 6.1};
  c.motion_mm = {0, 0, -0.3};
  return c;
}

SceneSpec BaseScene() {
  SceneSpec s;
  s.name = "variant";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {4, 4, 6};
  s.mesh.element_size_mm = 2;
  s.material = Material(MatKind::kNeoHookean, 100);
  s.boundary_conditions = {Held("bottom", BcKind::kFixed),
                           Held("top", BcKind::kDisplacement, {std::nullopt, std::nullopt, -0.2})};
  s.analysis.type = Type::kNonlinearStatic;
  return s;
}

namespace {

// The sample. "Consistent" draws keep to the combinations the analysis
// takes, so that a good share validates; the others roam freely, so that
// the refusals are crossed with everything else too.

void DrawTime(Dice& dice, bool consistent, SceneSpec* s) {
  const Type type = s->analysis.type;
  const bool dynamic = type == Type::kExplicitDynamic;
  if (type != Type::kQuasiStatic && !dynamic && (consistent || !dice.Chance(0.3))) return;
  const double end = dynamic ? dice.Of({2e-5, 2e-5, 5e-5, 2e-4}) : dice.Of({1.0, 1.0, 1e-3, 100.0});
  s->analysis.time.end_time_s = end;
  TimeSpec& t = s->analysis.time;
  switch (dice.Below(7)) {
    case 0:  // ramp and hold
      t.curve = {{0, 0}, {0.5 * end, 1}, {end, 1}};
      break;
    case 1:  // a step at t = 0: one point
      t.curve = {{0, 1}};
      break;
    case 2:  // starts late, ends early (held after)
      t.curve = {{0.2 * end, 0}, {0.6 * end, 1}};
      break;
    case 3:  // load and unload, through negative amplitudes
      t.curve = {{0, 0}, {0.3 * end, 1}, {0.6 * end, -0.5}, {2 * end, 0}};
      break;
    default:  // a ramp, a(t) = t / end
      break;
  }
  if (type != Type::kQuasiStatic && consistent) return;
  switch (dice.Below(5)) {
    case 0:  // one step: every bound at the end time
      t.min_step_s = t.initial_step_s = t.max_step_s = end;
      break;
    case 1:
      t.min_step_s = 1e-3 * end;
      t.initial_step_s = 0.5 * end;
      break;
    case 2:
      t.max_step_s = 0.05 * end;
      break;
    default:
      break;
  }
}

void DrawNonlinearOptions(Dice& dice, SceneSpec* s) {
  NonlinearOptionsSpec& n = s->analysis.nonlinear;
  n.increments = dice.Of({0, 1, 2, 12});
  n.max_iterations = dice.Of({0, 1, 3, 1000});
  n.residual_tolerance = dice.Of({0.0, 1e-14, 0.5, 0.999999});
  n.displacement_tolerance = dice.Of({0.0, 1e-14, 0.5, 0.999999});
  // A Newton that does not converge (starved of iterations, asked for
  // 1e-14, or stuck in frictional contact) cuts its increments over and
  // over: with a budget of 1000 iterations or a tight tolerance it must give
  // up at a large smallest increment, or the sample runs for minutes.
  const bool strict = n.residual_tolerance == 1e-14 || n.displacement_tolerance == 1e-14;
  if (strict && n.max_iterations == 1000) n.max_iterations = 0;
  const bool hard = strict || n.max_iterations != 0;
  n.min_increment = hard ? dice.Of({0.5, 0.999}) : dice.Of({0.0, 1e-9, 0.5, 0.999});
  n.line_search = dice.Chance(0.5);
}

void DrawExplicitControls(Dice& dice, bool consistent, SceneSpec* s) {
  const Type type = s->analysis.type;
  const bool dynamic = type == Type::kExplicitDynamic || !consistent;
  const bool relaxation = type == Type::kDynamicRelaxation || !consistent;
  const double end = s->analysis.time.end_time_s > 0 ? s->analysis.time.end_time_s : 1e-4;
  ExplicitSpec& e = s->analysis.explicit_dynamics;
  const auto maybe = [&] { return dice.Chance(0.35); };
  // Dynamic relaxation at a factor of 1 or less than 0.5 may not settle
  // within its 200000 steps, which take minutes on a busy machine.
  if (maybe()) {
    e.time_step_factor =
        type == Type::kDynamicRelaxation ? dice.Of({0.5, 2.0}) : dice.Of({0.05, 0.5, 1.0, 2.0});
  }
  if (maybe()) e.hourglass_coefficient = dice.Of({1e-6, 0.05, 0.5});
  if (dynamic) {
    if (maybe()) e.bulk_viscosity_linear = dice.Of({0.0, 1.5, 10.0});
    if (maybe()) e.bulk_viscosity_quadratic = dice.Of({0.0, 10.0});
    if (maybe()) e.mass_damping_per_s = dice.Of({1e-3, 1e4});
    if (maybe()) e.output_interval_s = dice.Of({end, 0.01 * end, 1e-9});
    if (maybe()) e.mass_scaling_step_s = dice.Of({1e-9, 1e-6, 1e-3});
    if (maybe()) e.erosion_strain = dice.Of({1e-6, 0.5, 10.0});
  }
  if (relaxation && maybe()) e.relaxation_tolerance = dice.Of({1e-6, 1e-3, 0.0999});
}

// Holds and loads on the box; `load_set` is the top or a patch of it.
void DrawConditions(Dice& dice, bool consistent, const std::string& load_set, SceneSpec* s) {
  const Type type = s->analysis.type;
  const bool dynamic = type == Type::kExplicitDynamic;
  int holding = dice.Below(10);
  // Velocity, a free body and an under-held one are for EXPLICIT_DYNAMIC,
  // which takes a piston more often.
  if (consistent && !dynamic && holding >= 7) holding = dice.Below(7);
  if (consistent && dynamic && dice.Chance(0.2)) holding = 7;
  // Unloaded, dynamic relaxation runs its 200000 steps (seconds, or
  // minutes on a busy machine) before it gives up.
  const bool relaxation = consistent && type == Type::kDynamicRelaxation;
  if (relaxation && holding == 5) holding = 1;
  const Components down = {std::nullopt, std::nullopt, -0.2};
  auto& bcs = s->boundary_conditions;
  switch (holding) {
    case 0:
      bcs = {Held("bottom", BcKind::kFixed), Held(load_set, BcKind::kDisplacement, down)};
      break;
    case 1:
      bcs = {Held("bottom", BcKind::kFixed),
             Pressure(load_set, relaxation ? 200.0 : dice.Of({200.0, -100.0, 0.0}))};
      break;
    case 2:
      bcs = {Held("bottom", BcKind::kFixed), Traction(load_set, {20, 0, -100})};
      break;
    case 3:  // a quarter model: three symmetry planes hold it
      bcs = {Held("x_min", BcKind::kSymmetry), Held("y_min", BcKind::kSymmetry),
             Held("bottom", BcKind::kSymmetry), Pressure(load_set, 200)};
      break;
    case 4:  // components only, on both ends
      bcs = {Held("bottom", BcKind::kDisplacement, {0.0, 0.0, 0.0}),
             Held(load_set, BcKind::kDisplacement, {0.05, std::nullopt, -0.2})};
      break;
    case 5:  // held only: gravity, contacts or growth load it
      bcs = {Held("bottom", BcKind::kFixed)};
      break;
    case 6:  // a load on a held face, and a symmetry beside a fixed one
      bcs = {Held("bottom", BcKind::kFixed), Traction("bottom", {0, 0, 50}),
             Held("x_min", BcKind::kSymmetry), Pressure(load_set, 150)};
      break;
    case 7:  // a piston
      bcs = {Velocity("bottom", {std::nullopt, std::nullopt, 1.0})};
      if (dice.Chance(0.5)) bcs.push_back(Held("top", BcKind::kFixed));
      break;
    case 8:  // free
      bcs.clear();
      break;
    default:  // held along z only
      bcs = {Held("bottom", BcKind::kDisplacement, {std::nullopt, std::nullopt, 0.0}),
             Pressure(load_set, 100)};
      break;
  }
}

// The tetrahedra of the tet4 family (the default element is one): growth,
// and relaxation in QUASI_STATIC, take only these.
bool Tet4Family(const SceneSpec& s) {
  return s.mesh.element == ElementType::kDefault || s.mesh.element == ElementType::kTet4 ||
         s.mesh.element == ElementType::kTet4Anp;
}

// The element and its size.
void DrawMesh(Dice& dice, bool consistent, SceneSpec* s) {
  const Type type = s->analysis.type;
  const bool explicit_engine = type == Type::kExplicitDynamic || type == Type::kDynamicRelaxation;
  if (!consistent) {
    s->mesh.element = dice.Of({ElementType::kDefault, ElementType::kTet4, ElementType::kTet4Anp,
                               ElementType::kTet10, ElementType::kTet10Md, ElementType::kHex8,
                               ElementType::kHex8Full});
  } else if (explicit_engine) {
    s->mesh.element = dice.Of(
        {ElementType::kDefault, ElementType::kTet4, ElementType::kTet4Anp, ElementType::kHex8});
  } else if (type == Type::kLinearStatic) {
    s->mesh.element = dice.Of({ElementType::kDefault, ElementType::kTet4, ElementType::kTet10,
                               ElementType::kHex8, ElementType::kHex8Full});
  } else {
    s->mesh.element = dice.Of({ElementType::kDefault, ElementType::kTet4, ElementType::kTet4Anp,
                               ElementType::kTet10, ElementType::kTet10Md, ElementType::kHex8,
                               ElementType::kHex8Full});
  }
  s->mesh.element_size_mm = dice.Of({2.0, 2.0, 2.0, 3.0, 6.0});
  // Dynamic relaxation does not always settle (HEX8 at 2 mm never does):
  // then it runs 200000 steps, cheap only on the coarsest meshes.
  if (consistent && type == Type::kDynamicRelaxation) {
    s->mesh.element_size_mm = dice.Of({3.0, 6.0});
  }
}

// The material, its density and maybe a relaxation.
void DrawMaterial(Dice& dice, bool consistent, SceneSpec* s) {
  const Type type = s->analysis.type;
  const bool dynamic = type == Type::kExplicitDynamic;
  const bool tet4_family = Tet4Family(*s);
  const bool linear_ok = type == Type::kLinearStatic || !consistent;
  const MatKind kind =
      linear_ok
          ? dice.Of({MatKind::kLinearElastic, MatKind::kOrthotropicElastic, MatKind::kNeoHookean,
                     MatKind::kMooneyRivlin, MatKind::kPolynomial, MatKind::kOgden})
          : dice.Of({MatKind::kNeoHookean, MatKind::kMooneyRivlin, MatKind::kPolynomial,
                     MatKind::kOgden});
  s->material = Material(kind, dice.Of({1.0, 10.0, 100.0, 1000.0}));
  if (!dynamic || !consistent) s->material.density_kg_per_m3 = dice.Of({1040.0, 1040.0, 0.0});
  const bool relaxation_ok =
      s->material.hyperelastic() && (type != Type::kQuasiStatic || tet4_family);
  if ((relaxation_ok || !consistent) && dice.Chance(0.5)) {
    const double scale = type == Type::kQuasiStatic ? s->analysis.time.end_time_s : 1.0;
    AddRelaxation(dice.Of({Form::kProny, Form::kExponential, Form::kModuli}), scale, &s->material);
  }
}

// Patches of the top; returns the set loads go on (the top or a patch).
std::string DrawPatches(Dice& dice, SceneSpec* s) {
  std::string load_set = "top";
  switch (dice.Below(12)) {
    case 0:
    case 1:
      s->geometry.patches = {PatchSpec::Ball("spot", "top", {2, 2, 6}, 3)};
      load_set = "spot";
      break;
    case 2:
      s->geometry.patches = {PatchSpec::HalfSpace("half", "top", {2, 2, 6}, {1, 0, 0})};
      load_set = "half";
      break;
    case 3: {
      PatchSpec rim = PatchSpec::Ball("rim", "top", {2, 2, 6}, 1);
      rim.invert = true;
      rim.half_space = true;
      rim.plane_normal = {0, 1, 0};
      s->geometry.patches = {rim};
      load_set = "rim";
      break;
    }
    case 4:  // holds no face at 2 mm: the mesh tells (kFailedPrecondition)
      s->geometry.patches = {PatchSpec::Ball("speck", "top", {1.3, 0.7, 6}, 0.05)};
      load_set = "speck";
      break;
    default:
      break;
  }
  return load_set;
}

// Gravity, with and without buoyancy.
void DrawGravity(Dice& dice, bool consistent, SceneSpec* s) {
  if (dice.Chance(0.3)) {
    GravitySpec& g = s->gravity;
    g.enabled = true;
    g.acceleration_m_per_s2 =
        dice.Of<std::array<double, 3>>({{0, 0, -9.81}, {3, 0, -9.81}, {0, 0, -1e4}});
    switch (dice.Below(4)) {
      case 0:
        g.fluid_density_kg_per_m3 = 1007;
        break;
      case 1:
        g.fluid_density_kg_per_m3 = 1007;
        g.fluid_level_mm = dice.Of({3.0, -10.0, 100.0});
        break;
      case 2:  // denser than the tissue: it floats
        g.fluid_density_kg_per_m3 = 1100;
        break;
      default:
        break;
    }
    if (consistent && s->material.density_kg_per_m3 == 0) s->material.density_kg_per_m3 = 1040;
  }
}

// Inclusions, growing or not.
void DrawInclusions(Dice& dice, bool consistent, SceneSpec* s) {
  const Type type = s->analysis.type;
  const bool tet4_family = Tet4Family(*s);
  const bool growth_ok =
      (type == Type::kNonlinearStatic || type == Type::kQuasiStatic) && tet4_family;
  switch (dice.Below(12)) {
    case 0:
    case 1:
    case 2:
    case 3: {
      InclusionSpec core{"core", {2, 2, 3}, 1.6, Stiffer(s->material), 0};
      if ((growth_ok || !consistent) && dice.Chance(0.6)) {
        core.growth_strain = dice.Of({0.1, -0.3, 1.0});
      }
      s->inclusions = {core};
      break;
    }
    case 4:  // outside the body, or too small to hold an element's centre
      s->inclusions = {
          InclusionSpec{"stray", dice.Of<std::array<double, 3>>({{20, 20, 20}, {0.1, 0.1, 0.1}}),
                        0.05, Stiffer(s->material), 0}};
      break;
    default:
      break;
  }
}

// Rigid contacts (impactors in EXPLICIT_DYNAMIC); `load_set` as for
// DrawConditions.
void DrawContacts(Dice& dice, bool consistent, const std::string& load_set, SceneSpec* s) {
  const Type type = s->analysis.type;
  const bool dynamic = type == Type::kExplicitDynamic;
  const bool contact_ok = type == Type::kNonlinearStatic || type == Type::kQuasiStatic || dynamic;
  if ((contact_ok || !consistent) && dice.Chance(0.4)) {
    ContactSpec c = Contact(dice.Of({Shape::kFlatPunch, Shape::kSphere, Shape::kPlane,
                                     Shape::kCylinderFlat, Shape::kCylinderRounded}),
                            dice.Chance(0.7) ? "top" : load_set);
    if (!dynamic || !consistent) {
      c.start_touching = dice.Chance(0.5);
      c.friction = dice.Of({0.0, 0.2, 0.5});
    }
    c.penalty_factor = dice.Of({0.0, 0.0, 1.0, 1e4});
    c.penetration_tolerance_mm = dice.Of({0.0, 0.0, 1e-3});
    s->contacts = {c};
  }
}

// Output fields, profiles, sensors, structures and reactions.
void DrawOutputs(Dice& dice, bool consistent, const std::string& load_set, SceneSpec* s) {
  const Type type = s->analysis.type;
  const bool dynamic = type == Type::kExplicitDynamic;
  OutputSpec& o = s->outputs;
  if (dice.Chance(0.3)) {
    o.profiles.push_back({"axis", {2, 2, 0}, {2, 2, 6}, dice.Of({0, 2, 1000})});
    if (dice.Chance(0.3)) o.profiles.push_back({"outside-1", {10, 10, 10}, {20, 20, 20}, 2});
  }
  if ((dynamic || !consistent) && dice.Chance(0.6)) {
    o.sensors = {{"centre", {2, 2, 3}, 0}};
    if (dice.Chance(0.4)) o.sensors.push_back({"ball_2", {2, 2, 1.5}, 1.5});
    if (dice.Chance(0.1)) o.sensors.push_back({"away", {2, 2, 30}, 0});
    const double end = s->analysis.time.end_time_s > 0 ? s->analysis.time.end_time_s : 1e-4;
    switch (dice.Below(4)) {
      case 0:  // every filter setting at a boundary
        o.sensor_interval_s = 2e-6;
        o.filter_cutoff_hz = dice.Of({100.0, 2.4999e5});
        o.filter_order = dice.Of({1, 10});
        break;
      case 1:  // coarse samples, the default cutoff (10 kHz)
        o.sensor_interval_s = dice.Of({0.4 * end, 0.75 * end});
        break;
      case 2:  // samples finer than the step
        o.sensor_interval_s = 1e-8;
        o.filter_cutoff_hz = 5e4;
        break;
      default:
        break;
    }
  }
  if ((!s->inclusions.empty() || !consistent) && dice.Chance(0.4)) {
    o.structure_displacements = {consistent ? dice.Of<std::string>({"*", s->inclusions[0].name})
                                            : dice.Of<std::string>({"*", "core", "body"})};
  }
  if (dice.Chance(0.3)) {
    o.reaction_sets = dice.Chance(0.5) ? std::vector<std::string>{"bottom"}
                                       : std::vector<std::string>{"x_max", load_set};
  }
  if (dice.Chance(0.15)) {
    o.displacement = o.stress = o.strain = o.von_mises = false;
    o.pk2_stress = o.almansi_strain = o.jacobian = false;
  }
}

// Newton, explicit and linear solver options, and formulation AUTO.
void DrawAnalysisOptions(Dice& dice, bool consistent, SceneSpec* s) {
  const Type type = s->analysis.type;
  const bool explicit_engine = type == Type::kExplicitDynamic || type == Type::kDynamicRelaxation;
  if ((type == Type::kNonlinearStatic || type == Type::kQuasiStatic || !consistent) &&
      dice.Chance(0.4)) {
    DrawNonlinearOptions(dice, s);
    // Time steps are cut to min_step_s (not min_increment): a hard Newton
    // stops there, at a hundredth of the analysis.
    TimeSpec& t = s->analysis.time;
    if (type == Type::kQuasiStatic && s->analysis.nonlinear.min_increment >= 0.5 &&
        t.min_step_s == 0) {
      t.min_step_s = 0.01 * t.end_time_s;
    }
  }
  if ((explicit_engine || !consistent) && dice.Chance(0.7)) {
    DrawExplicitControls(dice, consistent, s);
  }
  if (!explicit_engine) {
    s->analysis.linear_solver =
        dice.Of({AnalysisSpec::LinearSolver::kCholmod, AnalysisSpec::LinearSolver::kCholmod,
                 AnalysisSpec::LinearSolver::kEigenLdlt, AnalysisSpec::LinearSolver::kPcg});
  }
  if ((!explicit_engine || !consistent) && dice.Chance(0.2)) {
    s->formulation = Formulation::kAuto;
    s->formulation_tolerance = dice.Of({0.0, 1e-9, 0.5, 0.999999});
  }
}

SceneSpec SampledScene(Dice& dice) {
  SceneSpec s = BaseScene();
  const bool consistent = dice.Chance(0.85);
  // Dynamic relaxation has half the others' share: when it does not settle
  // it runs 200000 steps, slow on a busy machine.
  const Type type =
      dice.Of({Type::kLinearStatic, Type::kLinearStatic, Type::kNonlinearStatic,
               Type::kNonlinearStatic, Type::kQuasiStatic, Type::kQuasiStatic,
               Type::kExplicitDynamic, Type::kExplicitDynamic, Type::kDynamicRelaxation});
  s.analysis.type = type;
  DrawMesh(dice, consistent, &s);
  DrawTime(dice, consistent, &s);
  DrawMaterial(dice, consistent, &s);
  const std::string load_set = DrawPatches(dice, &s);
  DrawConditions(dice, consistent, load_set, &s);
  DrawGravity(dice, consistent, &s);
  DrawInclusions(dice, consistent, &s);
  DrawContacts(dice, consistent, load_set, &s);
  DrawOutputs(dice, consistent, load_set, &s);
  DrawAnalysisOptions(dice, consistent, &s);
  return s;
}

// A name from a table in the order of an enum's values; "?" for a value
// added since.
template <std::size_t N>
const char* Named(const char* const (&names)[N], int value) {
  return value >= 0 && value < static_cast<int>(N) ? names[value] : "?";
}

const char* AnalysisLabel(Type type) {
  static const char* kNames[] = {"LINEAR_STATIC", "NONLINEAR_STATIC", "QUASI_STATIC",
                                 "EXPLICIT_DYNAMIC", "DYNAMIC_RELAXATION"};
  return Named(kNames, static_cast<int>(type));
}

const char* ElementLabel(ElementType e) {
  static const char* kNames[] = {"DEFAULT", "TET4",      "TET4_ANP", "TET10",
                                 "HEX8",    "HEX8_FULL", "TET10_MD"};
  return Named(kNames, static_cast<int>(e));
}

std::string MaterialLabel(const MaterialSpec& m) {
  static const char* kKinds[] = {"none",          "linear_elastic", "orthotropic", "neo_hookean",
                                 "mooney_rivlin", "polynomial",     "ogden"};
  static const char* kForms[] = {"", "+prony", "+exponential", "+moduli"};
  return std::string(Named(kKinds, static_cast<int>(m.kind))) +
         Named(kForms, static_cast<int>(m.viscoelastic.form));
}

// The bulk modulus of a hyperelastic model [Pa]; 0 for the linear ones.
double BulkModulus(const MaterialSpec& m) {
  switch (m.kind) {
    case MatKind::kNeoHookean:
      return m.neo_hookean.bulk_modulus_pa;
    case MatKind::kMooneyRivlin:
      return m.mooney_rivlin.bulk_modulus_pa;
    case MatKind::kPolynomial:
      return m.polynomial.d_per_pa.empty() ? 0 : 2 / m.polynomial.d_per_pa[0];
    case MatKind::kOgden:
      return m.ogden.bulk_modulus_pa;
    default:
      return 0;
  }
}

std::string Join(const std::vector<std::string>& parts, const char* separator = ",") {
  std::string out;
  for (const std::string& p : parts) out += (out.empty() ? "" : separator) + p;
  return out;
}

std::string Number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

}  // namespace

std::vector<SceneSpec> SampledScenes(uint32_t seed, int count) {
  Dice dice(seed);
  std::vector<SceneSpec> scenes;
  for (int i = 0; i < count; ++i) scenes.push_back(SampledScene(dice));
  return scenes;
}

std::string Describe(const SceneSpec& s) {
  static const char* kBcKinds[] = {"none",     "fixed",    "displacement", "symmetry",
                                   "pressure", "traction", "velocity"};
  static const char* kShapes[] = {"none",  "FLAT_PUNCH",    "SPHERE",
                                  "PLANE", "CYLINDER_FLAT", "CYLINDER_ROUNDED"};
  static const char* kGeometries[] = {"none", "box", "cylinder", "shell", "ellipsoid", "atlas"};
  const AnalysisSpec& a = s.analysis;
  std::string d = std::string(AnalysisLabel(a.type)) + " " + ElementLabel(s.mesh.element) +
                  " h=" + Number(s.mesh.element_size_mm) + " " +
                  Named(kGeometries, static_cast<int>(s.geometry.kind)) + " | " +
                  MaterialLabel(s.material) + " K=" + Number(BulkModulus(s.material)) +
                  " rho=" + Number(s.material.density_kg_per_m3);
  std::vector<std::string> parts;
  for (const BoundaryConditionSpec& bc : s.boundary_conditions) {
    parts.push_back(bc.set + ":" + Named(kBcKinds, static_cast<int>(bc.kind)));
  }
  d += " | bc " + Join(parts);
  parts.clear();
  for (const PatchSpec& p : s.geometry.patches) parts.push_back(p.name);
  if (!parts.empty()) d += " | patches " + Join(parts);
  if (s.gravity.enabled) {
    d += " | gravity fluid=" + Number(s.gravity.fluid_density_kg_per_m3) +
         (s.gravity.fluid_level_mm ? " level=" + Number(*s.gravity.fluid_level_mm) : "");
  }
  for (const InclusionSpec& i : s.inclusions) {
    d += " | inclusion " + i.name + " r=" + Number(i.radius_mm) +
         " growth=" + Number(i.growth_strain) + " " + MaterialLabel(i.material);
  }
  for (const ContactSpec& c : s.contacts) {
    d += std::string(" | contact ") + Named(kShapes, static_cast<int>(c.shape)) + " on " + c.set +
         (c.start_touching ? " start_touching" : "") + " friction=" + Number(c.friction) +
         " penalty=" + Number(c.penalty_factor);
  }
  const OutputSpec& o = s.outputs;
  if (!o.profiles.empty()) d += " | profiles " + std::to_string(o.profiles.size());
  if (!o.sensors.empty() || o.sensor_interval_s != 0 || o.filter_cutoff_hz != 0 ||
      o.filter_order != 0) {
    d += " | sensors " + std::to_string(o.sensors.size()) +
         " interval=" + Number(o.sensor_interval_s) + " cutoff=" + Number(o.filter_cutoff_hz) +
         " order=" + std::to_string(o.filter_order);
  }
  if (!o.structure_displacements.empty()) d += " | structures " + Join(o.structure_displacements);
  if (!o.reaction_sets.empty()) d += " | reactions " + Join(o.reaction_sets);
  const NonlinearOptionsSpec& n = a.nonlinear;
  if (n.increments || n.max_iterations || n.residual_tolerance || n.displacement_tolerance ||
      n.min_increment || !n.line_search) {
    d += " | newton inc=" + std::to_string(n.increments) +
         " it=" + std::to_string(n.max_iterations) + " rtol=" + Number(n.residual_tolerance) +
         " utol=" + Number(n.displacement_tolerance) + " min=" + Number(n.min_increment) +
         (n.line_search ? "" : " no-line-search");
  }
  const TimeSpec& t = a.time;
  if (t.end_time_s != 0 || !t.curve.empty()) {
    d += " | time end=" + Number(t.end_time_s) + " curve=" + std::to_string(t.curve.size()) +
         " steps=" + Number(t.min_step_s) + "/" + Number(t.initial_step_s) + "/" +
         Number(t.max_step_s);
  }
  const ExplicitSpec& e = a.explicit_dynamics;
  parts.clear();
  if (e.time_step_factor) parts.push_back("dt_factor=" + Number(e.time_step_factor));
  if (e.bulk_viscosity_linear) parts.push_back("q1=" + Number(*e.bulk_viscosity_linear));
  if (e.bulk_viscosity_quadratic) parts.push_back("q2=" + Number(*e.bulk_viscosity_quadratic));
  if (e.mass_damping_per_s) parts.push_back("damping=" + Number(e.mass_damping_per_s));
  if (e.hourglass_coefficient) parts.push_back("hourglass=" + Number(e.hourglass_coefficient));
  if (e.output_interval_s) parts.push_back("output=" + Number(e.output_interval_s));
  if (e.mass_scaling_step_s) parts.push_back("mass_scaling=" + Number(e.mass_scaling_step_s));
  if (e.erosion_strain) parts.push_back("erosion=" + Number(e.erosion_strain));
  if (e.relaxation_tolerance) parts.push_back("dr_tol=" + Number(e.relaxation_tolerance));
  if (!parts.empty()) d += " | explicit " + Join(parts, " ");
  if (a.linear_solver != AnalysisSpec::LinearSolver::kCholmod) {
    d += a.linear_solver == AnalysisSpec::LinearSolver::kPcg ? " | PCG" : " | EIGEN_LDLT";
  }
  if (s.formulation == Formulation::kAuto) d += " | AUTO tol=" + Number(s.formulation_tolerance);
  return d;
}

}  // namespace pba::scene_variants
