#include "scene/formulation.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "atlas/colour_table.h"
#include "core/format.h"
#include "fem/element_kind.h"
#include "material/tissue_library.h"
#include "mesh/primitive_mesher.h"
#include "mesh/region_faces.h"
#include "scene/materials.h"
#include "scene/time_curve.h"

namespace pba {
namespace {

// The materials a scene names, with where (for the decisions' wording).
std::vector<std::pair<std::string, const MaterialSpec*>> NamedMaterials(const SceneSpec& scene) {
  std::vector<std::pair<std::string, const MaterialSpec*>> out = {{"material", &scene.material}};
  for (std::size_t i = 0; i < scene.region_materials.size(); ++i) {
    out.emplace_back(Format("region_materials[%zu]", i), &scene.region_materials[i].material);
  }
  for (const InclusionSpec& inclusion : scene.inclusions) {
    out.emplace_back("inclusion " + inclusion.name, &inclusion.material);
  }
  return out;
}

}  // namespace

AutoFormulationOptions AutoFormulationOptions::FromScene(const SceneSpec& scene) {
  AutoFormulationOptions options;
  options.written_tolerance = scene.formulation_tolerance;
  options.auto_formulation = scene.formulation == Formulation::kAuto;
  if (scene.formulation_tolerance != 0) options.tolerance = scene.formulation_tolerance;
  return options;
}

Status AutoFormulationOptions::Validate() const {
  if (written_tolerance == 0) return Status::Ok();
  if (!auto_formulation) {
    return Status::InvalidArgument(
        "formulation_tolerance",
        "applies only to formulation: AUTO (the scene is solved as written)");
  }
  if (!(written_tolerance > 0 && written_tolerance < 1)) {
    return Status::InvalidArgument(
        "formulation_tolerance",
        "must be a fraction between 0 and 1 (0.01 is 1 %), got " + ShortNumber(written_tolerance));
  }
  return Status::Ok();
}

void ReduceViscoelasticity(const SceneSpec& scene, SceneSpec* reduced,
                           std::vector<ModelDecision>* decisions) {
  bool any = !scene.material_library.empty();
  for (const auto& [where, material] : NamedMaterials(scene))
    any = any || material->viscoelastic.enabled();
  if (!any) return;
  if (scene.analysis.type != AnalysisSpec::Type::kQuasiStatic) {
    decisions->push_back(
        {"viscoelasticity", "instantaneous modulus", "a static analysis has no time to relax in"});
    return;
  }
  const double loading = TimeCurve(TimeOptions::FromSpec(scene.analysis.time)).ShortestLoading();
  const double relaxed = loading / 100, frozen = 100 * scene.analysis.time.end_time_s;
  reduced->analysis.relaxed_below_s = relaxed;
  reduced->analysis.frozen_above_s = frozen;
  for (const auto& [where, material] : NamedMaterials(scene)) {
    if (!material->viscoelastic.enabled()) continue;
    const PronySeries series = RelaxationOf(material->viscoelastic);
    double scale = 1;
    const PronySeries kept = ReduceRelaxation(series, relaxed, frozen, &scale);
    std::string decision;
    if (kept.g.empty()) {
      decision = scale < 1 ? Format("long-term modulus (%.3g of the instantaneous)", scale)
                           : std::string("instantaneous modulus");
    } else if (kept.g.size() == series.g.size()) {
      decision = Format("all %zu relaxation terms", series.g.size());
    } else {
      decision = Format("%zu of %zu relaxation terms", kept.g.size(), series.g.size());
    }
    std::string taus;
    for (double tau : series.tau_s) taus += (taus.empty() ? "" : ", ") + ShortNumber(tau);
    decisions->push_back(
        {"viscoelasticity", where + ": " + decision,
         Format("tau = [%s] s against loading over %g s and an analysis of %g s (terms below "
                "%g s relax within the loading, above %g s not within the analysis)",
                taus.c_str(), loading, scene.analysis.time.end_time_s, relaxed, frozen),
         kept.g.size() != series.g.size()});
  }
  if (!scene.material_library.empty()) {
    // The library's materials for the built-in atlas's structures: does the
    // window reduce any of their terms?
    int reduced_terms = 0, terms = 0;
    for (const ColourEntry& entry : ColourTable::Builtin().entries()) {
      MaterialSpec material;
      if (!LibraryMaterial(scene.material_library, entry.name, &material, nullptr).ok()) continue;
      const PronySeries series = RelaxationOf(material.viscoelastic);
      double scale = 1;
      terms += static_cast<int>(series.g.size());
      reduced_terms += static_cast<int>(series.g.size() -
                                        ReduceRelaxation(series, relaxed, frozen, &scale).g.size());
    }
    decisions->push_back(
        {"viscoelasticity",
         Format("library %s: %d of its %d relaxation terms (over the structures) reduced",
                scene.material_library.c_str(), reduced_terms, terms),
         Format("terms below %g s relaxed, above %g s dropped", relaxed, frozen),
         reduced_terms > 0});
  }
}

std::string FiniteStrainRequiredBy(const SceneSpec& scene) {
  if (!scene.contacts.empty()) return "rigid contact needs the finite-strain solve";
  for (const InclusionSpec& inclusion : scene.inclusions) {
    if (inclusion.growth_strain != 0) return "growth needs the finite-strain solve";
  }
  if (scene.analysis.type == AnalysisSpec::Type::kQuasiStatic) {
    return "a history through time needs the time-stepping (finite-strain) solve";
  }
  return "";
}

SceneSpec CheapStrainScene(const SceneSpec& scene) {
  SceneSpec cheap = Coarsened(scene);
  cheap.formulation = Formulation::kAsWritten;
  cheap.analysis.type = AnalysisSpec::Type::kLinearStatic;
  cheap.mesh.element = IsHexahedral(scene.mesh.element) ? ElementType::kHex8 : ElementType::kTet10;
  cheap.contacts.clear();
  cheap.outputs = OutputSpec();
  return cheap;
}

void ReduceFiniteStrain(const SceneSpec& scene, std::optional<double> max_strain,
                        SceneSpec* reduced, std::vector<ModelDecision>* decisions) {
  if (scene.analysis.type == AnalysisSpec::Type::kLinearStatic) return;
  const std::string required = FiniteStrainRequiredBy(scene);
  if (!required.empty()) {
    decisions->push_back({"finite strain", "kept", required});
    return;
  }
  if (!max_strain) return;
  const std::string measured =
      Format("largest strain %.3g %% in a linear solve on a mesh twice as coarse (threshold %g %%)",
             100 * *max_strain, 100 * kFiniteStrainThreshold);
  if (*max_strain >= kFiniteStrainThreshold) {
    decisions->push_back({"finite strain", "kept", measured});
    return;
  }
  // The average-nodal-pressure and mean-dilatation tetrahedra have no
  // small-strain counterpart: a linear solve would change the element, and
  // with it the discretisation error, which can exceed what the strain
  // costs. Their Newton solve then takes one load increment instead.
  if (!KindOf(ResolveElement(scene.mesh.element, scene.analysis.type)).linear_static) {
    reduced->analysis.nonlinear.increments = 1;
    decisions->push_back({"finite strain",
                          "one load increment (the element has no small-strain form)", measured,
                          true});
    return;
  }
  reduced->analysis.type = AnalysisSpec::Type::kLinearStatic;
  decisions->push_back({"finite strain", "small strain (LINEAR_STATIC)", measured, true});
}

void ReduceStructures(const SceneSpec& scene, SceneSpec* reduced,
                      std::vector<ModelDecision>* decisions) {
  if (scene.geometry.kind != GeometrySpec::Kind::kAtlas) return;
  std::set<std::string> named;
  for (const std::string& name : scene.outputs.structure_displacements) {
    if (name == "*") return;  // every structure is wanted
    named.insert(name);
  }
  for (const RegionMaterialSpec& r : scene.region_materials) {
    named.insert(r.structures.begin(), r.structures.end());
  }
  // Structures the loads and contacts touch: the sets of a structure's own
  // surface ("surface:<a>") or of an interface ("interface:<a>|<b>"), and
  // the patches cut out of them.
  std::vector<std::string> sets;
  for (const BoundaryConditionSpec& bc : scene.boundary_conditions) sets.push_back(bc.set);
  for (const ContactSpec& c : scene.contacts) sets.push_back(c.set);
  for (const PatchSpec& patch : scene.geometry.patches) {
    if (std::find(sets.begin(), sets.end(), patch.name) != sets.end()) sets.push_back(patch.set);
  }
  for (const std::string& set : sets) {
    if (const std::optional<RegionSetName> parts = ParseRegionSetName(set)) {
      named.insert(parts->first);
      if (parts->interface) named.insert(parts->second);
    }
  }
  for (const InclusionSpec& inclusion : scene.inclusions) named.erase(inclusion.name);
  // Without a named structure there is nothing to keep apart: the scene
  // is left as it is (an empty list would mean every structure).
  std::vector<std::string> kept;
  if (scene.geometry.atlas.structures.empty()) {
    kept.assign(named.begin(), named.end());
  } else {
    for (const std::string& s : scene.geometry.atlas.structures) {
      if (named.count(s) > 0) kept.push_back(s);
    }
    if (kept.size() == scene.geometry.atlas.structures.size()) return;
  }
  if (kept.empty()) return;
  reduced->geometry.atlas.structures = kept;
  reduced->geometry.atlas.merge_rest = true;
  decisions->push_back(
      {"structures", Format("%zu structure(s) kept, the rest merged into one region", kept.size()),
       "the structures the outputs and materials name", true});
}

SceneSpec Coarsened(const SceneSpec& scene) {
  SceneSpec coarse = scene;
  coarse.mesh.element_size_mm = 2 * EffectiveElementSize(scene.geometry, scene.mesh);
  AtlasSpec& atlas = coarse.geometry.atlas;
  if (atlas.roi_radius_mm > 0) atlas.roi_element_size_mm *= 2;
  if (atlas.facet_size_mm > 0) atlas.facet_size_mm *= 2;
  // A side run measures the model, on the scene's own (coarsened) mesh.
  coarse.mesh.adapt = AdaptSpec();
  return coarse;
}

double LargestRelativeDifference(const Summary& reference, const Summary& other,
                                 std::string* quantity) {
  double largest = 0;
  const auto compare = [&](const std::string& name, double a, double b, double scale) {
    const double d = std::abs(a - b) / std::max(scale, 1e-300);
    if (d > largest) largest = d, *quantity = name;
  };
  const auto norm = [](const std::array<double, 3>& v) {
    return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  };
  compare("largest displacement", reference.max_displacement_mm, other.max_displacement_mm,
          std::abs(reference.max_displacement_mm));
  for (const Reaction& r : reference.reactions) {
    for (const Reaction& o : other.reactions) {
      if (o.set != r.set) continue;
      double d = 0;
      for (int c = 0; c < 3; ++c)
        d += (r.force_n[c] - o.force_n[c]) * (r.force_n[c] - o.force_n[c]);
      compare("reaction on " + r.set, 0, std::sqrt(d), norm(r.force_n));
    }
  }
  for (const ContactSummary& r : reference.contacts) {
    for (const ContactSummary& o : other.contacts) {
      if (o.name == r.name)
        compare("force on " + r.name, norm(r.force_n), norm(o.force_n), norm(r.force_n));
    }
  }
  for (const StructureDisplacement& r : reference.structure_displacements) {
    for (const StructureDisplacement& o : other.structure_displacements) {
      if (o.name != r.name) continue;
      double d = 0;
      for (int c = 0; c < 3; ++c)
        d += (r.mean_mm[c] - o.mean_mm[c]) * (r.mean_mm[c] - o.mean_mm[c]);
      compare("mean displacement of " + r.name, 0, std::sqrt(d), norm(r.mean_mm));
    }
  }
  return largest;
}

}  // namespace pba
