// Derived structures' order and checks, and the names label steps leave
// (derived_structure.h). The recipe's YAML is read in label_steps_yaml.cc.
#include "atlas/derived_structure.h"

#include <algorithm>
#include <map>

#include "atlas/colour_table.h"

namespace pba {
namespace {

// Merges first, then fills, then cuts.
int Rank(LabelStep::Kind kind) {
  switch (kind) {
    case LabelStep::Kind::kMerge:
      return 0;
    case LabelStep::Kind::kFill:
      return 1;
    default:
      return 2;
  }
}

// Whether the structure `name` is `named` or in the group `named`.
bool Matches(const std::string& name, const std::string& named) {
  return name == named || InStructureGroup(name, named);
}

// Whether the structure `name` is one of `named` or in one of their groups.
bool NamedIn(const std::vector<std::string>& named, const std::string& name) {
  return std::any_of(named.begin(), named.end(),
                     [&](const std::string& g) { return Matches(name, g); });
}

// Whether `named` is one of `names` or a group of some of them.
bool Names(const std::vector<std::string>& names, const std::string& named) {
  return std::any_of(names.begin(), names.end(),
                     [&](const std::string& n) { return Matches(n, named); });
}

// `names` without those in `named` (names or groups).
std::vector<std::string> Without(std::vector<std::string> names,
                                 const std::vector<std::string>& named) {
  names.erase(std::remove_if(names.begin(), names.end(),
                             [&](const std::string& n) { return NamedIn(named, n); }),
              names.end());
  return names;
}

}  // namespace

std::vector<std::string> DerivedSources(const LabelStep& step) {
  std::vector<std::string> sources = step.structures;
  if (step.kind == LabelStep::Kind::kCut && step.region.kind == LabelRegion::Kind::kStructures) {
    sources.insert(sources.end(), step.region.structures.begin(), step.region.structures.end());
  }
  return sources;
}

Status OrderDerivedStructures(const std::vector<std::string>& base,
                              std::vector<DerivedStructure>* derived) {
  std::vector<size_t> order(derived->size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    const DerivedStructure& x = (*derived)[a];
    const DerivedStructure& y = (*derived)[b];
    const int rx = Rank(x.step.kind), ry = Rank(y.step.kind);
    return rx != ry ? rx < ry : x.name < y.name;
  });
  // The names there at each turn, and who took the ones merges took.
  std::vector<std::string> names = base;
  std::map<std::string, std::string> taken_by;
  for (size_t i : order) {
    const DerivedStructure& d = (*derived)[i];
    const std::string& at = d.field;
    if (Names(base, d.name)) {
      return Status::InvalidArgument(
          at, "derived structure '" + d.name + "' has the name of another structure");
    }
    for (const std::string& source : DerivedSources(d.step)) {
      if (source == d.name) {
        return Status::InvalidArgument(at, "derived structure '" + d.name + "' reads itself");
      }
      if (Names(names, source)) continue;
      if (const auto it = taken_by.find(source); it != taken_by.end()) {
        return Status::InvalidArgument(at, "derived structure '" + d.name + "' reads '" + source +
                                               "', which the merge '" + it->second +
                                               "' takes before it");
      }
      const bool later = std::any_of(derived->begin(), derived->end(),
                                     [&](const DerivedStructure& o) { return o.name == source; });
      return Status::InvalidArgument(
          at, "derived structure '" + d.name + "' reads '" + source + "', " +
                  (later ? "a derived structure made after it (merges come first, then fills, "
                           "then cuts)"
                         : "which is not among the structures"));
    }
    if (d.step.kind == LabelStep::Kind::kMerge) {
      for (const std::string& n : names) {
        if (NamedIn(d.step.structures, n)) taken_by.emplace(n, d.name);
      }
      for (const std::string& s : d.step.structures) taken_by.emplace(s, d.name);
    }
    names = NamesAfterStep(d.step, std::move(names));
  }
  std::vector<DerivedStructure> sorted;
  sorted.reserve(order.size());
  for (size_t i : order) sorted.push_back(std::move((*derived)[i]));
  *derived = std::move(sorted);
  return Status::Ok();
}

std::vector<std::string> NamesAfterStep(const LabelStep& step, std::vector<std::string> names) {
  switch (step.kind) {
    case LabelStep::Kind::kKeep: {
      std::vector<std::string> kept;
      for (const std::string& n : names) {
        if (NamedIn(step.structures, n)) kept.push_back(n);
      }
      return kept;
    }
    case LabelStep::Kind::kDrop:
      return Without(std::move(names), step.structures);
    case LabelStep::Kind::kMerge:
      names = Without(std::move(names), step.structures);
      names.push_back(step.name);
      return names;
    case LabelStep::Kind::kRename:
      for (std::string& n : names) {
        if (n == step.from) n = step.name;
      }
      return names;
    case LabelStep::Kind::kFill:
    case LabelStep::Kind::kCut:
      if (!step.name.empty() && std::find(names.begin(), names.end(), step.name) == names.end()) {
        names.push_back(step.name);
      }
      return names;
    default:
      return names;
  }
}

}  // namespace pba
