// Which material each element of a scene's model takes: the scene's
// `material`, a built-in tissue library's entry for an atlas structure
// (material/tissue_library.h), a region material, or an inclusion's; and the
// inclusions themselves, cut into the mesh as regions of their own.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "material/linear_elastic.h"
#include "material/material_field.h"
#include "mesh/mesh.h"
#include "pba/scene.h"

namespace pba {

struct SceneMaterials {
  // The distinct materials; [0] is the scene's `material`.
  std::vector<MaterialSpec> specs;
  std::vector<std::string> labels;    // what each is, e.g. "Putamen: rat-brain-prony"
  std::vector<double> growth_strain;  // per spec: an inclusion's growth at a(t) = 1
  std::vector<int> of_element;        // spec index of every element
  // One line per material in use beyond the scene's, for the summary.
  std::vector<std::string> notes;

  bool uniform() const { return specs.size() == 1; }
  double density(int e) const { return specs[of_element[e]].density_kg_per_m3; }
};

// Makes every inclusion a region of `mesh`: the elements whose centroid lies
// within its ball. A primitive body's elements become region "body" first.
// Fails naming the inclusion when its ball holds no element's centroid.
Status CutInclusions(const SceneSpec& scene, Mesh* mesh);

// The material of every element, in this order of precedence: an
// inclusion's, the region_materials entry naming the element's structure,
// the material_library's entry for it, the scene's. Fails naming the field
// of a region material whose structure the mesh does not have.
Status ResolveMaterials(const SceneSpec& scene, const Mesh& mesh, SceneMaterials* out);

// The material field of resolved (hyperelastic) materials, their
// relaxation reduced to what the analysis resolves (terms faster than
// relaxed_below_s relaxed, slower than frozen_above_s when > 0 frozen; see
// ReduceRelaxation); its passes run on `threads`.
std::unique_ptr<MaterialField> MakeMaterialField(const SceneMaterials& materials,
                                                 double relaxed_below_s, double frozen_above_s,
                                                 const ThreadContext& threads);

// The small-strain elasticity of every element (material/linear_elastic.h):
// linear models as they are, hyperelastic ones with their initial moduli,
// orthotropic ones in the global frame.
ElasticityField MakeElasticityField(const SceneMaterials& materials);

// The relaxation of a material spec as a normalised Prony series (no terms:
// elastic).
PronySeries RelaxationOf(const ViscoelasticSpec& spec);

}  // namespace pba
