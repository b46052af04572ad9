// Scene variants for the property test of the validation contract
// (validated_scenes_solve_test.cc): builders of small scenes, a
// deterministic pseudo-random sample of variants of one small box across
// what the validators read, and a one-line description of a scene to
// find it again by.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "pba/scene.h"

namespace pba::scene_variants {

using Components = std::array<std::optional<double>, 3>;  // x, y, z; nullopt = free

BoundaryConditionSpec Held(const std::string& set, BoundaryConditionSpec::Kind kind,
                           Components mm = {});
BoundaryConditionSpec Pressure(const std::string& set, double pa);
BoundaryConditionSpec Traction(const std::string& set, std::array<double, 3> pa);
BoundaryConditionSpec Velocity(const std::string& set, Components m_per_s);

// Tissue-like moduli: initial shear modulus about 1 kPa, bulk modulus
// bulk_ratio times it; density 1040 kg/m^3.
MaterialSpec Material(MaterialSpec::Kind kind, double bulk_ratio);

// A relaxation of `form` whose times sit around `time_scale` [s] (a
// QUASI_STATIC analysis's end time), so that a few dozen steps resolve it.
void AddRelaxation(ViscoelasticSpec::Form form, double time_scale, MaterialSpec* material);

// An inclusion's material: the family of `scene_material`, stiffer, without
// relaxation.
MaterialSpec Stiffer(const MaterialSpec& scene_material);

// A rigid body of `shape` named "tool" over the box's top (radius 1 mm),
// pressing down along -z by 0.3 mm, touching face set `set`.
ContactSpec Contact(ContactSpec::Shape shape, const std::string& set);

// A box of 4 x 4 x 6 mm in 2 mm cells (72 tetrahedra or 12 bricks),
// neo-Hookean, bottom fixed, top pushed down 0.2 mm; NONLINEAR_STATIC.
SceneSpec BaseScene();

// `count` variants of BaseScene(), drawn from std::mt19937(seed): the same
// list on every platform. Most keep to combinations the analysis takes, so
// that a good share validates; some roam freely.
std::vector<SceneSpec> SampledScenes(uint32_t seed, int count);

// The settings that tell a scene apart, on one line.
std::string Describe(const SceneSpec& scene);

}  // namespace pba::scene_variants
