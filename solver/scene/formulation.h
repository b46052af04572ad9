// `formulation: AUTO` (pba/scene.h): the decisions that reduce a scene to
// the physics it needs, each with the quantity that drove it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "pba/scene.h"
#include "pba/solve.h"

namespace pba {

// Strain (largest component magnitude) above which finite strain is kept.
constexpr double kFiniteStrainThreshold = 0.02;

// The options of `formulation: AUTO`, defaults applied.
struct AutoFormulationOptions {
  // The largest relative difference between the reduced and the full
  // model, on meshes twice as coarse, at which the reduced one is kept
  // (scene field formulation_tolerance; 0 there: this default).
  double tolerance = 0.01;

  static AutoFormulationOptions FromScene(const SceneSpec& scene);
  // Names formulation_tolerance when it is out of range, or given without
  // formulation: AUTO (where nothing would read it).
  Status Validate() const;

  // What the scene wrote, for Validate(): 0 when it was left out.
  double written_tolerance = 0;
  bool auto_formulation = false;
};

// The relaxation a QUASI_STATIC scene resolves: terms 100 times faster
// than its shortest loading segment (a stretch of the time curve where the
// amplitude changes) relax within it; terms 100 times slower than the
// whole analysis do not relax in it. Sets analysis.relaxed_below_s and
// frozen_above_s of `reduced` and says what that does to each relaxing
// material the scene names.
void ReduceViscoelasticity(const SceneSpec& scene, SceneSpec* reduced,
                           std::vector<ModelDecision>* decisions);

// Whether the scene can be solved in small strain at all, and if not why
// (contact, growth, relaxation through time, follower pressure on a time
// curve); empty when it can.
std::string FiniteStrainRequiredBy(const SceneSpec& scene);

// The first cheap solve that measures the strain: LINEAR_STATIC on a mesh
// twice as coarse, with quadratic tetrahedra (or the bricks the scene
// uses), which do not lock as 4-node tetrahedra would when nearly
// incompressible.
SceneSpec CheapStrainScene(const SceneSpec& scene);

// Switches `reduced` to LINEAR_STATIC when `max_strain` is below the
// threshold (a NONLINEAR_STATIC scene only) and its element has a linear
// form, else to one load increment; records the decision either way.
void ReduceFiniteStrain(const SceneSpec& scene, std::optional<double> max_strain,
                        SceneSpec* reduced, std::vector<ModelDecision>* decisions);

// Of an atlas, keeps only the structures the scene names (outputs,
// region_materials) or loads (conditions and contacts on a structure's
// surface or an interface, or on patches of them), merging the rest into
// one region; nothing changes when it names none.
void ReduceStructures(const SceneSpec& scene, SceneSpec* reduced,
                      std::vector<ModelDecision>* decisions);

// The scene on meshes twice as coarse (element and region-of-interest sizes),
// without adaptive refinement.
SceneSpec Coarsened(const SceneSpec& scene);

// The largest relative difference of the results two solutions of one
// scene share (largest displacement, reactions, contact forces, structure
// displacements), and its quantity's name.
double LargestRelativeDifference(const Summary& reference, const Summary& other,
                                 std::string* quantity);

}  // namespace pba
