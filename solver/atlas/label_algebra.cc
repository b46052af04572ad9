#include "atlas/label_algebra.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>

#include "atlas/distance_transform.h"
#include "atlas/label_table.h"
#include "atlas/label_volume_io.h"
#include "core/format.h"

namespace pba {
namespace {

constexpr double kMm3PerCm3 = 1000;

// The labels `names` stand for (a name, or a group: EntriesNamed), sorted
// and without repeats; empty names: none.
Status LabelsNamed(const ColourTable& table, const std::vector<std::string>& names,
                   const std::string& field, std::vector<uint16_t>* labels) {
  std::set<uint16_t> found;
  for (const std::string& name : names) {
    std::vector<const ColourEntry*> entries;
    PBA_RETURN_IF_ERROR(EntriesNamed(table, name, field, &entries));
    for (const ColourEntry* e : entries) found.insert(e->label);
  }
  labels->assign(found.begin(), found.end());
  return Status::Ok();
}

// A 65,536-entry membership table of `labels`.
std::vector<uint8_t> LabelSet(const std::vector<uint16_t>& labels) {
  std::vector<uint8_t> in(65536, 0);
  for (uint16_t l : labels) in[l] = 1;
  return in;
}

// The table without the entries whose labels are in `gone`, plus `added`.
Status Retable(const ColourTable& table, const std::vector<uint8_t>& gone,
               std::vector<ColourEntry> added, ColourTable* out) {
  std::vector<ColourEntry> entries;
  for (const ColourEntry& e : table.entries()) {
    if (!gone[e.label]) entries.push_back(e);
  }
  for (ColourEntry& e : added) entries.push_back(std::move(e));
  return ColourTable::FromEntries(std::move(entries), out);
}

// The lowest label no entry of `table` has; 0 when all 65,535 are taken.
uint16_t FreeLabel(const ColourTable& table) {
  std::vector<uint8_t> used = LabelSet({});
  for (const ColourEntry& e : table.entries()) used[e.label] = 1;
  for (int l = 1; l < 65536; ++l) {
    if (!used[l]) return static_cast<uint16_t>(l);
  }
  return 0;
}

// A new structure's entry: `name` (not in the table) under a free label,
// with a display colour of its own.
Status NewEntry(const ColourTable& table, const std::string& name, const std::string& field,
                ColourEntry* entry) {
  if (name.empty()) return Status::InvalidArgument(field, "the new structure needs a name");
  if (table.FindByName(name) != nullptr) {
    return Status::InvalidArgument(field, "the atlas already has a structure \"" + name + "\"");
  }
  entry->label = FreeLabel(table);
  if (entry->label == 0) {
    return Status::InvalidArgument(field, "every label 1..65535 is taken");
  }
  entry->name = name;
  ChooseDisplayColour(table, entry);
  return Status::Ok();
}

std::string Volume(int64_t voxels, const LabelVolume& volume) {
  return Format("%lld voxels, %.2f cm^3", static_cast<long long>(voxels),
                voxels * volume.voxel_volume_mm3() / kMm3PerCm3);
}

// Relabels every voxel whose label `map` sends elsewhere; the count changed.
int64_t Relabel(const std::vector<uint16_t>& map, LabelVolume* volume) {
  int64_t changed = 0;
  for (uint16_t& l : volume->mutable_labels()) {
    if (map[l] != l) {
      l = map[l];
      ++changed;
    }
  }
  return changed;
}

std::vector<uint16_t> IdentityMap() {
  std::vector<uint16_t> map(65536);
  for (int l = 0; l < 65536; ++l) map[l] = static_cast<uint16_t>(l);
  return map;
}

std::string NameList(const ColourTable& table, const std::vector<uint16_t>& labels) {
  std::string out;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (i == 6) return out + Format(" and %zu more", labels.size() - i);
    out += (i > 0 ? ", " : "") + table.FindByLabel(labels[i])->name;
  }
  return out;
}

// The structures with the most voxels in `counts` (per label), largest
// first, at most three, with their volumes.
std::string LargestShares(const ColourTable& table, const std::vector<int64_t>& counts,
                          const LabelVolume& volume) {
  std::vector<std::pair<int64_t, uint16_t>> order;
  for (const ColourEntry& e : table.entries()) {
    if (counts[e.label] > 0) order.emplace_back(-counts[e.label], e.label);
  }
  std::sort(order.begin(), order.end());
  std::string out;
  for (std::size_t i = 0; i < order.size() && i < 3; ++i) {
    out += Format("%s%s %.2f cm^3", i > 0 ? ", " : "",
                  table.FindByLabel(order[i].second)->name.c_str(),
                  -order[i].first * volume.voxel_volume_mm3() / kMm3PerCm3);
  }
  if (order.size() > 3) out += Format(" and %zu more", order.size() - 3);
  return out;
}

// ---- keep, drop, merge, rename

Status KeepOrDrop(const LabelStep& step, const std::string& field, LabelAtlas* atlas,
                  std::string* note) {
  std::vector<uint16_t> named;
  PBA_RETURN_IF_ERROR(LabelsNamed(atlas->table, step.structures, field, &named));
  if (named.empty()) return Status::InvalidArgument(field, "names no structure");
  const bool keep = step.kind == LabelStep::Kind::kKeep;
  std::vector<uint8_t> gone = LabelSet(named);
  if (keep) {
    for (int l = 0; l < 65536; ++l) gone[l] = !gone[l];
  }
  gone[0] = 0;
  std::vector<uint16_t> map = IdentityMap();
  int structures = 0;
  for (const ColourEntry& e : atlas->table.entries()) {
    if (gone[e.label]) {
      map[e.label] = 0;
      ++structures;
    }
  }
  ColourTable table;
  PBA_RETURN_IF_ERROR(Retable(atlas->table, gone, {}, &table));
  const int64_t changed = Relabel(map, &atlas->volume);
  atlas->table = std::move(table);
  *note = Format("%d structure%s dropped (%s made background)", structures,
                 structures == 1 ? "" : "s", Volume(changed, atlas->volume).c_str());
  return Status::Ok();
}

Status Merge(const LabelStep& step, const std::string& field, LabelAtlas* atlas,
             std::string* note) {
  std::vector<uint16_t> named;
  PBA_RETURN_IF_ERROR(LabelsNamed(atlas->table, step.structures, field + ".structures", &named));
  if (named.empty()) return Status::InvalidArgument(field, "names no structure to merge");
  if (step.name.empty())
    return Status::InvalidArgument(field + ".name", "the merged structure needs a name");
  const std::vector<uint8_t> gone = LabelSet(named);
  if (const ColourEntry* other = atlas->table.FindByName(step.name);
      other != nullptr && !gone[other->label]) {
    return Status::InvalidArgument(field + ".name", "the atlas already has a structure \"" +
                                                        step.name + "\" outside the merge");
  }
  // The merged structure keeps the lowest label and its colour.
  ColourEntry merged = *atlas->table.FindByLabel(named.front());
  merged.name = step.name;
  const std::string members = NameList(atlas->table, named);
  ColourTable table;
  PBA_RETURN_IF_ERROR(Retable(atlas->table, gone, {merged}, &table));
  std::vector<uint16_t> map = IdentityMap();
  for (uint16_t l : named) map[l] = merged.label;
  Relabel(map, &atlas->volume);
  int64_t voxels = 0;
  for (uint16_t l : atlas->volume.labels()) voxels += l == merged.label;
  atlas->table = std::move(table);
  *note = Format("\"%s\" (label %d) is the union of %zu structure%s: %s (%s)", step.name.c_str(),
                 merged.label, named.size(), named.size() == 1 ? "" : "s", members.c_str(),
                 Volume(voxels, atlas->volume).c_str());
  return Status::Ok();
}

Status Rename(const LabelStep& step, const std::string& field, LabelAtlas* atlas,
              std::string* note) {
  const ColourEntry* entry = atlas->table.FindByName(step.from);
  if (entry == nullptr) {
    return Status::InvalidArgument(field + ".from", "no structure \"" + step.from + "\"");
  }
  if (step.name.empty()) return Status::InvalidArgument(field + ".to", "the new name is empty");
  if (step.name != step.from && atlas->table.FindByName(step.name) != nullptr) {
    return Status::InvalidArgument(field + ".to",
                                   "the atlas already has a structure \"" + step.name + "\"");
  }
  ColourEntry renamed = *entry;
  renamed.name = step.name;
  std::vector<uint8_t> gone = LabelSet({entry->label});
  ColourTable table;
  PBA_RETURN_IF_ERROR(Retable(atlas->table, gone, {renamed}, &table));
  atlas->table = std::move(table);
  *note = Format("\"%s\" (label %d) renamed \"%s\"", step.from.c_str(), renamed.label,
                 step.name.c_str());
  return Status::Ok();
}

// ---- fill

// A grid padded by `pad` voxels on every side, x fastest.
struct PaddedGrid {
  int n[3] = {0, 0, 0};
  int pad = 0;
  size_t size() const { return static_cast<size_t>(n[0]) * n[1] * n[2]; }
  size_t Index(int i, int j, int k) const { return (static_cast<size_t>(k) * n[1] + j) * n[0] + i; }
};

// Marks every voxel of `open` (nonzero) that a 6-connected path through
// `open` joins to voxel `seed` with `mark` in `marks` (whose zero entries
// are unmarked); the count marked.
template <typename Mark>
int64_t Flood(const PaddedGrid& g, const std::vector<uint8_t>& open, size_t seed, Mark mark,
              std::vector<Mark>* marks) {
  if (!open[seed] || (*marks)[seed] != 0) return 0;
  const size_t sy = g.n[0], sz = static_cast<size_t>(g.n[0]) * g.n[1];
  std::vector<size_t> stack = {seed};
  (*marks)[seed] = mark;
  int64_t count = 0;
  while (!stack.empty()) {
    const size_t v = stack.back();
    stack.pop_back();
    ++count;
    const int i = static_cast<int>(v % sy), j = static_cast<int>(v / sy % g.n[1]);
    const int k = static_cast<int>(v / sz);
    const auto visit = [&](bool inside, size_t w) {
      if (inside && open[w] && (*marks)[w] == 0) {
        (*marks)[w] = mark;
        stack.push_back(w);
      }
    };
    visit(i > 0, v - 1);
    visit(i + 1 < g.n[0], v + 1);
    visit(j > 0, v - sy);
    visit(j + 1 < g.n[1], v + sy);
    visit(k > 0, v - sz);
    visit(k + 1 < g.n[2], v + sz);
  }
  return count;
}

// The closing of `solid` by a ball of `radius_mm`: dilated, then eroded.
std::vector<uint8_t> Closing(const PaddedGrid& g, const std::vector<uint8_t>& solid,
                             const double spacing[3], double radius_mm) {
  const double r2 = radius_mm * radius_mm;
  std::vector<double> d2;
  SquaredDistanceTransform3dMm(solid, g.n[0], g.n[1], g.n[2], spacing, &d2);
  std::vector<uint8_t> outside(g.size());
  for (size_t i = 0; i < g.size(); ++i) outside[i] = d2[i] > r2;
  SquaredDistanceTransform3dMm(outside, g.n[0], g.n[1], g.n[2], spacing, &d2);
  std::vector<uint8_t> closed(g.size());
  for (size_t i = 0; i < g.size(); ++i) closed[i] = d2[i] > r2;
  return closed;
}

// The background voxels enclosed by the atlas (after a closing of
// `closing_mm`), on the padded grid.
std::vector<uint8_t> Enclosed(const LabelVolume& v, double closing_mm, PaddedGrid* g) {
  const double spacing[3] = {v.spacing_mm().x(), v.spacing_mm().y(), v.spacing_mm().z()};
  g->pad = 1 + static_cast<int>(std::ceil(closing_mm / v.spacing_mm().minCoeff()));
  for (int a = 0; a < 3; ++a) g->n[a] = v.dims()[a] + 2 * g->pad;
  std::vector<uint8_t> solid(g->size(), 0);
  for (int k = 0; k < v.nz(); ++k) {
    for (int j = 0; j < v.ny(); ++j) {
      for (int i = 0; i < v.nx(); ++i) {
        solid[g->Index(i + g->pad, j + g->pad, k + g->pad)] = v.at(i, j, k) != 0;
      }
    }
  }
  const std::vector<uint8_t> closed =
      closing_mm > 0 ? Closing(*g, solid, spacing, closing_mm) : solid;
  std::vector<uint8_t> open(g->size());
  for (size_t i = 0; i < g->size(); ++i) open[i] = !closed[i];
  std::vector<uint8_t> outside(g->size(), 0);
  Flood<uint8_t>(*g, open, 0, 1, &outside);  // voxel 0 is in the padding: background
  std::vector<uint8_t> enclosed(g->size());
  for (size_t i = 0; i < g->size(); ++i) enclosed[i] = !outside[i] && !solid[i];
  return enclosed;
}

Status Fill(const LabelStep& step, const std::string& field, LabelAtlas* atlas, std::string* note) {
  ColourEntry entry;
  PBA_RETURN_IF_ERROR(NewEntry(atlas->table, step.name, field + ".name", &entry));
  LabelVolume& v = atlas->volume;
  // The closing works on the grid padded by its radius: bounded as a label
  // volume is (its distances take 8 bytes a voxel).
  double padded = 1;
  for (int a = 0; a < 3; ++a) {
    padded *= v.dims()[a] + 2 * (1 + std::ceil(step.closing_mm / v.spacing_mm().minCoeff()));
  }
  if (padded > static_cast<double>(kMaxLabelVolumeVoxels)) {
    return Status::InvalidArgument(
        field + ".closing_mm",
        Format("a %g mm closing on this grid needs %.3g voxels, over the %zu a label volume may "
               "hold: resample to coarser voxels first",
               step.closing_mm, padded, kMaxLabelVolumeVoxels));
  }
  PaddedGrid g;
  const std::vector<uint8_t> enclosed = Enclosed(v, step.closing_mm, &g);
  // Its 6-connected pieces, numbered from 1, and their sizes.
  std::vector<int32_t> piece(g.size(), 0);
  std::vector<int64_t> sizes = {0};
  for (size_t s = 0; s < g.size(); ++s) {
    const int32_t mark = static_cast<int32_t>(sizes.size());
    if (const int64_t count = Flood<int32_t>(g, enclosed, s, mark, &piece); count > 0) {
      sizes.push_back(count);
    }
  }
  if (sizes.size() == 1) {
    return Status::InvalidArgument(field,
                                   Format("the atlas encloses no background%s: nothing to fill",
                                          step.closing_mm > 0 ? " even after the closing" : ""));
  }
  const std::size_t largest = std::max_element(sizes.begin(), sizes.end()) - sizes.begin();
  const double min_voxels = step.min_piece_mm3 / v.voxel_volume_mm3();
  std::vector<uint8_t> kept(sizes.size(), 0);
  int64_t filled = 0, left = 0;
  int left_pieces = 0;
  for (std::size_t p = 1; p < sizes.size(); ++p) {
    kept[p] = p == largest || sizes[p] >= min_voxels;
    (kept[p] ? filled : left) += sizes[p];
    left_pieces += !kept[p];
  }
  for (int k = 0; k < v.nz(); ++k) {
    for (int j = 0; j < v.ny(); ++j) {
      for (int i = 0; i < v.nx(); ++i) {
        const int32_t p = piece[g.Index(i + g.pad, j + g.pad, k + g.pad)];
        if (kept[p]) v.set(i, j, k, entry.label);
      }
    }
  }
  ColourTable table;
  PBA_RETURN_IF_ERROR(Retable(atlas->table, LabelSet({}), {entry}, &table));
  atlas->table = std::move(table);
  *note = Format("\"%s\" (label %d) fills %s of background enclosed by the atlas",
                 step.name.c_str(), entry.label, Volume(filled, v).c_str());
  if (step.closing_mm > 0) *note += Format(" after a %g mm closing", step.closing_mm);
  const int pieces = static_cast<int>(sizes.size()) - 1 - left_pieces;
  *note += Format(" in %d piece%s", pieces, pieces == 1 ? "" : "s");
  if (left_pieces > 0) {
    *note += Format("; %d smaller enclosed piece%s (%s) left background", left_pieces,
                    left_pieces == 1 ? "" : "s", Volume(left, v).c_str());
  }
  int64_t atlas_voxels = 0;
  for (uint16_t l : v.labels()) atlas_voxels += l != 0 && l != entry.label;
  if (filled < 0.01 * atlas_voxels) {
    *note += Format(
        "; that is under 1 %% of the atlas: if it is open where the filling should "
        "be (AAL at the brainstem), a closing seals it (closing_mm, --closing-mm; "
        "AAL's white matter needs 7 mm)");
  }
  return Status::Ok();
}

// ---- islands

// The atlas's pieces (nonzero voxels joined by faces): each voxel's piece
// (0: background), and the pieces' sizes (entry 0 unused).
void AtlasPieces(const LabelVolume& v, std::vector<int32_t>* piece, std::vector<int64_t>* sizes) {
  PaddedGrid g;
  for (int a = 0; a < 3; ++a) g.n[a] = v.dims()[a];
  std::vector<uint8_t> solid(g.size());
  for (int64_t i = 0; i < v.num_voxels(); ++i) solid[i] = v.labels()[i] != 0;
  piece->assign(g.size(), 0);
  *sizes = {0};
  for (size_t s = 0; s < g.size(); ++s) {
    const int32_t mark = static_cast<int32_t>(sizes->size());
    if (const int64_t count = Flood<int32_t>(g, solid, s, mark, piece); count > 0) {
      sizes->push_back(count);
    }
  }
}

// Pieces under `min_voxels` (the largest kept) made background; false
// when there is none.
bool DropPiecesBelow(double min_voxels, LabelAtlas* atlas, std::string* note) {
  LabelVolume& v = atlas->volume;
  std::vector<int32_t> piece;
  std::vector<int64_t> sizes;
  AtlasPieces(v, &piece, &sizes);
  if (sizes.size() <= 2) return false;
  const std::size_t largest = std::max_element(sizes.begin(), sizes.end()) - sizes.begin();
  std::vector<uint8_t> drop(sizes.size(), 0);
  int dropped = 0;
  for (std::size_t p = 1; p < sizes.size(); ++p) {
    drop[p] = p != largest && sizes[p] < min_voxels;
    dropped += drop[p];
  }
  if (dropped == 0) return false;
  std::vector<int64_t> taken(65536, 0);
  int64_t total = 0;
  for (int64_t i = 0; i < v.num_voxels(); ++i) {
    if (!drop[piece[i]]) continue;
    ++taken[v.labels()[i]];
    ++total;
    v.mutable_labels()[i] = 0;
  }
  const int kept = static_cast<int>(sizes.size()) - 1 - dropped;
  *note = Format(
      "%d island%s of the atlas (pieces joined to the rest by no face: they would mesh "
      "as parts touching nothing, or hinged on an edge or a corner) made background: "
      "%s (%s); %d piece%s kept, the largest %s",
      dropped, dropped == 1 ? "" : "s", Volume(total, v).c_str(),
      LargestShares(atlas->table, taken, v).c_str(), kept, kept == 1 ? "" : "s",
      Volume(sizes[largest], v).c_str());
  return true;
}

Status Islands(const LabelStep& step, const std::string& field, LabelAtlas* atlas,
               std::string* note) {
  if (!DropPiecesBelow(step.min_piece_mm3 / atlas->volume.voxel_volume_mm3(), atlas, note)) {
    *note = Format("no island under %g mm^3", step.min_piece_mm3);
  }
  return Status::Ok();
}

// ---- overlay

Status ReadSecondAtlas(const LabelStep& step, const std::string& field, LabelAtlas* top,
                       std::vector<std::string>* notes) {
  if (step.table.empty()) {
    return Status::InvalidArgument(field + ".table",
                                   "the second atlas needs its label table to name its structures");
  }
  return ReadLabelAtlas(step.volume, step.table, field + ".volume", field + ".table", top, notes);
}

Status Overlay(const LabelStep& step, const std::string& field, LabelAtlas* atlas,
               std::string* note) {
  LabelAtlas top;
  std::vector<std::string> read_notes;
  PBA_RETURN_IF_ERROR(ReadSecondAtlas(step, field, &top, &read_notes));
  std::vector<uint16_t> chosen;
  if (step.structures.empty()) {
    for (const ColourEntry& e : top.table.entries()) chosen.push_back(e.label);
  } else {
    PBA_RETURN_IF_ERROR(LabelsNamed(top.table, step.structures, field + ".structures", &chosen));
  }
  // Each structure laid on gets a label this atlas does not use.
  std::vector<uint16_t> map(65536, 0);
  ColourTable table = atlas->table;
  for (uint16_t l : chosen) {
    const ColourEntry& e = *top.table.FindByLabel(l);
    if (table.FindByName(e.name) != nullptr) {
      return Status::InvalidArgument(
          field + ".structures",
          "both atlases have a structure \"" + e.name +
              "\": rename or drop it in this one first, or leave it out of the overlay");
    }
    ColourEntry added;
    PBA_RETURN_IF_ERROR(NewEntry(table, e.name, field, &added));
    if (table.FindByRgb(e.r, e.g, e.b) == nullptr) {
      added.r = e.r, added.g = e.g, added.b = e.b;
    }
    std::vector<ColourEntry> entries = table.entries();
    entries.push_back(added);
    PBA_RETURN_IF_ERROR(ColourTable::FromEntries(std::move(entries), &table));
    map[l] = added.label;
  }
  LabelVolume& v = atlas->volume;
  int64_t laid = 0, replaced = 0;
  std::vector<int64_t> taken(65536, 0);
  for (int k = 0; k < v.nz(); ++k) {
    for (int j = 0; j < v.ny(); ++j) {
      for (int i = 0; i < v.nx(); ++i) {
        const uint16_t t = map[top.volume.SampleNearest(v.VoxelCentreMm(i, j, k))];
        if (t == 0) continue;
        const uint16_t below = v.at(i, j, k);
        if (below != 0 && step.under) continue;
        v.set(i, j, k, t);
        ++laid;
        ++taken[below];
      }
    }
  }
  replaced = laid - taken[0];
  taken[0] = 0;
  *note = Format("%zu structure%s of %s laid %s: %s", chosen.size(), chosen.size() == 1 ? "" : "s",
                 step.volume.filename().string().c_str(), step.under ? "under" : "over",
                 Volume(laid, v).c_str());
  if (!step.under) {
    *note += Format(", of it %s on this atlas's structures (%s)", Volume(replaced, v).c_str(),
                    LargestShares(atlas->table, taken, v).c_str());
  }
  atlas->table = std::move(table);
  for (const std::string& n : read_notes) *note += "; " + n;
  return Status::Ok();
}

// ---- resample

Status Resample(const LabelStep& step, const std::string& field, LabelAtlas* atlas,
                std::string* note) {
  const LabelVolume& v = atlas->volume;
  const double h = step.voxel_mm;
  std::array<int, 3> dims;
  double voxels = 1;
  for (int a = 0; a < 3; ++a) {
    const double extent = v.dims()[a] * v.spacing_mm()[a];
    dims[a] = std::max(1, static_cast<int>(std::lround(extent / h)));
    voxels *= dims[a];
  }
  if (voxels > static_cast<double>(kMaxLabelVolumeVoxels)) {
    return Status::InvalidArgument(
        field + ".voxel_mm", Format("%g mm voxels would make %.3g voxels, over the %zu a label "
                                    "volume may hold",
                                    h, voxels, kMaxLabelVolumeVoxels));
  }
  // The same box: its lower corner stays where it was.
  const Eigen::Vector3d corner = v.origin_mm() - v.spacing_mm() / 2;
  LabelVolume out(dims, corner + Eigen::Vector3d::Constant(h / 2), Eigen::Vector3d::Constant(h));
  out.set_description(v.description());
  // Samples per axis: enough to see every old voxel when coarsening.
  int samples[3];
  for (int a = 0; a < 3; ++a) {
    samples[a] = std::clamp(static_cast<int>(std::ceil(h / v.spacing_mm()[a] - 1e-9)), 1, 4);
  }
  std::map<uint16_t, int> votes;
  for (int k = 0; k < dims[2]; ++k) {
    for (int j = 0; j < dims[1]; ++j) {
      for (int i = 0; i < dims[0]; ++i) {
        const Eigen::Vector3d c = out.VoxelCentreMm(i, j, k);
        votes.clear();
        for (int sk = 0; sk < samples[2]; ++sk) {
          for (int sj = 0; sj < samples[1]; ++sj) {
            for (int si = 0; si < samples[0]; ++si) {
              const Eigen::Vector3d offset((si + 0.5) / samples[0] - 0.5,
                                           (sj + 0.5) / samples[1] - 0.5,
                                           (sk + 0.5) / samples[2] - 0.5);
              ++votes[v.SampleNearest(c + h * offset)];
            }
          }
        }
        // The most votes; a tie goes to the lowest label.
        uint16_t best = 0;
        int most = -1;
        for (const auto& [label, count] : votes) {
          if (count > most) best = label, most = count;
        }
        out.set(i, j, k, best);
      }
    }
  }
  const std::vector<int64_t> before = CountLabels(v), after = CountLabels(out);
  std::vector<std::string> lost;
  for (const ColourEntry& e : atlas->table.entries()) {
    if (before[e.label] > 0 && after[e.label] == 0) lost.push_back(e.name);
  }
  *note = Format("resampled from %d x %d x %d voxels of %g x %g x %g mm to %d x %d x %d of %g mm",
                 v.nx(), v.ny(), v.nz(), v.spacing_mm().x(), v.spacing_mm().y(), v.spacing_mm().z(),
                 dims[0], dims[1], dims[2], h);
  if (!lost.empty()) {
    std::string names;
    for (const std::string& n : lost) names += (names.empty() ? "" : ", ") + n;
    *note += Format("; %zu structure%s thinner than the new voxels vanished: %s", lost.size(),
                    lost.size() == 1 ? "" : "s", names.c_str());
  }
  atlas->volume = std::move(out);
  return Status::Ok();
}

// ---- cut

// The voxels of the region, one byte each, and what it is for the note.
Status RegionVoxels(const LabelRegion& region, const std::string& field, const LabelAtlas& atlas,
                    std::vector<uint8_t>* in, std::vector<uint16_t>* own, std::string* what) {
  const LabelVolume& v = atlas.volume;
  in->assign(v.num_voxels(), 0);
  own->clear();
  const auto each = [&](const auto& inside) {
    for (int k = 0; k < v.nz(); ++k) {
      for (int j = 0; j < v.ny(); ++j) {
        for (int i = 0; i < v.nx(); ++i) (*in)[v.Index(i, j, k)] = inside(v.VoxelCentreMm(i, j, k));
      }
    }
  };
  switch (region.kind) {
    case LabelRegion::Kind::kSphere: {
      const double r2 = region.radius_mm * region.radius_mm;
      each([&](const Eigen::Vector3d& p) { return (p - region.centre_mm).squaredNorm() <= r2; });
      *what = Format("a sphere of %g mm", region.radius_mm);
      return Status::Ok();
    }
    case LabelRegion::Kind::kCylinder: {
      const Eigen::Vector3d axis = region.end_mm - region.centre_mm;
      const double length2 = axis.squaredNorm();
      const double r2 = region.radius_mm * region.radius_mm;
      each([&](const Eigen::Vector3d& p) {
        const double t = (p - region.centre_mm).dot(axis) / length2;
        return t >= 0 && t <= 1 && (p - region.centre_mm - t * axis).squaredNorm() <= r2;
      });
      *what = Format("a cylinder of radius %g mm and length %g mm", region.radius_mm,
                     std::sqrt(length2));
      return Status::Ok();
    }
    case LabelRegion::Kind::kMask: {
      LabelVolume mask;
      PBA_RETURN_IF_ERROR(ReadLabelVolume(region.mask, field + ".mask", &mask));
      each([&](const Eigen::Vector3d& p) { return mask.SampleNearest(p) != 0; });
      *what = "the mask " + region.mask.filename().string();
      return Status::Ok();
    }
    case LabelRegion::Kind::kStructures:
      break;
  }
  PBA_RETURN_IF_ERROR(
      LabelsNamed(atlas.table, region.structures, field + ".around.structures", own));
  if (own->empty())
    return Status::InvalidArgument(field + ".around.structures", "names no structure");
  const std::vector<uint8_t> member = LabelSet(*own);
  std::vector<uint8_t> seed(v.num_voxels());
  for (int64_t i = 0; i < v.num_voxels(); ++i) seed[i] = member[v.labels()[i]];
  std::vector<double> d2;
  const double spacing[3] = {v.spacing_mm().x(), v.spacing_mm().y(), v.spacing_mm().z()};
  SquaredDistanceTransform3dMm(seed, v.nx(), v.ny(), v.nz(), spacing, &d2);
  const double r2 = region.margin_mm * region.margin_mm;
  for (int64_t i = 0; i < v.num_voxels(); ++i) (*in)[i] = d2[i] <= r2;
  *what = Format("%s grown by %g mm", NameList(atlas.table, *own).c_str(), region.margin_mm);
  return Status::Ok();
}

Status Cut(const LabelStep& step, const std::string& field, LabelAtlas* atlas, std::string* note) {
  std::vector<uint8_t> in;
  std::vector<uint16_t> own;
  std::string what;
  PBA_RETURN_IF_ERROR(RegionVoxels(step.region, field, *atlas, &in, &own, &what));
  std::vector<uint16_t> targets;
  PBA_RETURN_IF_ERROR(LabelsNamed(atlas->table, step.structures, field + ".structures", &targets));
  std::vector<uint8_t> cut(65536, 0);
  if (step.structures.empty()) {
    for (const ColourEntry& e : atlas->table.entries()) cut[e.label] = 1;
    for (uint16_t l : own) cut[l] = 0;  // the region's own structures stay
  } else {
    cut = LabelSet(targets);
  }
  // What the cut voxels become: background, a structure of the table, or a
  // new one.
  uint16_t into = 0;
  ColourTable table = atlas->table;
  bool added = false;
  if (!step.name.empty()) {
    if (const ColourEntry* e = table.FindByName(step.name)) {
      into = e->label;
      cut[into] = 0;
    } else {
      ColourEntry entry;
      PBA_RETURN_IF_ERROR(NewEntry(table, step.name, field + ".name", &entry));
      into = entry.label;
      PBA_RETURN_IF_ERROR(Retable(table, LabelSet({}), {entry}, &table));
      added = true;
    }
  }
  std::vector<int64_t> taken(65536, 0);
  int64_t total = 0;
  std::vector<uint16_t>& labels = atlas->volume.mutable_labels();
  for (int64_t i = 0; i < atlas->volume.num_voxels(); ++i) {
    if (!in[i] || !cut[labels[i]]) continue;
    ++taken[labels[i]];
    ++total;
    labels[i] = into;
  }
  if (total == 0) {
    return Status::InvalidArgument(field, what + " holds no voxel of the structures it cuts");
  }
  int structures = 0;
  for (int l = 1; l < 65536; ++l) structures += taken[l] > 0;
  *note = Format("%s cut %s out of %d structure%s (%s)", what.c_str(),
                 Volume(total, atlas->volume).c_str(), structures, structures == 1 ? "" : "s",
                 LargestShares(atlas->table, taken, atlas->volume).c_str());
  *note += step.name.empty() ? std::string(", now background")
                             : Format(", now \"%s\"%s", step.name.c_str(), added ? " (new)" : "");
  atlas->table = std::move(table);
  return Status::Ok();
}

Status ApplyStep(const LabelStep& step, const std::string& field, LabelAtlas* atlas,
                 std::string* note) {
  PBA_RETURN_IF_ERROR(CheckLabelStep(step, field));
  switch (step.kind) {
    case LabelStep::Kind::kKeep:
    case LabelStep::Kind::kDrop:
      return KeepOrDrop(step, field, atlas, note);
    case LabelStep::Kind::kMerge:
      return Merge(step, field, atlas, note);
    case LabelStep::Kind::kRename:
      return Rename(step, field, atlas, note);
    case LabelStep::Kind::kFill:
      return Fill(step, field, atlas, note);
    case LabelStep::Kind::kOverlay:
      return Overlay(step, field, atlas, note);
    case LabelStep::Kind::kResample:
      return Resample(step, field, atlas, note);
    case LabelStep::Kind::kCut:
      return Cut(step, field, atlas, note);
    case LabelStep::Kind::kIslands:
      return Islands(step, field, atlas, note);
  }
  return Status::Internal("unknown label step");
}

}  // namespace

Status CheckLabelStep(const LabelStep& step, const std::string& field) {
  const auto finite_in = [](double x, double low, double high) {
    return std::isfinite(x) && x >= low && x <= high;
  };
  const auto positive = [](double x) { return std::isfinite(x) && x > 0; };
  switch (step.kind) {
    case LabelStep::Kind::kFill:
      if (!finite_in(step.closing_mm, 0, 50))
        return Status::InvalidArgument(field + ".closing_mm", "must lie in [0, 50] mm");
      [[fallthrough]];
    case LabelStep::Kind::kIslands:
      if (!finite_in(step.min_piece_mm3, 0, HUGE_VAL))
        return Status::InvalidArgument(field + ".min_piece_mm3", "must be >= 0");
      return Status::Ok();
    case LabelStep::Kind::kResample:
      if (!positive(step.voxel_mm))
        return Status::InvalidArgument(field + ".voxel_mm", "must be positive");
      return Status::Ok();
    case LabelStep::Kind::kCut:
      break;
    default:
      return Status::Ok();
  }
  const LabelRegion& region = step.region;
  switch (region.kind) {
    case LabelRegion::Kind::kSphere:
      if (!positive(region.radius_mm))
        return Status::InvalidArgument(field + ".sphere.radius_mm", "must be positive");
      break;
    case LabelRegion::Kind::kCylinder:
      if (!positive(region.radius_mm))
        return Status::InvalidArgument(field + ".cylinder.radius_mm", "must be positive");
      if (!((region.end_mm - region.centre_mm).squaredNorm() > 0))
        return Status::InvalidArgument(field + ".cylinder", "its two ends are one point");
      break;
    case LabelRegion::Kind::kStructures:
      if (!finite_in(region.margin_mm, 0, 50))
        return Status::InvalidArgument(field + ".around.margin_mm", "must lie in [0, 50] mm");
      break;
    case LabelRegion::Kind::kMask:
      break;
  }
  return Status::Ok();
}

const char* LabelStepName(LabelStep::Kind kind) {
  switch (kind) {
    case LabelStep::Kind::kKeep:
      return "keep";
    case LabelStep::Kind::kDrop:
      return "drop";
    case LabelStep::Kind::kMerge:
      return "merge";
    case LabelStep::Kind::kRename:
      return "rename";
    case LabelStep::Kind::kFill:
      return "fill";
    case LabelStep::Kind::kOverlay:
      return "overlay";
    case LabelStep::Kind::kResample:
      return "resample";
    case LabelStep::Kind::kCut:
      return "cut";
    case LabelStep::Kind::kIslands:
      return "islands";
  }
  return "?";
}

bool DropIslands(double share, LabelAtlas* atlas, std::string* note) {
  if (!(share > 0)) return false;
  std::vector<int32_t> piece;
  std::vector<int64_t> sizes;
  AtlasPieces(atlas->volume, &piece, &sizes);
  if (sizes.size() <= 2) return false;
  const int64_t largest = *std::max_element(sizes.begin(), sizes.end());
  return DropPiecesBelow(share * largest, atlas, note);
}

Status ReadLabelAtlas(const std::filesystem::path& volume, const std::filesystem::path& table,
                      const std::string& volume_field, const std::string& table_field,
                      LabelAtlas* atlas, std::vector<std::string>* notes) {
  LabelAtlas read;
  PBA_RETURN_IF_ERROR(ReadLabelVolume(volume, volume_field, &read.volume));
  if (table.empty()) {
    PBA_RETURN_IF_ERROR(LabelVolumeNeedsATable(read.volume, table_field));
    read.table = ColourTable::Builtin();
  } else {
    LabelTableRead info;
    PBA_RETURN_IF_ERROR(ReadLabelTable(table, &read.table, &info));
    notes->insert(notes->end(), info.notes.begin(), info.notes.end());
  }
  const std::vector<int64_t> counts = CountLabels(read.volume);
  for (int l = 1; l < 65536; ++l) {
    if (counts[l] > 0 && read.table.FindByLabel(static_cast<uint16_t>(l)) == nullptr) {
      return Status::InvalidArgument(
          table_field,
          Format("label %d of %s (%lld voxels) has no entry in %s", l,
                 volume.filename().string().c_str(), static_cast<long long>(counts[l]),
                 table.empty() ? "the built-in table" : table.filename().string().c_str()));
    }
  }
  *atlas = std::move(read);
  return Status::Ok();
}

Status ApplyLabelSteps(const std::vector<LabelStep>& steps, LabelAtlas* atlas,
                       std::vector<std::string>* notes) {
  LabelAtlas work = *atlas;
  std::vector<std::string> said;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const std::string field = Format("labels[%zu]", i);
    std::string note;
    if (Status s = ApplyStep(steps[i], field, &work, &note); !s.ok()) {
      return s.WithContext(Format("(%s) ", LabelStepName(steps[i].kind)));
    }
    said.push_back(Format("%s %s: ", field.c_str(), LabelStepName(steps[i].kind)) + note);
  }
  *atlas = std::move(work);
  notes->insert(notes->end(), said.begin(), said.end());
  return Status::Ok();
}

}  // namespace pba
