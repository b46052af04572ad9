// Scene YAML -> pba.v1.Scene -> SceneSpec for every material model and the
// nonlinear analysis, the field paths of bad values, and the summary of a
// nonlinear solve on its way back (proto and text).
#include "convert/convert.h"

#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "codec/summary_text.h"
#include "codec/yaml_codec.h"

namespace pba {
namespace {

constexpr const char* kBase = R"(
name: block
geometry: {box: {size_mm: [10, 10, 10]}}
boundary_conditions:
  - {set: bottom, fixed: {}}
  - {set: top, displacement: {z_mm: -2}}
)";

SceneSpec Parse(const std::string& extra) {
  v1::Scene scene;
  codec::ParseError error;
  EXPECT_TRUE(codec::ParseYaml(std::string(kBase) + extra, &scene, &error)) << error.ToString();
  SceneSpec spec;
  const Status status = SceneFromProto(scene, &spec);
  EXPECT_TRUE(status.ok()) << status.ToString();
  return spec;
}

Status Validate(const std::string& extra) {
  v1::Scene scene;
  codec::ParseError error;
  EXPECT_TRUE(codec::ParseYaml(std::string(kBase) + extra, &scene, &error)) << error.ToString();
  return ValidateSceneProto(scene);
}

TEST(SceneFromProto, EveryHyperelasticModel) {
  SceneSpec s = Parse("material: {neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1e6}}");
  EXPECT_EQ(s.material.kind, MaterialSpec::Kind::kNeoHookean);
  EXPECT_EQ(s.material.neo_hookean.shear_modulus_pa, 1000);
  EXPECT_EQ(s.material.neo_hookean.bulk_modulus_pa, 1e6);

  s = Parse("material: {mooney_rivlin: {c10_pa: 300, c01_pa: 200, bulk_modulus_pa: 5e5}}");
  EXPECT_EQ(s.material.kind, MaterialSpec::Kind::kMooneyRivlin);
  EXPECT_EQ(s.material.mooney_rivlin.c01_pa, 200);

  s = Parse(R"(material:
  polynomial:
    terms: [{i: 1, j: 0, c_pa: 300}, {i: 0, j: 1, c_pa: 200}, {i: 2, j: 0, c_pa: 10}]
    d_per_pa: [4e-6, 1e-7]
)");
  EXPECT_EQ(s.material.kind, MaterialSpec::Kind::kPolynomial);
  ASSERT_EQ(s.material.polynomial.terms.size(), 3u);
  EXPECT_EQ(s.material.polynomial.terms[2].i, 2);
  EXPECT_EQ(s.material.polynomial.terms[2].c_pa, 10);
  EXPECT_EQ(s.material.polynomial.d_per_pa, (std::vector<double>{4e-6, 1e-7}));

  s = Parse(
      "material: {name: brain, ogden: {terms: [{mu_pa: 842, alpha: -4.7}], "
      "bulk_modulus_pa: 8.42e7}}");
  EXPECT_EQ(s.material.kind, MaterialSpec::Kind::kOgden);
  EXPECT_EQ(s.material.name, "brain");
  ASSERT_EQ(s.material.ogden.terms.size(), 1u);
  EXPECT_EQ(s.material.ogden.terms[0].alpha, -4.7);
  EXPECT_EQ(s.material.ogden.bulk_modulus_pa, 8.42e7);
}

TEST(SceneFromProto, LoadsShellAndElements) {
  SceneSpec s = Parse(
      R"(material: {density_kg_per_m3: 1040, neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1e6}}
gravity: {acceleration_m_per_s2: [0, 0, -9.81]}
mesh: {element: TET10}
analysis: {type: NONLINEAR_STATIC}
)");
  EXPECT_EQ(s.material.density_kg_per_m3, 1040);
  EXPECT_TRUE(s.gravity.enabled);
  EXPECT_EQ(s.gravity.acceleration_m_per_s2[2], -9.81);
  EXPECT_EQ(s.mesh.element, ElementType::kTet10);
  EXPECT_FALSE(Parse("mesh: {element: TET4}").gravity.enabled);
  EXPECT_EQ(Parse("mesh: {element: HEX8}").mesh.element, ElementType::kHex8);
  EXPECT_EQ(Parse("mesh: {element: HEX8_FULL}").mesh.element, ElementType::kHex8Full);
  EXPECT_EQ(Parse("mesh: {element: TET10_MD}").mesh.element, ElementType::kTet10Md);
  const AdaptSpec adapt =
      Parse(
          "mesh: {element: TET4, adapt: {target_error_percent: 5, max_elements: 20000, "
          "max_cycles: 4, refine_fraction: 0.3}}")
          .mesh.adapt;
  EXPECT_TRUE(adapt.enabled());
  EXPECT_EQ(adapt.target_error_percent, 5);
  EXPECT_EQ(adapt.max_elements, 20000);
  EXPECT_EQ(adapt.max_cycles, 4);
  EXPECT_EQ(adapt.refine_fraction, 0.3);
  EXPECT_FALSE(Parse("mesh: {element: TET4}").mesh.adapt.enabled());

  // Conditions beyond the base's two.
  v1::Scene scene;
  codec::ParseError error;
  ASSERT_TRUE(codec::ParseYaml(R"(
name: cavity
geometry: {spherical_shell: {inner_radius_mm: 10, outer_radius_mm: 20}}
boundary_conditions:
  - {set: x0, symmetry: {}}
  - {set: inner, pressure: {pressure_pa: 550}}
  - {set: outer, traction: {traction_pa: [1, 2, 3]}}
)",
                               &scene, &error))
      << error.ToString();
  ASSERT_TRUE(SceneFromProto(scene, &s).ok());
  EXPECT_EQ(s.geometry.kind, GeometrySpec::Kind::kSphericalShell);
  EXPECT_EQ(s.geometry.spherical_shell.outer_radius_mm, 20);
  ASSERT_EQ(s.boundary_conditions.size(), 3u);
  EXPECT_EQ(s.boundary_conditions[1].kind, BoundaryConditionSpec::Kind::kPressure);
  EXPECT_EQ(s.boundary_conditions[1].pressure_pa, 550);
  EXPECT_TRUE(s.boundary_conditions[1].is_load());
  EXPECT_EQ(s.boundary_conditions[2].kind, BoundaryConditionSpec::Kind::kTraction);
  EXPECT_EQ(s.boundary_conditions[2].traction_pa[2], 3);
}

TEST(SceneFromProto, EllipsoidAndPatches) {
  v1::Scene scene;
  codec::ParseError error;
  ASSERT_TRUE(codec::ParseYaml(R"(
name: brain
geometry:
  ellipsoid: {semi_axes_mm: [67, 93, 59]}
  patches:
    - {name: punch, set: surface, centre_mm: [0, 0, 59], radius_mm: 15}
    - {name: base, set: surface, centre_mm: [0, 0, -59], radius_mm: 40}
boundary_conditions:
  - {set: base, fixed: {}}
  - {set: punch, displacement: {z_mm: -4}}
)",
                               &scene, &error))
      << error.ToString();
  SceneSpec s;
  ASSERT_TRUE(SceneFromProto(scene, &s).ok());
  EXPECT_EQ(s.geometry.kind, GeometrySpec::Kind::kEllipsoid);
  EXPECT_EQ(s.geometry.ellipsoid.semi_axes_mm[1], 93);
  ASSERT_EQ(s.geometry.patches.size(), 2u);
  EXPECT_EQ(s.geometry.patches[0].name, "punch");
  EXPECT_EQ(s.geometry.patches[0].set, "surface");
  EXPECT_EQ(s.geometry.patches[0].centre_mm[2], 59);
  EXPECT_EQ(s.geometry.patches[1].radius_mm, 40);

  ASSERT_TRUE(codec::ParseYaml("geometry: {ellipsoid: {semi_axes_mm: [1, 2]}}", &scene, &error))
      << error.ToString();
  Status status = SceneFromProto(scene, &s);
  EXPECT_EQ(status.field(), "geometry.ellipsoid.semi_axes_mm") << status.ToString();
  ASSERT_TRUE(codec::ParseYaml(
      "geometry: {box: {size_mm: [1, 2, 3]}, patches: [{name: p, set: top, centre_mm: [0, 0]}]}",
      &scene, &error))
      << error.ToString();
  status = SceneFromProto(scene, &s);
  EXPECT_EQ(status.field(), "geometry.patches[0].centre_mm") << status.ToString();
}

TEST(SceneFromProto, HalfCylinderAndInvertedPatch) {
  v1::Scene scene;
  codec::ParseError error;
  ASSERT_TRUE(codec::ParseYaml(R"(
geometry:
  cylinder: {radius_mm: 23.5, height_mm: 25, half: true}
  patches:
    - {name: plate, set: cut, centre_mm: [0, 0, 25], radius_mm: 1.5, invert: true}
)",
                               &scene, &error))
      << error.ToString();
  SceneSpec s;
  ASSERT_TRUE(SceneFromProto(scene, &s).ok());
  EXPECT_TRUE(s.geometry.cylinder.half);
  ASSERT_EQ(s.geometry.patches.size(), 1u);
  EXPECT_TRUE(s.geometry.patches[0].invert);
  EXPECT_TRUE(s.geometry.patches[0].ball);
}

TEST(SceneFromProto, Atlas) {
  v1::Scene scene;
  codec::ParseError error;
  ASSERT_TRUE(codec::ParseYaml(R"(
geometry:
  atlas:
    source: synthetic
    structures: [Putamen, "Thalamus: pulvinar"]
    merge_rest: true
    voxel_size_mm: 2
    facet_size_mm: 3
    roi_centre_mm: [-24, -5, 6]
    roi_radius_mm: 12
    roi_element_size_mm: 1.5
  patches: [{name: base, set: surface, centre_mm: [0, -29, -54], radius_mm: 30}]
)",
                               &scene, &error))
      << error.ToString();
  SceneSpec s;
  ASSERT_TRUE(SceneFromProto(scene, &s).ok());
  EXPECT_EQ(s.geometry.kind, GeometrySpec::Kind::kAtlas);
  const AtlasSpec& a = s.geometry.atlas;
  EXPECT_EQ(a.source, "synthetic");
  EXPECT_EQ(a.structures, (std::vector<std::string>{"Putamen", "Thalamus: pulvinar"}));
  EXPECT_TRUE(a.merge_rest);
  EXPECT_EQ(a.voxel_size_mm, 2);
  EXPECT_EQ(a.facet_size_mm, 3);
  EXPECT_EQ(a.roi_centre_mm[0], -24);
  EXPECT_EQ(a.roi_radius_mm, 12);
  EXPECT_EQ(a.roi_element_size_mm, 1.5);
  ASSERT_TRUE(codec::ParseYaml("geometry: {atlas: {roi_centre_mm: [1, 2]}}", &scene, &error));
  EXPECT_EQ(SceneFromProto(scene, &s).field(), "geometry.atlas.roi_centre_mm");
}

TEST(SceneFromProto, LoadFieldPathsOfBadValues) {
  v1::Scene scene;
  codec::ParseError error;
  ASSERT_TRUE(codec::ParseYaml(std::string(kBase) + "gravity: {acceleration_m_per_s2: [0, -9.81]}",
                               &scene, &error));
  SceneSpec s;
  Status status = SceneFromProto(scene, &s);
  EXPECT_EQ(status.field(), "gravity.acceleration_m_per_s2") << status.ToString();
  ASSERT_TRUE(codec::ParseYaml(R"(
geometry: {box: {size_mm: [10, 10, 10]}}
boundary_conditions:
  - {set: bottom, fixed: {}}
  - {set: top, traction: {traction_pa: [1, 2]}}
)",
                               &scene, &error));
  status = SceneFromProto(scene, &s);
  EXPECT_EQ(status.field(), "boundary_conditions[1].traction.traction_pa") << status.ToString();
  // Gravity without a density is refused naming the density.
  status = Validate(
      "material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}\n"
      "gravity: {acceleration_m_per_s2: [0, 0, -9.81]}");
  EXPECT_EQ(status.field(), "material.density_kg_per_m3") << status.ToString();
  // A shell whose outer radius is not beyond the inner one.
  ASSERT_TRUE(codec::ParseYaml(R"(
geometry: {spherical_shell: {inner_radius_mm: 10, outer_radius_mm: 10}}
material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}
boundary_conditions:
  - {set: x0, symmetry: {}}
  - {set: y0, symmetry: {}}
  - {set: z0, symmetry: {}}
)",
                               &scene, &error));
  status = ValidateSceneProto(scene);
  EXPECT_EQ(status.field(), "geometry.spherical_shell.outer_radius_mm") << status.ToString();
}

TEST(SceneFromProto, OrthotropicElasticFromYaml) {
  SceneSpec s = Parse(R"(material:
  orthotropic_elastic:
    e1_pa: 6000
    e2_pa: 3000
    e3_pa: 1500
    nu12: 0.3
    nu13: 0.35
    nu23: 0.4
    g12_pa: 1500
    g13_pa: 900
    g23_pa: 600
    axis_1: [1, 1, 0]
    axis_2: [-1, 1, 0.5]
)");
  ASSERT_EQ(s.material.kind, MaterialSpec::Kind::kOrthotropicElastic);
  const OrthotropicElasticParams& p = s.material.orthotropic_elastic;
  EXPECT_EQ(p.e1_pa, 6000);
  EXPECT_EQ(p.e2_pa, 3000);
  EXPECT_EQ(p.e3_pa, 1500);
  EXPECT_EQ(p.nu12, 0.3);
  EXPECT_EQ(p.nu13, 0.35);
  EXPECT_EQ(p.nu23, 0.4);
  EXPECT_EQ(p.g12_pa, 1500);
  EXPECT_EQ(p.g13_pa, 900);
  EXPECT_EQ(p.g23_pa, 600);
  EXPECT_EQ(p.axis_1, (std::array<double, 3>{1, 1, 0}));
  EXPECT_EQ(p.axis_2, (std::array<double, 3>{-1, 1, 0.5}));
  EXPECT_FALSE(s.material.hyperelastic());

  // Axes left out are the global x and y axes.
  s = Parse(
      "material: {orthotropic_elastic: {e1_pa: 1, e2_pa: 1, e3_pa: 1, g12_pa: 1, g13_pa: 1, "
      "g23_pa: 1}}");
  EXPECT_EQ(s.material.orthotropic_elastic.axis_1, (std::array<double, 3>{1, 0, 0}));
  EXPECT_EQ(s.material.orthotropic_elastic.axis_2, (std::array<double, 3>{0, 1, 0}));

  v1::Scene scene;
  scene.mutable_material()->mutable_orthotropic_elastic()->add_axis_2(1);
  SceneSpec spec;
  EXPECT_EQ(SceneFromProto(scene, &spec).field(), "material.orthotropic_elastic.axis_2");

  const std::string good =
      "material: {orthotropic_elastic: {e1_pa: 6000, e2_pa: 3000, e3_pa: 1500, nu12: 0.3, "
      "nu13: 0.35, nu23: 0.4, g12_pa: 1500, g13_pa: 900, g23_pa: 600, axis_1: [0, 0, 1], "
      "axis_2: [1, 0, 0]}}\n";
  EXPECT_TRUE(Validate(good).ok()) << Validate(good).ToString();
  std::string bad = good;
  bad.replace(bad.find("nu12: 0.3"), 9, "nu12: 1.6");
  EXPECT_EQ(Validate(bad).field(), "material.orthotropic_elastic.nu12");
  bad = good;
  bad.replace(bad.find("axis_2: [1, 0, 0]"), 17, "axis_2: [0, 0, 2]");
  EXPECT_EQ(Validate(bad).field(), "material.orthotropic_elastic.axis_2");
  const Status nonlinear = Validate(good + "analysis: {type: NONLINEAR_STATIC}\n");
  EXPECT_EQ(nonlinear.field(), "material");
  EXPECT_NE(nonlinear.message().find("LINEAR_STATIC only"), std::string::npos)
      << nonlinear.ToString();
}

TEST(SceneFromProto, NonlinearAnalysisAndOutputs) {
  SceneSpec s = Parse(R"(material: {neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1e6}}
analysis:
  type: NONLINEAR_STATIC
  nonlinear: {increments: 12, max_iterations: 30, residual_tolerance: 1e-9, line_search: false}
outputs: {fields: [DISPLACEMENT, JACOBIAN]}
)");
  EXPECT_EQ(s.analysis.type, AnalysisSpec::Type::kNonlinearStatic);
  EXPECT_EQ(s.analysis.nonlinear.increments, 12);
  EXPECT_EQ(s.analysis.nonlinear.max_iterations, 30);
  EXPECT_EQ(s.analysis.nonlinear.residual_tolerance, 1e-9);
  EXPECT_FALSE(s.analysis.nonlinear.line_search);
  EXPECT_TRUE(s.outputs.displacement);
  EXPECT_TRUE(s.outputs.jacobian);
  EXPECT_FALSE(s.outputs.pk2_stress);
  EXPECT_FALSE(s.outputs.almansi_strain);
  EXPECT_FALSE(s.outputs.stress);

  // Unset: line search on, every field on.
  s = Parse(
      "material: {neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1e6}}\n"
      "analysis: {type: NONLINEAR_STATIC}\n");
  EXPECT_TRUE(s.analysis.nonlinear.line_search);
  EXPECT_TRUE(s.outputs.pk2_stress && s.outputs.almansi_strain && s.outputs.jacobian);
}

TEST(SceneFromProto, EveryLinearSolver) {
  const std::string material =
      "material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}\n";
  EXPECT_EQ(Parse(material).analysis.linear_solver, AnalysisSpec::LinearSolver::kAuto);
  EXPECT_EQ(Parse(material + "analysis: {linear_solver: AUTO}\n").analysis.linear_solver,
            AnalysisSpec::LinearSolver::kAuto);
  EXPECT_EQ(Parse(material + "analysis: {linear_solver: AMG}\n").analysis.linear_solver,
            AnalysisSpec::LinearSolver::kAmg);
  EXPECT_EQ(Parse(material + "analysis: {linear_solver: MUMPS}\n").analysis.linear_solver,
            AnalysisSpec::LinearSolver::kMumps);
  EXPECT_EQ(Parse(material + "analysis: {linear_solver: CHOLMOD}\n").analysis.linear_solver,
            AnalysisSpec::LinearSolver::kCholmod);
  EXPECT_EQ(Parse(material + "analysis: {linear_solver: EIGEN_LDLT}\n").analysis.linear_solver,
            AnalysisSpec::LinearSolver::kEigenLdlt);
  // Enum names are matched case-insensitively in YAML.
  EXPECT_EQ(Parse(material + "analysis: {linear_solver: PCG}\n").analysis.linear_solver,
            AnalysisSpec::LinearSolver::kPcg);
  EXPECT_EQ(Parse(material + "analysis: {linear_solver: pcg}\n").analysis.linear_solver,
            AnalysisSpec::LinearSolver::kPcg);
  EXPECT_TRUE(Validate(material + "analysis: {linear_solver: PCG}\n").ok());

  // A number the solver does not know (a newer client) names the field.
  v1::Scene scene;
  scene.mutable_analysis()->set_linear_solver(static_cast<v1::Analysis::LinearSolver>(99));
  SceneSpec spec;
  EXPECT_EQ(SceneFromProto(scene, &spec).field(), "analysis.linear_solver");
  scene.mutable_analysis()->set_linear_solver(v1::Analysis::AMG);
  scene.mutable_analysis()->mutable_linear_solver_options()->set_preconditioner(
      static_cast<v1::LinearSolverOptions::Preconditioner>(7));
  EXPECT_EQ(SceneFromProto(scene, &spec).field(), "analysis.linear_solver_options.preconditioner");

  // The options reach the spec; unset ones stay unset (their defaults).
  const SceneSpec options =
      Parse(material +
            "analysis: {linear_solver: AMG, linear_solver_options: {preconditioner: BOOMERAMG, "
            "relative_tolerance: 1e-8, max_iterations: 300, boomeramg_strong_threshold: 0.6, "
            "fallback_direct_max_unknowns: 0}}\n");
  const LinearSolverSpec& l = options.analysis.linear_solver_options;
  EXPECT_EQ(l.preconditioner, LinearSolverSpec::Preconditioner::kBoomerAmg);
  EXPECT_EQ(l.relative_tolerance, 1e-8);
  EXPECT_EQ(l.max_iterations, 300);
  EXPECT_EQ(l.boomeramg_strong_threshold, 0.6);
  EXPECT_FALSE(l.gamg_threshold.has_value());
  ASSERT_TRUE(l.fallback_direct_max_unknowns.has_value());
  EXPECT_EQ(*l.fallback_direct_max_unknowns, 0);
  EXPECT_EQ(l.auto_direct_max_factor_mb, 0);
  EXPECT_EQ(
      Parse(material + "analysis: {linear_solver: AMG, linear_solver_options: {preconditioner: "
                       "PRESSURE_SCHUR}}\n")
          .analysis.linear_solver_options.preconditioner,
      LinearSolverSpec::Preconditioner::kPressureSchur);
  // Out of range: the scene is refused, naming the field.
  EXPECT_EQ(
      Validate(material + "analysis: {linear_solver_options: {relative_tolerance: 2}}\n").field(),
      "analysis.linear_solver_options.relative_tolerance");

  // The solver's name comes back in the summary.
  Summary summary;
  summary.linear_solver = "conjugate gradient with incomplete Cholesky (IC) preconditioner";
  EXPECT_EQ(SummaryToProto(summary).modelled().linear_solver(), summary.linear_solver);
}

TEST(SceneFromProto, SymmetryCondition) {
  v1::Scene scene;
  codec::ParseError error;
  ASSERT_TRUE(codec::ParseYaml(R"(
geometry: {cylinder: {radius_mm: 5, height_mm: 10}}
material: {neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1e6}}
boundary_conditions:
  - {set: bottom, symmetry: {}}
  - {set: side, symmetry: {}}
)",
                               &scene, &error))
      << error.ToString();
  SceneSpec spec;
  ASSERT_TRUE(SceneFromProto(scene, &spec).ok());
  EXPECT_EQ(spec.boundary_conditions[0].kind, BoundaryConditionSpec::Kind::kSymmetry);
  const Status status = ValidateSceneProto(scene);
  EXPECT_EQ(status.field(), "boundary_conditions[1].symmetry") << status.ToString();
  EXPECT_NE(status.message().find("curved"), std::string::npos);
}

TEST(ValidateSceneProto, NamesTheBadField) {
  EXPECT_EQ(
      Validate("material: {neo_hookean: {shear_modulus_pa: 0, bulk_modulus_pa: 1e6}}").field(),
      "material.neo_hookean.shear_modulus_pa");
  EXPECT_EQ(
      Validate("material: {neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 10}}").field(),
      "material.neo_hookean.bulk_modulus_pa");
  EXPECT_EQ(Validate("material: {ogden: {terms: [{mu_pa: 842, alpha: 0}], bulk_modulus_pa: 1e6}}")
                .field(),
            "material.ogden.terms[0].alpha");
  EXPECT_EQ(Validate("material: {ogden: {terms: [], bulk_modulus_pa: 1e6}}").field(),
            "material.ogden.terms");
  EXPECT_EQ(Validate("material: {polynomial: {terms: [{i: 1, j: 0, c_pa: 500}], d_per_pa: "
                     "[1e-6, 1e-7]}}")
                .field(),
            "material.polynomial.d_per_pa");
  EXPECT_EQ(Validate("material: {polynomial: {terms: [{i: 2, j: 2, c_pa: 5}], d_per_pa: [1e-6]}}")
                .field(),
            "material.polynomial.terms[0]");
  EXPECT_EQ(Validate("material: {mooney_rivlin: {c10_pa: 100, c01_pa: -200, bulk_modulus_pa: 1e6}}")
                .field(),
            "material.mooney_rivlin.c10_pa");
  EXPECT_EQ(Validate("material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}\n"
                     "analysis: {type: NONLINEAR_STATIC}\n")
                .field(),
            "material");
  EXPECT_EQ(Validate("material: {neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1e6}}\n"
                     "analysis: {type: NONLINEAR_STATIC, nonlinear: {increments: -3}}\n")
                .field(),
            "analysis.nonlinear.increments");
  EXPECT_EQ(Validate("material: {neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1e6}}\n"
                     "analysis: {type: NONLINEAR_STATIC, nonlinear: {residual_tolerance: 2}}\n")
                .field(),
            "analysis.nonlinear.residual_tolerance");
  EXPECT_EQ(Validate("material: {neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1e6}}\n"
                     "mesh: {element: TET4_ANP}\n")
                .field(),
            "mesh.element");
  EXPECT_EQ(Validate("material: {neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1e6}}\n"
                     "mesh: {element: TET10_MD}\n")
                .field(),
            "mesh.element");
  EXPECT_TRUE(Validate("material: {ogden: {terms: [{mu_pa: 842, alpha: -4.7}], "
                       "bulk_modulus_pa: 8.42e7}}\nanalysis: {type: NONLINEAR_STATIC}\n")
                  .ok());
}

// A box scene of the finite-strain fields that need no atlas: the scene's
// material relaxing, a growing inclusion, a punch, buoyancy and a time curve.
constexpr const char* kQuasiStatic = R"(
material:
  neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1e6}
  density_kg_per_m3: 1040
  viscoelastic: {prony: {g: [0.5, 0.2], tau_s: [0.5, 5]}}
inclusions:
  - name: tumour
    centre_mm: [5, 5, 5]
    radius_mm: 2
    growth_strain: 0.1
    material:
      name: tumour tissue
      mooney_rivlin: {c10_pa: 600, c01_pa: 400, bulk_modulus_pa: 2e6}
      viscoelastic: {moduli: {long_term_modulus_pa: 300, moduli_pa: [500, 200], tau_s: [0.1, 10]}}
contacts:
  - {name: punch, set: top, shape: FLAT_PUNCH, position_mm: [5, 5, 10], radius_mm: 2,
     motion_mm: [0, 0, -1], friction: 0.2, penalty_factor: 50, penetration_tolerance_mm: 0.01}
  - {name: base, set: bottom, shape: PLANE, position_mm: [0, 0, 0], axis: [0, 0, 2]}
gravity: {acceleration_m_per_s2: [0, 0, -9.81], fluid_density_kg_per_m3: 1007, fluid_level_mm: 4}
analysis:
  type: QUASI_STATIC
  time:
    end_time_s: 10
    initial_step_s: 0.5
    min_step_s: 0.01
    max_step_s: 2
    curve: [{time_s: 0, amplitude: 0}, {time_s: 5, amplitude: 1}]
outputs: {structure_displacements: [tumour]}
)";

TEST(SceneFromProto, QuasiStaticWithEveryNewField) {
  const SceneSpec s = Parse(kQuasiStatic);
  EXPECT_EQ(s.analysis.type, AnalysisSpec::Type::kQuasiStatic);
  EXPECT_EQ(s.material.viscoelastic.form, ViscoelasticSpec::Form::kProny);
  EXPECT_EQ(s.material.viscoelastic.g, (std::vector<double>{0.5, 0.2}));
  EXPECT_EQ(s.material.viscoelastic.tau_s, (std::vector<double>{0.5, 5}));

  ASSERT_EQ(s.inclusions.size(), 1u);
  const InclusionSpec& tumour = s.inclusions[0];
  EXPECT_EQ(tumour.name, "tumour");
  EXPECT_EQ(tumour.centre_mm, (std::array<double, 3>{5, 5, 5}));
  EXPECT_EQ(tumour.radius_mm, 2);
  EXPECT_EQ(tumour.growth_strain, 0.1);
  EXPECT_EQ(tumour.material.name, "tumour tissue");
  EXPECT_EQ(tumour.material.kind, MaterialSpec::Kind::kMooneyRivlin);
  EXPECT_EQ(tumour.material.mooney_rivlin.c01_pa, 400);
  EXPECT_EQ(tumour.material.viscoelastic.form, ViscoelasticSpec::Form::kModuli);
  EXPECT_EQ(tumour.material.viscoelastic.long_term_modulus_pa, 300);
  EXPECT_EQ(tumour.material.viscoelastic.moduli_pa, (std::vector<double>{500, 200}));
  EXPECT_EQ(tumour.material.viscoelastic.tau_s, (std::vector<double>{0.1, 10}));

  ASSERT_EQ(s.contacts.size(), 2u);
  const ContactSpec& punch = s.contacts[0];
  EXPECT_EQ(punch.name, "punch");
  EXPECT_EQ(punch.set, "top");
  EXPECT_EQ(punch.shape, ContactSpec::Shape::kFlatPunch);
  EXPECT_EQ(punch.position_mm, (std::array<double, 3>{5, 5, 10}));
  EXPECT_EQ(punch.axis, (std::array<double, 3>{0, 0, -1}));  // absent: the default
  EXPECT_EQ(punch.radius_mm, 2);
  EXPECT_EQ(punch.motion_mm, (std::array<double, 3>{0, 0, -1}));
  EXPECT_EQ(punch.friction, 0.2);
  EXPECT_EQ(punch.penalty_factor, 50);
  EXPECT_EQ(punch.penetration_tolerance_mm, 0.01);
  EXPECT_EQ(s.contacts[1].shape, ContactSpec::Shape::kPlane);
  EXPECT_EQ(s.contacts[1].axis, (std::array<double, 3>{0, 0, 2}));
  EXPECT_EQ(s.contacts[1].motion_mm, (std::array<double, 3>{0, 0, 0}));

  EXPECT_EQ(s.gravity.fluid_density_kg_per_m3, 1007);
  ASSERT_TRUE(s.gravity.fluid_level_mm.has_value());
  EXPECT_EQ(*s.gravity.fluid_level_mm, 4);

  const TimeSpec& t = s.analysis.time;
  EXPECT_EQ(t.end_time_s, 10);
  EXPECT_EQ(t.initial_step_s, 0.5);
  EXPECT_EQ(t.min_step_s, 0.01);
  EXPECT_EQ(t.max_step_s, 2);
  ASSERT_EQ(t.curve.size(), 2u);
  EXPECT_EQ(t.curve[1], (std::pair<double, double>{5, 1}));
  EXPECT_EQ(s.outputs.structure_displacements, (std::vector<std::string>{"tumour"}));

  const Status status = Validate(kQuasiStatic);
  EXPECT_TRUE(status.ok()) << status.ToString();
}

TEST(SceneFromProto, RegionMaterialsOnAnAtlas) {
  v1::Scene scene;
  codec::ParseError error;
  ASSERT_TRUE(codec::ParseYaml(R"(
geometry: {atlas: {structures: [Putamen, Globus pallidus lateralis]}}
material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}
material_library: rat-brain-prony
region_materials:
  - structures: [Putamen]
    material: {linear_elastic: {youngs_modulus_pa: 6000, poissons_ratio: 0.4}}
  - structures: [Globus pallidus lateralis]
    material:
      orthotropic_elastic: {e1_pa: 6000, e2_pa: 3000, e3_pa: 3000, g12_pa: 1500, g13_pa: 1500,
                            g23_pa: 1000, axis_1: [1, 1]}
boundary_conditions: [{set: surface, fixed: {}}]
outputs: {structure_displacements: ["*"]}
)",
                               &scene, &error))
      << error.ToString();
  SceneSpec spec;
  // The shared material conversion names the region's own path.
  Status status = SceneFromProto(scene, &spec);
  EXPECT_EQ(status.field(), "region_materials[1].material.orthotropic_elastic.axis_1")
      << status.ToString();
  scene.mutable_region_materials(1)->mutable_material()->mutable_orthotropic_elastic()->add_axis_1(
      0);
  status = SceneFromProto(scene, &spec);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_EQ(spec.material_library, "rat-brain-prony");
  ASSERT_EQ(spec.region_materials.size(), 2u);
  EXPECT_EQ(spec.region_materials[0].structures, (std::vector<std::string>{"Putamen"}));
  EXPECT_EQ(spec.region_materials[0].material.linear_elastic.youngs_modulus_pa, 6000);
  EXPECT_EQ(spec.region_materials[1].material.orthotropic_elastic.axis_1,
            (std::array<double, 3>{1, 1, 0}));
  EXPECT_EQ(spec.outputs.structure_displacements, (std::vector<std::string>{"*"}));
  status = ValidateSceneProto(scene);
  EXPECT_TRUE(status.ok()) << status.ToString();
}

TEST(SceneFromProto, NewFieldPathsOfBadValues) {
  const std::string base = kQuasiStatic;
  // Lists that must hold three values name themselves.
  v1::Scene scene;
  codec::ParseError error;
  ASSERT_TRUE(codec::ParseYaml(std::string(kBase) + base, &scene, &error)) << error.ToString();
  SceneSpec spec;
  v1::Scene bad = scene;
  bad.mutable_inclusions(0)->clear_centre_mm();
  EXPECT_EQ(SceneFromProto(bad, &spec).field(), "inclusions[0].centre_mm");
  bad = scene;
  bad.mutable_contacts(1)->add_axis(1);
  EXPECT_EQ(SceneFromProto(bad, &spec).field(), "contacts[1].axis");
  bad = scene;
  bad.mutable_contacts(0)->clear_position_mm();
  EXPECT_EQ(SceneFromProto(bad, &spec).field(), "contacts[0].position_mm");
  bad = scene;
  bad.mutable_contacts(0)->add_motion_mm(0);
  EXPECT_EQ(SceneFromProto(bad, &spec).field(), "contacts[0].motion_mm");
  bad = scene;
  bad.mutable_contacts(0)->set_shape(static_cast<v1::Contact::Shape>(9));
  EXPECT_EQ(SceneFromProto(bad, &spec).field(), "contacts[0].shape");
  // Values the validation refuses, through the proto.
  bad = scene;
  bad.mutable_contacts(1)->set_shape(v1::Contact::SHAPE_UNSPECIFIED);
  EXPECT_EQ(ValidateSceneProto(bad).field(), "contacts[1].shape");
  bad = scene;
  bad.mutable_material()->mutable_viscoelastic()->mutable_prony()->set_g(0, 0.9);
  EXPECT_EQ(ValidateSceneProto(bad).field(), "material.viscoelastic.prony.g");
  bad = scene;
  bad.mutable_analysis()->set_type(v1::Analysis::NONLINEAR_STATIC);
  EXPECT_EQ(ValidateSceneProto(bad).field(), "analysis.time");
  bad = scene;
  bad.mutable_analysis()->mutable_time()->mutable_curve(1)->set_time_s(0);
  EXPECT_EQ(ValidateSceneProto(bad).field(), "analysis.time.curve[1].time_s");
}

TEST(SceneFromProto, Profiles) {
  const SceneSpec spec =
      Parse(R"(material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}
outputs:
  profiles:
    - {name: radial, from_mm: [1, 2, 3], to_mm: [4, 5, 6], points: 7}
    - {name: axis, from_mm: [5, 5, 0], to_mm: [5, 5, 10]}
)");
  ASSERT_EQ(spec.outputs.profiles.size(), 2u);
  EXPECT_EQ(spec.outputs.profiles[0].name, "radial");
  EXPECT_EQ(spec.outputs.profiles[0].from_mm, (std::array<double, 3>{1, 2, 3}));
  EXPECT_EQ(spec.outputs.profiles[0].to_mm, (std::array<double, 3>{4, 5, 6}));
  EXPECT_EQ(spec.outputs.profiles[0].points, 7);
  EXPECT_EQ(spec.outputs.profiles[1].points, 0);
  EXPECT_TRUE(ValidateScene(spec).ok());
  // Two values where three belong; then the checks, through the proto.
  v1::Scene scene;
  codec::ParseError error;
  ASSERT_TRUE(codec::ParseYaml(
      std::string(kBase) +
          R"(material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}
outputs:
  profiles: [{name: r, from_mm: [0, 0], to_mm: [1, 1, 1]}]
)",
      &scene, &error));
  SceneSpec out;
  const Status status = SceneFromProto(scene, &out);
  EXPECT_EQ(status.field(), "outputs.profiles[0].from_mm");
  EXPECT_NE(status.message().find("expected three"), std::string::npos) << status.message();
  scene.mutable_outputs()->mutable_profiles(0)->add_from_mm(0);
  scene.mutable_outputs()->mutable_profiles(0)->set_points(1);
  EXPECT_EQ(ValidateSceneProto(scene).field(), "outputs.profiles[0].points");
  scene.mutable_outputs()->mutable_profiles(0)->set_points(0);
  scene.mutable_outputs()->mutable_profiles(0)->set_name("r/s");
  EXPECT_EQ(ValidateSceneProto(scene).field(), "outputs.profiles[0].name");
}

TEST(SummaryToProto, ProfilesAndTheirLines) {
  Summary s;
  s.profiles = {{"radial", 50, 48, -512.31, 3.5, {13.5, 0, 0}}, {"away", 10, 0, 0, 0, {0, 0, 0}}};
  const v1::Summary proto = SummaryToProto(s);
  ASSERT_EQ(proto.results().profiles_size(), 2);
  const v1::ProfileResult& radial = proto.results().profiles(0);
  EXPECT_EQ(radial.name(), "radial");
  EXPECT_EQ(radial.points(), 50);
  EXPECT_EQ(radial.inside(), 48);
  EXPECT_EQ(radial.max_stress_along_pa(), -512.31);
  EXPECT_EQ(radial.at_distance_mm(), 3.5);
  ASSERT_EQ(radial.at_mm_size(), 3);
  EXPECT_EQ(radial.at_mm(0), 13.5);
  const std::string text = codec::FormatSummary(proto);
  EXPECT_NE(text.find("profile radial     48 of 50 points inside; largest stress along the line "
                      "-512.3 Pa at 3.5 mm (13.5, 0, 0)"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("profile away       0 of 10 points inside\n"), std::string::npos) << text;
  EXPECT_EQ(codec::FormatSummary(SummaryToProto(Summary())).find("profile"), std::string::npos);
}

// The example scenes stay valid as the checks grow.
TEST(ValidateSceneProto, EveryExampleIsValid) {
  int examples = 0;
  for (const auto& entry : std::filesystem::directory_iterator(PBA_EXAMPLES_DIR)) {
    if (entry.path().extension() != ".yaml") continue;
    v1::Scene scene;
    codec::ParseError error;
    ASSERT_TRUE(codec::ReadYamlFile(entry.path(), &scene, &error)) << error.ToString();
    const Status status = ValidateSceneProto(scene);
    EXPECT_TRUE(status.ok()) << entry.path().filename() << ": " << status.ToString();
    ++examples;
  }
  EXPECT_GT(examples, 0);
}

Summary QuasiStaticSummary(int structures) {
  Summary s;
  s.scene_name = "punch";
  s.analysis = "quasi-static";
  s.increments = {{0.5, 3, 1e-10}, {1, 4, 1e-10}};
  s.newton_iterations = 7;
  s.time_steps = {{0.5, 0.5, 0.5, 3, 1e-10}, {5, 4.5, 1, 4, 2e-10}};
  s.contacts = {{"punch", {0, 0, -0.0123}, 0.0125, 12.5, 0.004, 2e4, 3}};
  for (int i = 0; i < structures; ++i) {
    s.structure_displacements.push_back(
        {"structure " + std::to_string(i), {0, 0, -0.1 * (i + 1)}, 0.2 * (i + 1)});
  }
  return s;
}

TEST(SummaryToProto, CarriesTimeStepsContactsAndStructures) {
  const v1::Summary proto = SummaryToProto(QuasiStaticSummary(2));
  const v1::Convergence& c = proto.results().convergence();
  ASSERT_EQ(c.time_steps_size(), 2);
  EXPECT_EQ(c.time_steps(1).time_s(), 5);
  EXPECT_EQ(c.time_steps(1).step_s(), 4.5);
  EXPECT_EQ(c.time_steps(1).amplitude(), 1);
  EXPECT_EQ(c.time_steps(1).iterations(), 4);
  EXPECT_EQ(c.time_steps(1).relative_residual(), 2e-10);
  ASSERT_EQ(proto.results().contacts_size(), 1);
  const v1::ContactResult& punch = proto.results().contacts(0);
  EXPECT_EQ(punch.name(), "punch");
  ASSERT_EQ(punch.force_n_size(), 3);
  EXPECT_EQ(punch.force_n(2), -0.0123);
  EXPECT_EQ(punch.peak_force_n(), 0.0125);
  EXPECT_EQ(punch.area_mm2(), 12.5);
  EXPECT_EQ(punch.max_penetration_mm(), 0.004);
  EXPECT_EQ(punch.penalty_pa_per_mm(), 2e4);
  EXPECT_EQ(punch.augmentations(), 3);
  ASSERT_EQ(proto.results().structure_displacements_size(), 2);
  EXPECT_EQ(proto.results().structure_displacements(1).name(), "structure 1");
  ASSERT_EQ(proto.results().structure_displacements(1).mean_mm_size(), 3);
  EXPECT_EQ(proto.results().structure_displacements(1).max_mm(), 0.4);
}

TEST(FormatSummary, TimeStepsContactsAndStructures) {
  std::string text = codec::FormatSummary(SummaryToProto(QuasiStaticSummary(3)));
  EXPECT_NE(text.find("time               2 steps to 5 s, step 0.5 s first, 4.5 s last; 7 "
                      "iterations"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("punch"), std::string::npos) << text;
  EXPECT_NE(text.find("(0, 0, -0.0123)"), std::string::npos) << text;
  EXPECT_NE(text.find("0.0125"), std::string::npos) << text;
  // Largest mean first.
  EXPECT_LT(text.find("structure 2"), text.find("structure 0")) << text;
  EXPECT_EQ(text.find("more"), std::string::npos) << text;

  text = codec::FormatSummary(SummaryToProto(QuasiStaticSummary(20)));
  EXPECT_NE(text.find("structure 19"), std::string::npos) << text;
  EXPECT_NE(text.find("structure 5 "), std::string::npos) << text;
  EXPECT_EQ(text.find("structure 4 "), std::string::npos) << text;
  EXPECT_NE(text.find("... and 5 more"), std::string::npos) << text;
  // A static summary has none of it.
  text = codec::FormatSummary(SummaryToProto(Summary()));
  EXPECT_EQ(text.find("contact"), std::string::npos) << text;
  EXPECT_EQ(text.find("structure"), std::string::npos) << text;
  EXPECT_EQ(text.find("steps to"), std::string::npos) << text;
}

Summary NonlinearSummary(int increments) {
  Summary s;
  s.scene_name = "block";
  s.analysis = "nonlinear static";
  for (int i = 1; i <= increments; ++i) {
    s.increments.push_back({static_cast<double>(i) / increments, 3, 1e-10 * i});
  }
  s.newton_iterations = 3 * increments;
  s.increment_cuts = 1;
  s.relative_residual = 1e-10;
  return s;
}

TEST(SummaryToProto, CarriesTheNewtonPath) {
  const v1::Summary proto = SummaryToProto(NonlinearSummary(4));
  ASSERT_TRUE(proto.results().has_convergence());
  const v1::Convergence& c = proto.results().convergence();
  ASSERT_EQ(c.increments_size(), 4);
  EXPECT_EQ(c.increments(3).load_factor(), 1.0);
  EXPECT_EQ(c.increments(1).iterations(), 3);
  EXPECT_EQ(c.newton_iterations(), 12);
  EXPECT_EQ(c.increment_cuts(), 1);
  EXPECT_FALSE(SummaryToProto(Summary()).results().has_convergence());
}

TEST(FormatSummary, NewtonLineAndAShortenedPath) {
  std::string text = codec::FormatSummary(SummaryToProto(NonlinearSummary(4)));
  EXPECT_NE(text.find("Newton             4 increments, 12 iterations, 1 cut back"),
            std::string::npos)
      << text;
  EXPECT_EQ(text.find("linear residual"), std::string::npos);
  EXPECT_NE(text.find("load 0.75"), std::string::npos) << text;
  text = codec::FormatSummary(SummaryToProto(NonlinearSummary(20)));
  EXPECT_NE(text.find("... 14 more increments ..."), std::string::npos) << text;
  EXPECT_NE(text.find("load 1 "), std::string::npos) << text;
  // A linear summary keeps its residual line.
  EXPECT_NE(codec::FormatSummary(SummaryToProto(Summary())).find("linear residual"),
            std::string::npos);
}

TEST(FormatSummary, AdaptationCyclesAndWhyTheyEnded) {
  Summary s;
  s.adaptation.adapted = true;
  s.adaptation.target_error = 0.05;
  s.adaptation.max_cycles = 6;
  s.adaptation.stop_reason = "6 solves ran (mesh.adapt.max_cycles)";
  s.adaptation.cycles = {{1536, 405, 945, 0.33, 0.01, 96, 0, ""},
                         {1956, 480, 1120, 0.25, 0.02, 0, 0.055, "reaction on pressed"}};
  const v1::Summary proto = SummaryToProto(s);
  ASSERT_TRUE(proto.modelled().has_adaptation());
  ASSERT_EQ(proto.modelled().adaptation().cycles_size(), 2);
  EXPECT_EQ(proto.modelled().adaptation().cycles(1).changed_quantity(), "reaction on pressed");
  EXPECT_EQ(proto.modelled().adaptation().cycles(0).marked(), 96);
  std::string text = codec::FormatSummary(proto);
  EXPECT_NE(text.find("Adapted      TARGET NOT REACHED: 6 solves ran (mesh.adapt.max_cycles)"),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("1956"), std::string::npos) << text;
  EXPECT_NE(text.find("5.5 % (reaction on pressed)"), std::string::npos) << text;
  s.adaptation.reached = true;
  EXPECT_NE(codec::FormatSummary(SummaryToProto(s)).find("Adapted      target reached"),
            std::string::npos);
  // Without mesh.adapt, no such lines.
  EXPECT_FALSE(SummaryToProto(Summary()).modelled().has_adaptation());
  EXPECT_EQ(codec::FormatSummary(SummaryToProto(Summary())).find("Adapted"), std::string::npos);
}

TEST(FormatSummary, ErrorPerStructureWhenThereAreSeveral) {
  Summary s;
  s.error.estimated = true;
  s.error.method = "ZZ";
  s.error.relative_error = 0.05;
  s.error.regions = {{"body", 10, 0.05, 1.0}};
  std::string text = codec::FormatSummary(SummaryToProto(s));
  EXPECT_EQ(text.find("body"), std::string::npos) << text;  // one region: the overall line
  s.error.regions = {{"putamen", 120, 0.08, 0.75}, {"caudate", 80, 0.03, 0.25}};
  const v1::Summary proto = SummaryToProto(s);
  ASSERT_EQ(proto.error_estimate().regions_size(), 2);
  EXPECT_EQ(proto.error_estimate().regions(0).elements(), 120);
  text = codec::FormatSummary(proto);
  EXPECT_NE(text.find("putamen"), std::string::npos) << text;
  EXPECT_NE(text.find("about 8 % (75 % of the error, 120 elements)"), std::string::npos) << text;
  EXPECT_NE(text.find("caudate"), std::string::npos) << text;
}

}  // namespace
}  // namespace pba
