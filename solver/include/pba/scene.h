// SceneSpec: the solver's own, protobuf-free description of one scene.
// It mirrors proto/pba/v1/scene.proto field by field (same names, same units),
// so a field path reported by ValidateScene() is the path in the YAML file.
// Units at this edge: lengths in mm, moduli and stresses in Pa.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "pba/status.h"

namespace pba {

struct BoxSpec {
  std::array<double, 3> size_mm{0, 0, 0};  // edge lengths along x, y, z [mm]
};

struct CylinderSpec {
  double radius_mm = 0;  // [mm]
  double height_mm = 0;  // [mm], axis along z, bottom centre at the origin
  // Only the half y <= 0 (e.g. a gel half-cylinder whose flat face, the
  // face set `cut` in the plane y = 0, faces up along +y).
  bool half = false;
};

// One octant (x, y, z >= 0) of a thick spherical shell centred at the
// origin, e.g. a pressurised cavity; its cut planes carry symmetry conditions.
struct SphericalShellSpec {
  double inner_radius_mm = 0;  // [mm], > 0
  double outer_radius_mm = 0;  // [mm], > inner
};

// A solid ellipsoid centred at the origin, (x/a)^2 + (y/b)^2 + (z/c)^2 <= 1,
// e.g. a whole brain's envelope; one face set, surface.
struct EllipsoidSpec {
  std::array<double, 3> semi_axes_mm{0, 0, 0};  // a, b, c along x, y, z [mm], > 0
};

// A physics-based atlas meshed for the scene (docs/atlas.md): one
// conforming tetrahedral mesh whose regions are the atlas's structures,
// made with mesh.element_size_mm inside them (default 8 mm). Face sets:
// surface (the outside of every structure kept) and
// "interface:<a>|<b>" between structures.
struct AtlasSpec {
  // "synthetic" (or empty): the built-in synthetic atlas; else a plate
  // directory or a label volume file (.nii, .nii.gz, .nrrd) on the machine
  // that solves.
  std::string source;
  std::string colour_table;             // label table of a label volume; empty: built-in
  std::vector<std::string> structures;  // keep only these (names); empty: all
  bool merge_rest = false;   // the others as one region, "Surrounding tissue" (else dropped)
  double voxel_size_mm = 0;  // of the painted or lofted label volume; 0: 1.5 mm
  double facet_size_mm = 0;  // triangles on surfaces and interfaces; 0: half the element size
  // Region of interest (radius 0: none): elements of at most
  // roi_element_size_mm within roi_radius_mm of roi_centre_mm, coarsening
  // over one radius outside.
  std::array<double, 3> roi_centre_mm{0, 0, 0};
  double roi_radius_mm = 0;
  double roi_element_size_mm = 0;
  // geometry.atlas.labels, the label algebra on a label volume source, as a
  // JSON list of steps (the form atlas/label_algebra.h reads); empty: none.
  std::string label_steps_json;
  // Not read from a scene: the names of the structures the atlas the scene
  // is built from has, set before validation by whoever knows them (the
  // server from a snapshot's structures, pba-solve from the source's table:
  // KnownAtlasStructures). Every structure the scene names (region
  // materials, surfaces, interfaces, outputs, structures kept) is then
  // checked against them; empty: the synthetic atlas's names when the
  // source is the synthetic atlas, else unchecked until the atlas is built.
  std::vector<std::string> known_structures;
};

// A face set cut out of another: the faces of `set` whose nodes all lie
// within `radius_mm` of `centre_mm` (a ball, e.g. the patch a punch presses
// on), or on the side of a plane its normal points to (a half-space, e.g.
// the base of a brain below z = -40 mm), or both. It names a region of a
// curved face for a condition of its own.
struct PatchSpec {
  std::string name;  // new face set; not a name the geometry has
  std::string set;   // one of the geometry's own face sets
  bool ball = false;
  std::array<double, 3> centre_mm{0, 0, 0};  // [mm]
  double radius_mm = 0;                      // [mm], > 0
  bool half_space = false;
  std::array<double, 3> plane_point_mm{0, 0, 0};  // a point of the plane [mm]
  std::array<double, 3> plane_normal{0, 0, 0};    // towards the kept side; any length, non-zero
  // Keep the faces the ball and half-space would drop instead (e.g. a
  // plate's face with a hole: the set less a ball).
  bool invert = false;

  static PatchSpec Ball(std::string name, std::string set, std::array<double, 3> centre_mm,
                        double radius_mm) {
    PatchSpec p;
    p.name = std::move(name);
    p.set = std::move(set);
    p.ball = true;
    p.centre_mm = centre_mm;
    p.radius_mm = radius_mm;
    return p;
  }
  static PatchSpec HalfSpace(std::string name, std::string set,
                             std::array<double, 3> plane_point_mm,
                             std::array<double, 3> plane_normal) {
    PatchSpec p;
    p.name = std::move(name);
    p.set = std::move(set);
    p.half_space = true;
    p.plane_point_mm = plane_point_mm;
    p.plane_normal = plane_normal;
    return p;
  }
};

struct GeometrySpec {
  enum class Kind { kNone, kBox, kCylinder, kSphericalShell, kEllipsoid, kAtlas };
  Kind kind = Kind::kNone;
  BoxSpec box;
  CylinderSpec cylinder;
  SphericalShellSpec spherical_shell;
  EllipsoidSpec ellipsoid;
  AtlasSpec atlas;
  std::vector<PatchSpec> patches;  // made in order, after the mesh
};

enum class ElementType {
  kDefault,   // TET4 for linear analyses, TET4_ANP for nonlinear ones
  kTet4,      // 4-node tetrahedron, one F per element (locks when nearly incompressible)
  kTet4Anp,   // 4-node tetrahedron with average nodal pressure (nonlinear analyses)
  kTet10,     // 10-node quadratic tetrahedron; mid-edge nodes on curved faces lie on the surface
  kHex8,      // 8-node hexahedron with a mean-dilatation (B-bar) volumetric treatment
  kHex8Full,  // 8-node hexahedron, full 2x2x2 integration (locks when nearly incompressible)
  // 10-node tetrahedron with mean dilatation (constant element pressure,
  // P2/P0): does not lock when nearly incompressible, unlike TET10 at
  // K / mu = 1e6 (nonlinear analyses)
  kTet10Md,
};

// True for the 10-node elements (the primitive's tetrahedra get a node on
// every edge, see MakeQuadratic).
inline bool IsQuadratic(ElementType e) {
  return e == ElementType::kTet10 || e == ElementType::kTet10Md;
}

// True for the brick elements (the primitive is meshed into hexahedra).
inline bool IsHexahedral(ElementType e) {
  return e == ElementType::kHex8 || e == ElementType::kHex8Full;
}

// The scene's name of an element type, as in mesh.element: "TET4",
// "TET4_ANP", "TET10", "TET10_MD", "HEX8", "HEX8_FULL" ("DEFAULT" for
// kDefault).
const char* ElementName(ElementType element);

// Adaptive refinement (mesh.adapt): the scene is solved, the error of
// every element estimated (Zienkiewicz-Zhu, the estimate the summary
// reports), the elements carrying `refine_fraction` of the squared error
// bisected three times, which halves their edges (longest-edge bisection,
// mesh/refine.h), and the scene solved again on the refined mesh, until
// the estimated relative error is at most target_error_percent, another
// refinement would pass max_elements, or max_cycles solves have run. Each
// cycle is in the summary; the result files are the last cycle's.
struct AdaptSpec {
  double target_error_percent = 0;  // 0: no adaptation; else in (0, 100)
  int64_t max_elements = 0;         // 0: kDefaultAdaptMaxElements
  int max_cycles = 0;               // solves, counting the first; 0: kDefaultAdaptCycles
  double refine_fraction = 0;       // (0, 1]; 0: kDefaultAdaptFraction
  bool enabled() const { return target_error_percent != 0; }
};
inline constexpr int64_t kDefaultAdaptMaxElements = 500'000;
inline constexpr int kDefaultAdaptCycles = 6;
inline constexpr double kDefaultAdaptFraction = 0.5;

struct MeshSpec {
  ElementType element = ElementType::kDefault;
  // Target edge length of the structured grid [mm]; 0 picks a twentieth of the
  // body's largest dimension.
  double element_size_mm = 0;
  AdaptSpec adapt;
};

// Isotropic small-strain elasticity (DOMAIN.md eq. 2.21).
struct LinearElasticParams {
  double youngs_modulus_pa = 0;  // E [Pa], > 0
  double poissons_ratio = 0;     // nu [-], -1 < nu < 0.5
  // Names the bad field as `path` + ".youngs_modulus_pa" or ".poissons_ratio".
  Status Validate(const std::string& path) const;
};

// Orthotropic small-strain elasticity from engineering constants in the
// material frame (1, 2, 3); LINEAR_STATIC only. nu_ij is the contraction
// along j under uniaxial stress along i, -eps_j / eps_i; the other ratios
// follow from the symmetry nu_ji / E_j = nu_ij / E_i (Jones, Mechanics of
// Composite Materials, 2nd ed. 1999, sec. 2.3). E = E_i, nu = nu_ij and
// G = E / (2 (1 + nu)) is isotropic elasticity.
struct OrthotropicElasticParams {
  double e1_pa = 0;   // E1 [Pa], > 0
  double e2_pa = 0;   // E2 [Pa], > 0
  double e3_pa = 0;   // E3 [Pa], > 0
  double nu12 = 0;    // [-], |nu12| < sqrt(E1 / E2)
  double nu13 = 0;    // [-], |nu13| < sqrt(E1 / E3)
  double nu23 = 0;    // [-], |nu23| < sqrt(E2 / E3)
  double g12_pa = 0;  // G12 [Pa], > 0
  double g13_pa = 0;  // G13 [Pa], > 0
  double g23_pa = 0;  // G23 [Pa], > 0
  // Material directions 1 and 2 as vectors in the global x, y, z frame (any
  // length). Direction 1 is axis_1 normalised; direction 2 is the part of
  // axis_2 orthogonal to it (Gram-Schmidt), normalised, so axis_2 need only
  // lie in the 1-2 plane on the side of +2; direction 3 = 1 x 2.
  std::array<double, 3> axis_1{1, 0, 0};
  std::array<double, 3> axis_2{0, 1, 0};
  // Names the bad field as `path` + ".e1_pa", ".nu23", ".axis_2" and so on;
  // a compliance that is not positive definite (a condition on all three
  // Poisson's ratios together) names `path` itself.
  Status Validate(const std::string& path) const;
};

// Hyperelastic models, all with the uncoupled volumetric/deviatoric split
// W = W_iso(I1b, I2b or the isochoric stretches) + U(J) (DOMAIN.md eq. 2.32).
// The bulk modulus K = 2 / D1 sets U = (K / 2)(J - 1)^2.

// W = (mu / 2)(I1b - 3) + (K / 2)(J - 1)^2.
struct NeoHookeanParams {
  double shear_modulus_pa = 0;  // mu [Pa], > 0
  double bulk_modulus_pa = 0;   // K [Pa], > 0; brain tissue: 1e5..1e6 mu
};

// W = C10 (I1b - 3) + C01 (I2b - 3) + (K / 2)(J - 1)^2; mu0 = 2 (C10 + C01).
struct MooneyRivlinParams {
  double c10_pa = 0;           // [Pa]
  double c01_pa = 0;           // [Pa]; C10 + C01 > 0
  double bulk_modulus_pa = 0;  // K [Pa], > 0
};

// W = sum C_ij (I1b - 3)^i (I2b - 3)^j + sum_k (1 / D_k)(J - 1)^(2k), order
// N = max(i + j) <= 3, k = 1..N.
struct PolynomialTermSpec {
  int i = 0;        // power of (I1b - 3)
  int j = 0;        // power of (I2b - 3); 1 <= i + j <= 3
  double c_pa = 0;  // C_ij [Pa]
};
struct PolynomialParams {
  std::vector<PolynomialTermSpec> terms;
  std::vector<double> d_per_pa;  // D_1..D_N [1/Pa]; D_1 > 0, K = 2 / D_1
};

// W = sum_p (2 mu_p / alpha_p^2)(lb1^alpha_p + lb2^alpha_p + lb3^alpha_p - 3)
//     + (K / 2)(J - 1)^2, lb the isochoric principal stretches (Abaqus form).
struct OgdenTermSpec {
  double mu_pa = 0;  // [Pa]; sum of mu_p > 0
  double alpha = 0;  // [-], nonzero; brain: mu = 842 Pa, alpha = -4.7
};
struct OgdenParams {
  std::vector<OgdenTermSpec> terms;  // 1..3
  double bulk_modulus_pa = 0;        // K [Pa], > 0
};

// Quasi-linear viscoelasticity (DOMAIN.md eq. 2.31): the isochoric stress
// of the hyperelastic model relaxes as mu(t) = mu0 [1 - sum_k g_k (1 -
// exp(-t/tau_k))]; the volumetric response stays elastic. Three ways to give
// the relaxation, all mapped onto one normalised Prony series:
//   kProny:       g_k [-] and tau_k [s] directly;
//   kExponential: G(t) = G_inf + (G0 - G_inf) exp(-beta t), as
//                 long_term_ratio = G_inf / G0 and beta_per_s;
//   kModuli:      G(t) = G_inf + sum_i G_i exp(-t/tau_i) with moduli in Pa
//                 (the rat-brain tables); only the ratios G_i / G0 enter, G0
//                 = G_inf + sum G_i, the scale staying the hyperelastic one.
// Only analyses with time (QUASI_STATIC) use it; the others take the
// instantaneous (static analyses: elastic) response and say so.
struct ViscoelasticSpec {
  enum class Form { kNone, kProny, kExponential, kModuli };
  Form form = Form::kNone;
  std::vector<double> g;            // kProny: g_k [-], each >= 0, sum < 1
  std::vector<double> tau_s;        // kProny, kModuli: relaxation times [s], > 0
  double long_term_ratio = 0;       // kExponential: G_inf / G0, in (0, 1]
  double beta_per_s = 0;            // kExponential: decay rate [1/s], > 0
  double long_term_modulus_pa = 0;  // kModuli: G_inf [Pa], > 0
  std::vector<double> moduli_pa;    // kModuli: G_i [Pa], >= 0, one per tau_s

  bool enabled() const { return form != Form::kNone; }
};

struct MaterialSpec {
  enum class Kind {
    kNone,
    kLinearElastic,
    kOrthotropicElastic,
    kNeoHookean,
    kMooneyRivlin,
    kPolynomial,
    kOgden
  };
  std::string name;
  Kind kind = Kind::kNone;
  // Mass density [kg/m^3], >= 0; needed by gravity (brain tissue about 1040).
  double density_kg_per_m3 = 0;
  LinearElasticParams linear_elastic;
  OrthotropicElasticParams orthotropic_elastic;
  NeoHookeanParams neo_hookean;
  MooneyRivlinParams mooney_rivlin;
  PolynomialParams polynomial;
  OgdenParams ogden;
  // Relaxation of a hyperelastic model's isochoric stress; not for the
  // linear models.
  ViscoelasticSpec viscoelastic;

  bool hyperelastic() const {
    return kind != Kind::kNone && kind != Kind::kLinearElastic && kind != Kind::kOrthotropicElastic;
  }
};

// A material of its own for some structures of an atlas (their regions);
// the others keep the scene's `material`. Every region material must be the
// same family as the scene's (all hyperelastic for a nonlinear analysis).
struct RegionMaterialSpec {
  std::vector<std::string> structures;  // structure (region) names, each kept by the scene
  MaterialSpec material;
};

// A ball of tissue made a region of its own (e.g. a tumour): the elements
// whose centroid lies within radius_mm of centre_mm, cut out of whichever
// regions held them. It takes its own material, and may grow: an isotropic
// growth strain, F = F_e (1 + growth_strain a(t)) I with a(t) the analysis's
// time curve (the multiplicative split of growth, Rodriguez, Hoger and
// McCulloch, J. Biomech. 27:455, 1994), so that a free inclusion's volume
// becomes (1 + growth_strain)^3 times its own.
struct InclusionSpec {
  std::string name;                          // region name, e.g. "tumour"; new
  std::array<double, 3> centre_mm{0, 0, 0};  // [mm]
  double radius_mm = 0;                      // [mm], > 0
  MaterialSpec material;                     // same family as the scene's material
  double growth_strain = 0;                  // linear growth strain at a(t) = 1 [-], > -1
};

// A rigid body pressed against a face set of the tissue (node-to-surface,
// frictionless or with Coulomb friction), moved by motion_mm times the
// analysis's time curve a(t) (a static analysis: its load factor).
//   kFlatPunch: a flat-ended cylinder of radius_mm whose end face is centred
//               at position_mm with outward normal -axis; axis points from
//               the face into the tissue (the direction it presses).
//   kSphere:    a ball of radius_mm centred at position_mm.
//   kPlane:     the half-space behind the plane through position_mm with
//               normal axis pointing into the tissue (e.g. a skull base).
//   kCylinderFlat, kCylinderRounded: a rigid cylinder of radius_mm (a bolt, a
//               probe) whose tip is at position_mm, pointing along axis into
//               the tissue and reaching back without end; the tip is flat or
//               a hemisphere of the same radius (its pole at position_mm). A
//               node inside is pushed out through the nearest of its
//               surfaces: the tip or the side wall, so the bolt may
//               penetrate (EXPLICIT_DYNAMIC only).
// In an EXPLICIT_DYNAMIC analysis every contact is an impactor: its
// motion_mm times a(t) is its displacement (a(t) with a constant slope is
// a constant speed), friction is not modelled, and the penalty is chosen
// from each node's mass and the time step (explicit/impactor.h), reported
// in the summary; penalty_factor scales it (0: 1) and the tolerance is
// not used.
// The contact is enforced by a penalty, augmented (Uzawa) until the deepest
// penetration is below penetration_tolerance_mm; the penalty stiffness is
// penalty_factor times the tissue's initial shear modulus over the finest
// element size (an atlas's region-of-interest size when it has one), per
// unit area, and the default tolerance 1 % of that size.
struct ContactSpec {
  enum class Shape { kNone, kFlatPunch, kSphere, kPlane, kCylinderFlat, kCylinderRounded };
  std::string name;  // names its force and area in the summary and history
  std::string set;   // face set of the tissue that may touch it
  Shape shape = Shape::kNone;
  std::array<double, 3> position_mm{0, 0, 0};
  std::array<double, 3> axis{0, 0, -1};  // any length, non-zero
  double radius_mm = 0;                  // all but kPlane: > 0
  std::array<double, 3> motion_mm{0, 0, 0};
  double friction = 0;                  // Coulomb coefficient, 0..0.5
  double penalty_factor = 0;            // 0: 100
  double penetration_tolerance_mm = 0;  // 0: 1 % of the finest element size
  // Moved along `axis` before the analysis until it just touches the set's
  // nearest node (position_mm need only lie off the surface, on the side
  // the axis points from).
  bool start_touching = false;
};

struct BoundaryConditionSpec {
  // kSymmetry: the displacement normal to a planar face set is zero, the
  // others are free (a mirror plane of the model).
  // kPressure: a pressure on the face set, pushing into the body when
  // positive; in a NONLINEAR_STATIC analysis it follows the deformed surface
  // (acts on the current area along the current normal).
  // kTraction: a force per reference area of fixed direction (a dead load).
  // Loads are ramped with the load factor like prescribed displacements.
  // kVelocity (EXPLICIT_DYNAMIC only): the given components of the nodes'
  // velocity are velocity_m_per_s times a(t) (e.g. a piston), the others
  // free.
  enum class Kind { kNone, kFixed, kDisplacement, kSymmetry, kPressure, kTraction, kVelocity };
  std::string set;  // named face set of the geometry
  Kind kind = Kind::kNone;
  // kDisplacement: prescribed x, y, z components [mm]; nullopt = free.
  std::array<std::optional<double>, 3> displacement_mm;
  // kVelocity: prescribed x, y, z components [m/s] at a(t) = 1; nullopt = free.
  std::array<std::optional<double>, 3> velocity_m_per_s{};
  double pressure_pa = 0;                      // kPressure [Pa]
  std::array<double, 3> traction_pa{0, 0, 0};  // kTraction, x y z [Pa]

  // True for the conditions that load a set rather than hold it.
  bool is_load() const { return kind == Kind::kPressure || kind == Kind::kTraction; }
};

// A uniform body force: the acceleration of gravity acting on the
// material's density (material.density_kg_per_m3).
struct GravitySpec {
  bool enabled = false;
  std::array<double, 3> acceleration_m_per_s2{0, 0, 0};  // e.g. (0, 0, -9.81)
  // Buoyancy in a surrounding fluid (cerebrospinal fluid: about 1007
  // kg/m^3): tissue below the fluid level weighs (rho - rho_fluid) g, tissue
  // above it rho g; 0: no fluid. The level is a height along -g (up) [mm];
  // unset: the fluid covers everything.
  double fluid_density_kg_per_m3 = 0;
  std::optional<double> fluid_level_mm;
};

// Load stepping and Newton-Raphson controls of a nonlinear static analysis;
// 0 (or unset) picks the default given.
// Controls of the linear solve (analysis.linear_solver_options); 0 picks the
// default (LinearSolverSettings in linear/linear_solver.h declares them).
struct LinearSolverSpec {
  // kPressureSchur: TET10_MD's (and HEX8's) element pressures as unknowns,
  // FGMRES with a Schur field split; other elements get GAMG.
  enum class Preconditioner { kGamg, kBoomerAmg, kPressureSchur };
  Preconditioner preconditioner = Preconditioner::kGamg;  // AMG
  double relative_tolerance = 0;                          // AMG, [1e-14, 1e-2]
  int max_iterations = 0;                                 // AMG, 1..100000
  std::optional<double> gamg_threshold;                   // GAMG, [0, 0.5]
  double boomeramg_strong_threshold = 0;                  // BoomerAMG, (0, 1)
  int auto_direct_max_factor_mb = 0;                      // AUTO [MB], >= 0
  std::optional<int> fallback_direct_max_unknowns;        // AMG, >= 0 (0: never)
};

struct NonlinearOptionsSpec {
  int increments = 0;                 // initial number of load increments, default 5, <= 10000
  int max_iterations = 0;             // Newton iterations per increment, default 20, <= 1000
  double residual_tolerance = 0;      // relative force residual, default 1e-8, < 1
  double displacement_tolerance = 0;  // relative displacement correction, default 1e-8, < 1
  double min_increment = 0;  // smallest load-factor increment before giving up, default 1e-4
  bool line_search = true;
};

// Time of a QUASI_STATIC analysis. Every prescribed displacement, load,
// gravity, rigid-body motion and growth strain is its full value times the
// amplitude a(t) of `curve`, piecewise linear through (time_s, amplitude)
// points with increasing times, held at its last value after them; no curve:
// a(t) = t / end_time_s, a ramp. Steps adapt: they shrink when Newton
// struggles and grow after quick convergence, are at most half the shortest
// relaxation time that is active while the amplitude changes, and never
// step over a corner of the curve.
struct TimeSpec {
  double end_time_s = 0;                         // [s], > 0
  double initial_step_s = 0;                     // [s]; 0: end_time_s / 20
  double min_step_s = 0;                         // [s]; 0: end_time_s * 1e-6
  double max_step_s = 0;                         // [s]; 0: end_time_s / 5
  std::vector<std::pair<double, double>> curve;  // (time [s], amplitude [-])
};

// Controls of the explicit engine (EXPLICIT_DYNAMIC, DYNAMIC_RELAXATION);
// 0 (or unset) picks the default given.
struct ExplicitSpec {
  // Fraction of the stable time step (each element's characteristic length
  // over its dilatational wave speed, the smallest over the mesh) taken as
  // the step; 0: 0.7. Above 1 the integration is unstable: allowed, so that
  // the run's blow-up detection can be seen to catch it; at most 2.
  double time_step_factor = 0;
  // Bulk viscosity (von Neumann-Richtmyer with a linear term, as in LS-DYNA):
  // q = rho l (q_quadratic l tr(D)^2 - q_linear c tr(D)) while the element
  // compresses (tr(D) < 0), added to its pressure. Unset: 0.06 and 1.5;
  // 0 turns a term off. EXPLICIT_DYNAMIC only (dynamic relaxation damps on
  // its own).
  std::optional<double> bulk_viscosity_linear;
  std::optional<double> bulk_viscosity_quadratic;
  // Mass-proportional damping C = alpha M [1/s], >= 0 (EXPLICIT_DYNAMIC;
  // dynamic relaxation chooses its own).
  double mass_damping_per_s = 0;
  // HEX8: stiffness of the hourglass control, a fraction of the element's
  // dilatational stiffness; 0: 0.05, at most 0.5.
  double hourglass_coefficient = 0;
  // Energy balance, history.csv rows and result frames every this many
  // seconds; 0: end_time_s / 100.
  double output_interval_s = 0;
  // Selective mass scaling: an element whose stable step is below this
  // [s] takes the density that makes its step this one (a sliver of an
  // atlas mesh would otherwise set the step of the whole run); the mass
  // added is reported. 0: none, else > 0. EXPLICIT_DYNAMIC only.
  double mass_scaling_step_s = 0;
  // Element erosion: an element whose largest principal Green-Lagrange
  // strain exceeds this is removed (its mass and the kinetic and internal
  // energy it held are accounted for); 0: none, else > 0.
  double erosion_strain = 0;
  // DYNAMIC_RELAXATION: converged when the largest out-of-balance force is
  // below this fraction of the largest reaction or load, and the estimated
  // distance to the answer (from the rate at which the steps shrink) below
  // it times the largest displacement; 0: 1e-4.
  double relaxation_tolerance = 0;
};

struct AnalysisSpec {
  enum class Type {
    kLinearStatic,     // small strain, K u = f; hyperelastic models use their initial moduli
    kNonlinearStatic,  // finite strain, total Lagrangian, Newton-Raphson; needs a hyperelastic
                       // model
    // finite strain through time: loads follow `time`, viscoelastic
    // materials relax, rigid bodies move; a history of every step
    kQuasiStatic,
    // Explicit central-difference dynamics on the total-Lagrangian
    // formulation (lumped mass; TET4_ANP, TET4 or HEX8 with one-point
    // integration and hourglass control) to time.end_time_s: impacts and
    // pressure waves. Loads, prescribed motions and impactors follow
    // time.curve; viscoelastic materials relax; sensors sample the fields.
    kExplicitDynamic,
    // The explicit engine, damped, run until the body comes to rest under
    // its loads at full value: the static answer of NONLINEAR_STATIC with
    // no tangent and no linear solve (explicit/dynamic_relaxation.h).
    kDynamicRelaxation,
  };
  enum class LinearSolver {
    kAuto,       // CHOLMOD while its factor fits linear_solver_options.auto_direct_max_factor_mb
    kCholmod,    // supernodal sparse Cholesky (SuiteSparse)
    kEigenLdlt,  // Eigen's simplicial LDL^T, the fallback
    // Conjugate gradients with an incomplete Cholesky preconditioner, to a
    // relative residual of 1e-12: memory near the matrix's own, for systems
    // too big to factorise; slow to converge when nearly incompressible.
    kPcg,
    kAmg,    // PETSc conjugate gradients with algebraic multigrid
    kMumps,  // MUMPS sparse direct (PETSc)
  };
  Type type = Type::kLinearStatic;
  LinearSolver linear_solver = LinearSolver::kAuto;
  LinearSolverSpec linear_solver_options;  // tolerances and parameters (0: default)
  NonlinearOptionsSpec nonlinear;          // Newton controls (increments: see time)
  TimeSpec time;                           // kQuasiStatic, kExplicitDynamic (end and curve only)
  ExplicitSpec explicit_dynamics;          // kExplicitDynamic, kDynamicRelaxation
  // Set by formulation AUTO, not read from a scene file: relaxation terms
  // with tau below the first are taken as relaxed (folded into the
  // long-term modulus), those above the second as never relaxing (dropped).
  double relaxed_below_s = 0;
  double frozen_above_s = 0;  // 0: none
};

// A straight line along which fields are sampled at the end of the
// analysis and written as profile_<name>.csv (docs/results.md): e.g. a
// radial line from a tumour's centre gives the displacement of the
// neighbouring tissue and the radial stress and strain. Points are located
// in the reference (undeformed) configuration.
struct ProfileSpec {
  std::string name;                        // names the file: letters, digits, '_' and '-'; unique
  std::array<double, 3> from_mm{0, 0, 0};  // first point [mm]
  std::array<double, 3> to_mm{0, 0, 0};    // last point [mm], not from_mm
  int points = 0;  // equally spaced points, ends included; 0: 50, else 2..1000
};

// A point (or a small ball) inside the body at which an EXPLICIT_DYNAMIC
// analysis samples its fields through time (sensors.csv, docs/results.md):
// the pressure -tr(sigma)/3 [Pa], the velocity [m/s] and the largest
// principal Green-Lagrange strain in magnitude, raw and low-pass filtered.
struct SensorSpec {
  std::string name;                            // letters, digits, '_' and '-'; unique
  std::array<double, 3> position_mm{0, 0, 0};  // reference configuration [mm]
  // 0: the element holding the point (velocity: its nodes' mean); else the
  // volume-weighted mean of the elements whose centroid lies within it.
  double radius_mm = 0;
};

struct OutputSpec {
  bool displacement = true;
  bool stress = true;
  bool von_mises = true;
  bool strain = true;  // small strain (linear) or Green-Lagrange strain (nonlinear)
  // Finite-strain fields, written by nonlinear analyses only.
  bool pk2_stress = true;      // second Piola-Kirchhoff stress
  bool almansi_strain = true;  // Euler-Almansi strain
  bool jacobian = true;        // J = det F
  // Sets whose total reaction goes into the summary; empty = every set that
  // carries a boundary condition.
  std::vector<std::string> reaction_sets;
  // Structures (regions) whose mean and largest displacement are reported at
  // the end and, in a QUASI_STATIC analysis, at every step of history.csv;
  // "*" means all of them.
  std::vector<std::string> structure_displacements;
  // Lines along which the final fields are sampled (profile_<name>.csv).
  std::vector<ProfileSpec> profiles;
  // EXPLICIT_DYNAMIC: sensors sampled every sensor_interval_s (0: 1e-6 s,
  // or the time step if longer) and filtered by a zero-phase Butterworth
  // low-pass (signal/butterworth.h) of filter_order (0: 4, 1..10) and
  // filter_cutoff_hz (0: 10 kHz; below half the sampling rate).
  std::vector<SensorSpec> sensors;
  double sensor_interval_s = 0;
  double filter_cutoff_hz = 0;
  int filter_order = 0;
};

// How much of the physics the scene asks for is modelled.
//   kAsWritten: all of it.
//   kAuto: only what the scene needs (docs/scenes.md): relaxation terms far
//     faster than the loading fold into the long-term modulus and those far
//     slower than the analysis drop out; finite strain only when a first
//     cheap linear solve strains beyond 2 %; of an atlas, only the
//     structures the scene names, the rest merged into one region. Each
//     decision is reported with the quantity that drove it, and a coarse run
//     of the full model estimates what the reduction costs in accuracy.
enum class Formulation { kAsWritten, kAuto };

struct SceneSpec {
  std::string name;
  std::string description;
  GeometrySpec geometry;
  MeshSpec mesh;
  MaterialSpec material;
  // A built-in table of per-structure tissue (material/tissue_library.h,
  // docs/materials.md): each atlas structure it names takes its material;
  // `region_materials` then override it, and the rest keep `material`.
  // Empty: none.
  std::string material_library;
  std::vector<RegionMaterialSpec> region_materials;
  std::vector<InclusionSpec> inclusions;
  std::vector<BoundaryConditionSpec> boundary_conditions;
  std::vector<ContactSpec> contacts;
  GravitySpec gravity;
  AnalysisSpec analysis;
  OutputSpec outputs;
  Formulation formulation = Formulation::kAsWritten;
  // kAuto: a reduced model is kept only when, on meshes twice as coarse,
  // its results differ from the full model's by at most this fraction;
  // otherwise the scene is solved as written. 0: 0.01 (1 %), else in (0, 1).
  double formulation_tolerance = 0;
};

// Face set names a geometry defines (box: bottom top x_min x_max y_min y_max;
// cylinder: bottom top side, and cut for a half cylinder; spherical shell: inner outer x0 y0 z0,
// the last three the cut planes x = 0, y = 0, z = 0; ellipsoid, atlas: surface), then its patches'
// names.
std::vector<std::string> FaceSetNames(const GeometrySpec& geometry);

// The axis (0 = x, 1 = y, 2 = z) normal to a planar face set (or a patch of
// one), or -1 when the set is curved (the cylinder's side) or unknown.
int PlaneNormalAxis(const GeometrySpec& geometry, const std::string& set);

// The structure names of a scene atlas's source where they can be read
// before meshing: a structure set's manifest (less what its derived merges
// take, with the derived structures), a plate directory's colour table, a
// label volume's table (in any format label_table.h reads); then as the
// scene's label steps leave them (NamesAfterStep: keep, drop, merge and
// rename take names away, fill, cut and overlay add them). None for the
// synthetic atlas (its names are built in), a label volume without a
// table, or a source that cannot be read (the build then says what is
// wrong): for AtlasSpec::known_structures.
std::vector<std::string> KnownAtlasStructures(const AtlasSpec& atlas);

// Checks everything that can be checked without meshing: a geometry and a
// material are given, sizes and moduli are in range, every boundary condition
// names an existing set, the body cannot move as a rigid body (some set is
// fixed or prescribed in every direction), the mesh would not be absurdly
// large. The returned Status names the field path, e.g.
// "boundary_conditions[1].set".
// Also, as a rank of an MPI job, ValidateSceneOnRanks with its number of ranks.
Status ValidateScene(const SceneSpec& scene);

// Whether `scene` can run on `ranks` MPI processes (mpirun -np ranks
// pba-solve): the ranks share its linear solves, so it must have some
// (LINEAR_STATIC, NONLINEAR_STATIC, QUASI_STATIC) and solve them with a
// backend that works across processes (AUTO, AMG, MUMPS). Any scene runs on
// one. The returned Status names the field that stands in the way.
Status ValidateSceneOnRanks(const SceneSpec& scene, int ranks);

}  // namespace pba
