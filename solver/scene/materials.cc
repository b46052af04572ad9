#include "scene/materials.h"

#include <algorithm>
#include <map>

#include "core/format.h"
#include "material/factory.h"
#include "material/tissue_library.h"

namespace pba {

Status CutInclusions(const SceneSpec& scene, Mesh* mesh) {
  if (scene.inclusions.empty()) return Status::Ok();
  constexpr double kMm = 1e-3;
  const int ne = mesh->num_elements();
  if (mesh->element_region.empty()) {
    mesh->region_names = {"body"};
    mesh->element_region.assign(ne, 0);
  }
  for (std::size_t i = 0; i < scene.inclusions.size(); ++i) {
    const InclusionSpec& inclusion = scene.inclusions[i];
    const Eigen::Vector3d centre = Eigen::Vector3d(inclusion.centre_mm.data()) * kMm;
    const double radius = inclusion.radius_mm * kMm;
    const int region = static_cast<int>(mesh->region_names.size());
    int count = 0;
    for (int e = 0; e < ne; ++e) {
      // The mean of the corners (of a 10-node element's too).
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      const NodeList corners = mesh->ElementCorners(e);
      for (int a : corners) centroid += mesh->nodes.row(a).transpose() / corners.size();
      if ((centroid - centre).norm() <= radius) {
        mesh->element_region[e] = region;
        ++count;
      }
    }
    if (count == 0) {
      return Status::InvalidArgument(
          "inclusions[" + std::to_string(i) + "]",
          Format("the ball of radius %g mm around (%g, %g, %g) mm holds no element's centre; "
                 "make it larger than the elements or move it inside the body",
                 inclusion.radius_mm, inclusion.centre_mm[0], inclusion.centre_mm[1],
                 inclusion.centre_mm[2]));
    }
    mesh->region_names.push_back(inclusion.name);
  }
  return Status::Ok();
}

Status ResolveMaterials(const SceneSpec& scene, const Mesh& mesh, SceneMaterials* out) {
  *out = SceneMaterials();
  out->specs.push_back(scene.material);
  out->labels.push_back(scene.material.name.empty() ? "material" : scene.material.name);
  out->growth_strain.push_back(0);
  const int ne = mesh.num_elements();
  out->of_element.assign(ne, 0);
  if (mesh.region_names.empty()) return Status::Ok();

  // Region material entries by structure name.
  std::map<std::string, int> region_entry;
  for (std::size_t i = 0; i < scene.region_materials.size(); ++i) {
    const auto& structures = scene.region_materials[i].structures;
    for (std::size_t j = 0; j < structures.size(); ++j) {
      if (std::find(mesh.region_names.begin(), mesh.region_names.end(), structures[j]) ==
          mesh.region_names.end()) {
        return Status::InvalidArgument(
            Format("region_materials[%zu].structures[%zu]", i, j),
            "the model has no structure named \"" + structures[j] +
                "\" (names as in the atlas's colour table, among the structures the scene keeps)");
      }
      region_entry[structures[j]] = static_cast<int>(i);
    }
  }
  std::map<std::string, int> inclusion_entry;
  for (std::size_t i = 0; i < scene.inclusions.size(); ++i) {
    inclusion_entry[scene.inclusions[i].name] = static_cast<int>(i);
  }

  // The spec index of each region; equal specs share an entry only when they
  // come from the same source (a library entry, a region_materials entry).
  std::map<std::string, int> by_source;
  std::vector<int> of_region(mesh.region_names.size(), 0);
  for (std::size_t r = 0; r < mesh.region_names.size(); ++r) {
    const std::string& name = mesh.region_names[r];
    MaterialSpec spec;
    double growth = 0;
    std::string source, label;
    if (const auto it = inclusion_entry.find(name); it != inclusion_entry.end()) {
      const InclusionSpec& inclusion = scene.inclusions[it->second];
      spec = inclusion.material;
      growth = inclusion.growth_strain;
      source = "inclusion:" + name;
      label = name + ": inclusion";
    } else if (const auto at = region_entry.find(name); at != region_entry.end()) {
      spec = scene.region_materials[at->second].material;
      source = Format("region_materials[%d]", at->second);
      label = name + ": " + source;
    } else if (!scene.material_library.empty()) {
      std::string citation;
      const Status found = LibraryMaterial(scene.material_library, name, &spec, &citation);
      if (found.code() == Status::Code::kNotFound) continue;  // the scene's material
      PBA_RETURN_IF_ERROR(found);
      source = "library:" + scene.material_library + ":" + spec.name;
      label = name + ": " + scene.material_library + " (" + citation + ")";
    } else {
      continue;
    }
    auto [it, added] = by_source.emplace(source, static_cast<int>(out->specs.size()));
    if (added) {
      out->specs.push_back(spec);
      out->labels.push_back(label);
      out->growth_strain.push_back(growth);
    }
    of_region[r] = it->second;
  }
  for (int e = 0; e < ne; ++e) out->of_element[e] = of_region[mesh.element_region[e]];

  // One note per material beyond the scene's, with the structures it fills.
  for (std::size_t k = 1; k < out->specs.size(); ++k) {
    std::vector<std::string> users;
    for (std::size_t r = 0; r < mesh.region_names.size(); ++r) {
      if (of_region[r] == static_cast<int>(k)) users.push_back(mesh.region_names[r]);
    }
    std::string list;
    for (std::size_t i = 0; i < users.size() && i < 6; ++i) list += (i ? ", " : "") + users[i];
    if (users.size() > 6) list += Format(" and %zu more", users.size() - 6);
    out->notes.push_back("material of " + list + ": " + DescribeMaterial(out->specs[k]) +
                         (out->growth_strain[k] != 0
                              ? Format(", growing by a strain of %g", out->growth_strain[k])
                              : std::string()));
  }
  return Status::Ok();
}

ElasticityField MakeElasticityField(const SceneMaterials& materials) {
  std::vector<Matrix6d> d, compliance;
  for (const MaterialSpec& spec : materials.specs) {
    d.push_back(ElasticityMatrix(spec));
    compliance.push_back(ComplianceMatrix(spec));
  }
  return ElasticityField(std::move(d), std::move(compliance), materials.of_element);
}

PronySeries RelaxationOf(const ViscoelasticSpec& spec) {
  switch (spec.form) {
    case ViscoelasticSpec::Form::kProny:
      return PronySeries{spec.g, spec.tau_s};
    case ViscoelasticSpec::Form::kExponential:
      return FromExponential(spec.long_term_ratio, spec.beta_per_s);
    case ViscoelasticSpec::Form::kModuli:
      return FromModuli(spec.long_term_modulus_pa, spec.moduli_pa, spec.tau_s);
    case ViscoelasticSpec::Form::kNone:
      break;
  }
  return PronySeries();
}

std::unique_ptr<MaterialField> MakeMaterialField(const SceneMaterials& materials,
                                                 double relaxed_below_s, double frozen_above_s,
                                                 const ThreadContext& threads) {
  std::vector<MaterialField::Entry> entries;
  for (std::size_t k = 0; k < materials.specs.size(); ++k) {
    MaterialField::Entry entry;
    entry.material = MakeHyperelasticMaterial(materials.specs[k]);
    entry.relaxation = ReduceRelaxation(RelaxationOf(materials.specs[k].viscoelastic),
                                        relaxed_below_s, frozen_above_s, &entry.isochoric_scale);
    entry.growth_strain = materials.growth_strain[k];
    entry.name = materials.labels[k];
    entries.push_back(std::move(entry));
  }
  return std::make_unique<MaterialField>(std::move(entries), materials.of_element, threads);
}

}  // namespace pba
