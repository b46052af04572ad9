// Derived structures: a structure of a structure set (and of the atlas
// store, where it is versioned, locked and pinned by snapshots like any
// other) that has no geometry of its own. It is one label step over the
// others, done when the set is composed into voxels
// (ComposeStructureSet), so it follows every edit of the structures it is
// made from:
//
//   merge: [Caudate, Putamen]           the union of structures, as one
//                                       (they are no longer separate)
//   merge: {structures: [...]}
//   fill: {closing_mm: 4, min_piece_mm3: 1000}
//                                       the background the others enclose
//                                       (AAL's white matter); fill: {} too
//   cut: {sphere: {centre_mm: [x, y, z], radius_mm: 10}, structures: [...]}
//   cut: {cylinder: {from_mm: [..], to_mm: [..], radius_mm: 5}}
//   cut: {around: {structures: [Tumour], margin_mm: 3}}
//                                       a region taken out of structures
//                                       (all, or those named): a resection
//                                       cavity, which is this structure
//
// The file is that YAML (or JSON) map with one key; the step's new name is
// the structure's own, so the recipe names none. A cut reads no mask file:
// a derived structure is made from the set alone.
//
// Order: every merge first, then every fill, then every cut, each by name;
// a structure a derived one reads is a structure of the set (or a group of
// them, "Thalamus"), or a derived structure done before it, and not one a
// merge took (it is gone by then).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "atlas/label_algebra.h"
#include "pba/status.h"

namespace pba {

struct DerivedStructure {
  std::string name;
  LabelStep step;
  std::string field;  // where it was given, for messages ("structures[3]")
};

// Parses a derived structure's recipe; the step's name is `name`, and
// `field` is kept in the result.
// kInvalidArgument on `field` naming what is wrong: not one of merge,
// fill or cut, a `name` key, a mask file, an unknown key.
Status ParseDerivedStructure(std::string_view yaml, const std::string& name,
                             const std::string& field, DerivedStructure* derived);

// The structures (or groups) the step reads: a merge's, a cut's and its
// `around` region's. A fill reads the whole atlas and names none.
std::vector<std::string> DerivedSources(const LabelStep& step);

// Sorts `derived` into the order they are done (above) and checks that
// every structure each reads is there at its turn: one of `base` (the set's
// other structures, or a group of them) or a derived structure done
// earlier, and not one a merge took. kInvalidArgument on the structure's
// field naming it and why.
Status OrderDerivedStructures(const std::vector<std::string>& base,
                              std::vector<DerivedStructure>* derived);

// The structure names an atlas has after `step`, given those it had (for
// checking a scene's names before it is meshed): keep, drop, merge and
// rename change them, fill and a named cut add one; the others leave
// them, an overlay included (its table's names are the caller's to add).
std::vector<std::string> NamesAfterStep(const LabelStep& step, std::vector<std::string> names);

}  // namespace pba
