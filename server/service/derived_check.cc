#include "service/derived_check.h"

#include <string>
#include <vector>

#include "atlas/derived_structure.h"
#include "core/yaml_guard.h"

namespace pba {
namespace {

// A head's recipe, read and parsed (a derived blob passed the commit check,
// so it is small YAML).
Status ReadRecipe(const SnapshotFile& file, DerivedStructure* derived) {
  std::string text;
  Status read = ReadYamlFileText(file.blob, "structure '" + file.revision.structure + "'", &text);
  if (read.ok()) {
    read = ParseDerivedStructure(text, file.revision.structure,
                                 "structure '" + file.revision.structure + "'", derived);
  }
  return read;
}

}  // namespace

Status CheckDerivedStructure(AtlasStore& store, const std::string& user, const StructureRef& ref,
                             StructureFormat format, std::string_view content,
                             const std::string& field) {
  if (format != StructureFormat::kDerived) return Status::Ok();
  std::vector<DerivedStructure> derived(1);
  PBA_RETURN_IF_ERROR(ParseDerivedStructure(content, ref.structure, field, &derived[0]));
  std::vector<SnapshotFile> heads;
  PBA_RETURN_IF_ERROR(store.Heads(user, ref.project, &heads));
  std::vector<std::string> base;
  for (const SnapshotFile& head : heads) {
    if (head.revision.structure == ref.structure) continue;
    if (head.revision.format != StructureFormat::kDerived) {
      base.push_back(head.revision.structure);
      continue;
    }
    DerivedStructure other;
    if (Status s = ReadRecipe(head, &other); !s.ok()) {
      return Status::Internal("the recipe of derived structure '" + head.revision.structure +
                              "' cannot be read: " + s.message());
    }
    derived.push_back(std::move(other));
  }
  return OrderDerivedStructures(base, &derived);
}

}  // namespace pba
