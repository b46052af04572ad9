// Label algebra steps as YAML (ParseLabelSteps, and one step as a derived
// structure's recipe: ParseDerivedStructure) and as a cache key's canonical
// text (DescribeLabelSteps, LabelStepFiles): label_algebra.h,
// derived_structure.h.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>

#include "atlas/derived_structure.h"
#include "atlas/label_algebra.h"
#include "atlas/label_table.h"
#include "core/format.h"
#include "core/yaml_guard.h"

namespace pba {
namespace {

using Keys = std::initializer_list<const char*>;

// A map node whose keys are all among `allowed` and that has every one of
// `required`.
Status CheckMap(const YAML::Node& node, const std::string& field, Keys allowed, Keys required) {
  if (!node.IsMap()) return Status::InvalidArgument(field, "expected a map");
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    if (std::none_of(allowed.begin(), allowed.end(), [&](const char* a) { return key == a; })) {
      std::string known;
      for (const char* a : allowed) known += (known.empty() ? "" : ", ") + std::string(a);
      return Status::InvalidArgument(field + "." + key, "unknown key (known: " + known + ")");
    }
  }
  for (const char* key : required) {
    if (!node[key]) return Status::InvalidArgument(field + "." + key, "is required");
  }
  return Status::Ok();
}

Status ReadText(const YAML::Node& node, const std::string& field, std::string* out) {
  if (!node.IsScalar() || node.Scalar().empty()) {
    return Status::InvalidArgument(field, "expected a non-empty string");
  }
  *out = node.Scalar();
  return Status::Ok();
}

Status ReadNames(const YAML::Node& node, const std::string& field, std::vector<std::string>* out) {
  out->clear();
  if (node.IsScalar()) return ReadText(node, field, &out->emplace_back());
  if (!node.IsSequence() || node.size() == 0) {
    return Status::InvalidArgument(field, "expected a structure name or a list of them");
  }
  for (std::size_t i = 0; i < node.size(); ++i) {
    PBA_RETURN_IF_ERROR(
        ReadText(node[i], Format("%s[%zu]", field.c_str(), i), &out->emplace_back()));
  }
  return Status::Ok();
}

Status ReadNumber(const YAML::Node& node, const std::string& field, double* out) {
  if (!node.IsScalar() || node.Tag() == "!" || !YAML::convert<double>::decode(node, *out) ||
      !std::isfinite(*out)) {
    return Status::InvalidArgument(field, "expected a number");
  }
  return Status::Ok();
}

Status ReadPoint(const YAML::Node& node, const std::string& field, Eigen::Vector3d* out) {
  if (!node.IsSequence() || node.size() != 3) {
    return Status::InvalidArgument(field, "expected [x, y, z] in mm");
  }
  for (int a = 0; a < 3; ++a) {
    PBA_RETURN_IF_ERROR(ReadNumber(node[a], Format("%s[%d]", field.c_str(), a), &(*out)[a]));
  }
  return Status::Ok();
}

Status ReadPath(const YAML::Node& node, const std::string& field,
                const std::filesystem::path& base_dir, std::filesystem::path* out) {
  std::string text;
  PBA_RETURN_IF_ERROR(ReadText(node, field, &text));
  const std::filesystem::path path(text);
  *out = path.is_absolute() ? path : base_dir / path;
  return Status::Ok();
}

Status ParseRegion(const YAML::Node& m, const std::string& at, const std::filesystem::path& base,
                   LabelRegion* r) {
  int given = 0;
  if (const YAML::Node s = m["sphere"]) {
    ++given;
    r->kind = LabelRegion::Kind::kSphere;
    PBA_RETURN_IF_ERROR(
        CheckMap(s, at + ".sphere", {"centre_mm", "radius_mm"}, {"centre_mm", "radius_mm"}));
    PBA_RETURN_IF_ERROR(ReadPoint(s["centre_mm"], at + ".sphere.centre_mm", &r->centre_mm));
    PBA_RETURN_IF_ERROR(ReadNumber(s["radius_mm"], at + ".sphere.radius_mm", &r->radius_mm));
  }
  if (const YAML::Node c = m["cylinder"]) {
    ++given;
    r->kind = LabelRegion::Kind::kCylinder;
    PBA_RETURN_IF_ERROR(CheckMap(c, at + ".cylinder", {"from_mm", "to_mm", "radius_mm"},
                                 {"from_mm", "to_mm", "radius_mm"}));
    PBA_RETURN_IF_ERROR(ReadPoint(c["from_mm"], at + ".cylinder.from_mm", &r->centre_mm));
    PBA_RETURN_IF_ERROR(ReadPoint(c["to_mm"], at + ".cylinder.to_mm", &r->end_mm));
    PBA_RETURN_IF_ERROR(ReadNumber(c["radius_mm"], at + ".cylinder.radius_mm", &r->radius_mm));
  }
  if (const YAML::Node mask = m["mask"]) {
    ++given;
    r->kind = LabelRegion::Kind::kMask;
    PBA_RETURN_IF_ERROR(ReadPath(mask, at + ".mask", base, &r->mask));
  }
  if (const YAML::Node around = m["around"]) {
    ++given;
    r->kind = LabelRegion::Kind::kStructures;
    PBA_RETURN_IF_ERROR(
        CheckMap(around, at + ".around", {"structures", "margin_mm"}, {"structures"}));
    PBA_RETURN_IF_ERROR(ReadNames(around["structures"], at + ".around.structures", &r->structures));
    if (around["margin_mm"]) {
      PBA_RETURN_IF_ERROR(ReadNumber(around["margin_mm"], at + ".around.margin_mm", &r->margin_mm));
    }
  }
  if (given != 1) {
    return Status::InvalidArgument(at, "give exactly one region: sphere, cylinder, mask or around");
  }
  return Status::Ok();
}

Status ParseStepKeys(const YAML::Node& node, const std::string& at,
                     const std::filesystem::path& base, LabelStep* step) {
  if (!node.IsMap() || node.size() != 1) {
    return Status::InvalidArgument(
        at,
        "expected one step: keep, drop, merge, rename, fill, overlay, resample, cut or islands");
  }
  const std::string kind = node.begin()->first.as<std::string>();
  const YAML::Node m = node.begin()->second;
  const std::string in = at + "." + kind;
  if (kind == "keep" || kind == "drop") {
    step->kind = kind == "keep" ? LabelStep::Kind::kKeep : LabelStep::Kind::kDrop;
    if (m.IsMap()) {  // {structures: [...]}, as a scene writes it
      PBA_RETURN_IF_ERROR(CheckMap(m, in, {"structures"}, {"structures"}));
      return ReadNames(m["structures"], in + ".structures", &step->structures);
    }
    return ReadNames(m, in, &step->structures);
  }
  if (kind == "merge") {
    step->kind = LabelStep::Kind::kMerge;
    PBA_RETURN_IF_ERROR(CheckMap(m, in, {"structures", "name"}, {"structures", "name"}));
    PBA_RETURN_IF_ERROR(ReadNames(m["structures"], in + ".structures", &step->structures));
    return ReadText(m["name"], in + ".name", &step->name);
  }
  if (kind == "rename") {
    step->kind = LabelStep::Kind::kRename;
    PBA_RETURN_IF_ERROR(CheckMap(m, in, {"from", "to"}, {"from", "to"}));
    PBA_RETURN_IF_ERROR(ReadText(m["from"], in + ".from", &step->from));
    return ReadText(m["to"], in + ".to", &step->name);
  }
  if (kind == "fill") {
    step->kind = LabelStep::Kind::kFill;
    PBA_RETURN_IF_ERROR(CheckMap(m, in, {"name", "closing_mm", "min_piece_mm3"}, {"name"}));
    PBA_RETURN_IF_ERROR(ReadText(m["name"], in + ".name", &step->name));
    if (m["closing_mm"])
      PBA_RETURN_IF_ERROR(ReadNumber(m["closing_mm"], in + ".closing_mm", &step->closing_mm));
    if (m["min_piece_mm3"]) {
      PBA_RETURN_IF_ERROR(
          ReadNumber(m["min_piece_mm3"], in + ".min_piece_mm3", &step->min_piece_mm3));
    }
    return Status::Ok();
  }
  if (kind == "overlay") {
    step->kind = LabelStep::Kind::kOverlay;
    PBA_RETURN_IF_ERROR(
        CheckMap(m, in, {"volume", "table", "structures", "under"}, {"volume", "table"}));
    PBA_RETURN_IF_ERROR(ReadPath(m["volume"], in + ".volume", base, &step->volume));
    PBA_RETURN_IF_ERROR(ReadPath(m["table"], in + ".table", base, &step->table));
    if (m["structures"])
      PBA_RETURN_IF_ERROR(ReadNames(m["structures"], in + ".structures", &step->structures));
    if (const YAML::Node under = m["under"]) {
      if (!under.IsScalar() || !YAML::convert<bool>::decode(under, step->under)) {
        return Status::InvalidArgument(in + ".under", "expected true or false");
      }
    }
    return Status::Ok();
  }
  if (kind == "resample") {
    step->kind = LabelStep::Kind::kResample;
    PBA_RETURN_IF_ERROR(CheckMap(m, in, {"voxel_mm"}, {"voxel_mm"}));
    return ReadNumber(m["voxel_mm"], in + ".voxel_mm", &step->voxel_mm);
  }
  if (kind == "islands") {
    step->kind = LabelStep::Kind::kIslands;
    PBA_RETURN_IF_ERROR(CheckMap(m, in, {"min_piece_mm3"}, {"min_piece_mm3"}));
    return ReadNumber(m["min_piece_mm3"], in + ".min_piece_mm3", &step->min_piece_mm3);
  }
  if (kind == "cut") {
    step->kind = LabelStep::Kind::kCut;
    PBA_RETURN_IF_ERROR(
        CheckMap(m, in, {"sphere", "cylinder", "mask", "around", "structures", "name"}, {}));
    PBA_RETURN_IF_ERROR(ParseRegion(m, in, base, &step->region));
    if (m["structures"])
      PBA_RETURN_IF_ERROR(ReadNames(m["structures"], in + ".structures", &step->structures));
    if (m["name"]) PBA_RETURN_IF_ERROR(ReadText(m["name"], in + ".name", &step->name));
    return Status::Ok();
  }
  return Status::InvalidArgument(
      at + "." + kind,
      "unknown step (known: keep, drop, merge, rename, fill, overlay, resample, cut, islands)");
}

// A step read and its values checked (CheckLabelStep).
Status ParseStep(const YAML::Node& node, const std::string& at, const std::filesystem::path& base,
                 LabelStep* step) {
  PBA_RETURN_IF_ERROR(ParseStepKeys(node, at, base, step));
  return CheckLabelStep(*step, at + "." + LabelStepName(step->kind));
}

// `yaml` loaded, once checked for what a YAML load must not meet
// (core/yaml_guard.h).
Status LoadYaml(std::string_view yaml, const std::string& field, YAML::Node* root) {
  PBA_RETURN_IF_ERROR(CheckYamlText(yaml, field));
  try {
    *root = YAML::Load(std::string(yaml));
  } catch (const YAML::Exception& e) {
    return Status::InvalidArgument(field, std::string("is not valid YAML: ") + e.what());
  }
  return Status::Ok();
}

std::string Names(const std::vector<std::string>& names) {
  std::string out = Format("%zu", names.size());
  for (const std::string& n : names) out += Format(" %zu:", n.size()) + n;
  return out;
}

Status ParseDerivedStep(const YAML::Node& root, const std::string& name, const std::string& field,
                        DerivedStructure* derived) {
  const std::string kind = root.begin()->first.as<std::string>();
  if (kind != "merge" && kind != "fill" && kind != "cut") {
    return Status::InvalidArgument(field + "." + kind,
                                   "a derived structure is made by merge, fill or cut");
  }
  const std::string in = field + "." + kind;
  // The step as label algebra writes it, with the structure's name. (A
  // node assigned to changes every node that shares it: each is made once.)
  const YAML::Node given = root.begin()->second;
  const bool short_merge = kind == "merge" && (given.IsSequence() || given.IsScalar());
  if (!given.IsNull() && !given.IsMap() && !short_merge) {
    return Status::InvalidArgument(in, "expected a map");
  }
  YAML::Node m = given.IsMap() ? YAML::Clone(given) : YAML::Node(YAML::NodeType::Map);
  if (short_merge) m["structures"] = YAML::Clone(given);
  if (m["name"]) {
    return Status::InvalidArgument(in + ".name",
                                   "a derived structure's step takes the structure's own name");
  }
  if (m["mask"]) {
    return Status::InvalidArgument(
        in + ".mask", "a derived structure is made from the set alone; it reads no mask file");
  }
  m["name"] = name;
  YAML::Node step(YAML::NodeType::Map);
  step[kind] = m;
  DerivedStructure out;
  out.name = name;
  out.field = field;
  PBA_RETURN_IF_ERROR(ParseStep(step, field, {}, &out.step));
  *derived = std::move(out);
  return Status::Ok();
}

}  // namespace

Status ParseLabelSteps(std::string_view yaml, const std::string& field,
                       const std::filesystem::path& base_dir, std::vector<LabelStep>* steps) {
  YAML::Node root;
  PBA_RETURN_IF_ERROR(LoadYaml(yaml, field, &root));
  if (!root.IsSequence()) {
    return Status::InvalidArgument(field,
                                   "expected a list of steps (- keep: [...], - fill: {...})");
  }
  std::vector<LabelStep> out(root.size());
  try {  // a key that is not text (a list, a map) throws
    for (std::size_t i = 0; i < root.size(); ++i) {
      PBA_RETURN_IF_ERROR(
          ParseStep(root[i], Format("%s[%zu]", field.c_str(), i), base_dir, &out[i]));
    }
  } catch (const YAML::Exception& e) {
    return Status::InvalidArgument(field, std::string("malformed: ") + e.what());
  }
  *steps = std::move(out);
  return Status::Ok();
}

Status ParseDerivedStructure(std::string_view yaml, const std::string& name,
                             const std::string& field, DerivedStructure* derived) {
  YAML::Node root;
  PBA_RETURN_IF_ERROR(LoadYaml(yaml, field, &root));
  if (!root.IsMap() || root.size() != 1) {
    return Status::InvalidArgument(
        field, "expected one step a derived structure is made by: merge, fill or cut");
  }
  try {  // a key that is not text (a list, a map) throws
    return ParseDerivedStep(root, name, field, derived);
  } catch (const YAML::Exception& e) {
    return Status::InvalidArgument(field, std::string("malformed: ") + e.what());
  }
}

std::string DescribeLabelSteps(const std::vector<LabelStep>& steps) {
  std::string text = Format("label steps %zu\n", steps.size());
  for (const LabelStep& s : steps) {
    const LabelRegion& r = s.region;
    // %.17g: the numbers exactly; names length-prefixed.
    text += Format(
        "%s structures %s name %zu:%s from %zu:%s closing %.17g min %.17g under %d "
        "voxel %.17g volume %zu:%s table %zu:%s",
        LabelStepName(s.kind), Names(s.structures).c_str(), s.name.size(), s.name.c_str(),
        s.from.size(), s.from.c_str(), s.closing_mm, s.min_piece_mm3, s.under ? 1 : 0, s.voxel_mm,
        s.volume.string().size(), s.volume.c_str(), s.table.string().size(), s.table.c_str());
    if (s.kind == LabelStep::Kind::kCut) {
      text +=
          Format(" region %d %.17g %.17g %.17g %.17g %.17g %.17g %.17g mask %zu:%s around %s %.17g",
                 static_cast<int>(r.kind), r.centre_mm.x(), r.centre_mm.y(), r.centre_mm.z(),
                 r.end_mm.x(), r.end_mm.y(), r.end_mm.z(), r.radius_mm, r.mask.string().size(),
                 r.mask.c_str(), Names(r.structures).c_str(), r.margin_mm);
    }
    text += "\n";
  }
  return text;
}

std::vector<std::filesystem::path> LabelStepFiles(const std::vector<LabelStep>& steps) {
  std::vector<std::filesystem::path> files;
  for (const LabelStep& s : steps) {
    if (s.kind == LabelStep::Kind::kOverlay) {
      files.push_back(s.volume);
      for (const std::filesystem::path& f : LabelTableFiles(s.table)) files.push_back(f);
    }
    if (s.kind == LabelStep::Kind::kCut && s.region.kind == LabelRegion::Kind::kMask) {
      files.push_back(s.region.mask);
    }
  }
  return files;
}

}  // namespace pba
