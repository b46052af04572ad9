#include "atlas/atlas_mesh_cache.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <utility>
#include <vector>

#include "atlas/label_table.h"
#include "atlas/structure_set.h"
#include "core/atomic_write.h"
#include "core/cache_dir.h"
#include "core/format.h"
#include "core/sha256.h"
#include "pba/solve.h"

namespace pba {
namespace fs = std::filesystem;

namespace {

// Bump when the key's canonical text changes meaning (a new option, a new
// way of reading a source), or when the atlas build makes a different mesh
// from the same input without a new solver version (the version is the
// project's, not a commit's), so old entries stop matching.
// 2: label volumes lose their islands (island_share); 3: improvement on the
// aspect ratio too, boundary slivers peeled, mesh fragments dropped; 4:
// node insertion in the improvement; 5: short edges collapsed.
constexpr int kKeyFormatVersion = 5;

// The entry file: magic, format version, a byte-order mark (entries hold
// the host's native integers and doubles: a cache directory shared with a
// host of the other byte order sees misses, not garbage), the payload, then
// the SHA-256 of everything before it.
constexpr char kMagic[8] = {'P', 'B', 'A', 'M', 'E', 'S', 'H', 'C'};
constexpr std::uint32_t kFileFormatVersion = 1;
constexpr std::uint32_t kByteOrderMark = 0x01020304;
constexpr std::size_t kHeaderBytes = sizeof(kMagic) + 2 * sizeof(std::uint32_t);
constexpr std::size_t kDigestBytes = 32;
constexpr char kEntrySuffix[] = ".mesh";

static_assert(sizeof(int) == 4, "entries store node indices as 32-bit integers");

using Digest = Sha256Digest;
static_assert(sizeof(Digest) == kDigestBytes);

// A name in the canonical text, length-prefixed so that no name (with
// spaces or newlines) can run into the next field.
std::string Quoted(const std::string& s) { return Format("%zu:", s.size()) + s; }

const char* SourceName(AtlasBuildOptions::Source source) {
  switch (source) {
    case AtlasBuildOptions::Source::kSynthetic:
      return "synthetic";
    case AtlasBuildOptions::Source::kPlates:
      return "plates";
    case AtlasBuildOptions::Source::kLabelVolume:
      return "label-volume";
    case AtlasBuildOptions::Source::kStructures:
      return "structure-set";
    default:
      return "other";  // a kind added later: its number tells it apart
  }
}

// The content of the source: every regular file of a directory (plates, a
// structure set) by relative name and digest, sorted by name; a file's
// digest, with its colour table's.
Status DescribeSourceContent(const AtlasBuildOptions& options, std::string* text) {
  if (options.source == AtlasBuildOptions::Source::kSynthetic) {
    text->append("content synthetic\n");
    return Status::Ok();
  }
  std::error_code ec;
  if (options.source == AtlasBuildOptions::Source::kStructures) {
    // A structure set by what makes its atlas: each structure's name,
    // colour, format and file digest, not the manifest's provenance (the
    // project and snapshot it was exported or staged from), so two
    // snapshots pinning the same revisions share one mesh.
    StructureSet set;
    PBA_RETURN_IF_ERROR(ReadStructureSet(options.input, &set));
    text->append(Format("content structure set %zu structures\n", set.structures.size()));
    for (const StructureEntry& entry : set.structures) {
      std::string digest;
      PBA_RETURN_IF_ERROR(FileSha256Hex(options.input / entry.file, &digest));
      text->append(Format("structure %s %s %d,%d,%d %s\n", Quoted(entry.name).c_str(),
                          StructureFormatName(entry.format), entry.r, entry.g, entry.b,
                          digest.c_str()));
    }
  } else if (fs::is_directory(options.input, ec)) {
    std::vector<std::pair<std::string, fs::path>> files;
    fs::recursive_directory_iterator it(options.input, ec), end;
    if (ec) return Status::Io("cannot list " + options.input.string() + ": " + ec.message());
    for (; it != end; it.increment(ec)) {
      if (ec) return Status::Io("cannot list " + options.input.string() + ": " + ec.message());
      if (!it->is_regular_file(ec)) continue;
      files.emplace_back(it->path().lexically_relative(options.input).generic_string(), it->path());
    }
    std::sort(files.begin(), files.end());
    text->append(Format("content directory %zu files\n", files.size()));
    for (const auto& [name, path] : files) {
      std::string digest;
      PBA_RETURN_IF_ERROR(FileSha256Hex(path, &digest));
      text->append("file " + Quoted(name) + " " + digest + "\n");
    }
  } else {
    std::string digest;
    PBA_RETURN_IF_ERROR(FileSha256Hex(options.input, &digest));
    text->append("content file " + digest + "\n");
  }
  if (options.colour_table.empty()) {
    text->append("colour_table built-in\n");
  } else {
    // Every file the table is read from (an MRIcron .txt and its .lut).
    for (const std::filesystem::path& file : LabelTableFiles(options.colour_table)) {
      std::string digest;
      PBA_RETURN_IF_ERROR(FileSha256Hex(file, &digest));
      text->append("colour_table " + digest + "\n");
    }
  }
  // The label algebra, and the contents of every file it reads.
  if (!options.label_steps.empty()) {
    text->append(DescribeLabelSteps(options.label_steps));
    for (const std::filesystem::path& file : LabelStepFiles(options.label_steps)) {
      std::string digest;
      PBA_RETURN_IF_ERROR(FileSha256Hex(file, &digest));
      text->append("label_step_file " + digest + "\n");
    }
  }
  return Status::Ok();
}

// ---- The entry file's payload.

class Writer {
 public:
  template <typename T>
  void Pod(const T& value) {
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  void String(const std::string& s) {
    Pod<std::uint64_t>(s.size());
    bytes_.append(s);
  }
  template <typename T>
  void Vector(const std::vector<T>& v) {
    Pod<std::uint64_t>(v.size());
    bytes_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
  }
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
};

// Reads what Writer wrote; any read past the end (or a count that would
// run past it) leaves it failed, and everything read after is zero.
class Reader {
 public:
  Reader(const char* data, std::size_t size) : p_(data), left_(size) {}
  template <typename T>
  T Pod() {
    T value{};
    if (!Take(&value, sizeof(T))) ok_ = false;
    return value;
  }
  std::string String() {
    const std::uint64_t n = Pod<std::uint64_t>();
    if (!ok_ || n > left_) return Fail<std::string>();
    std::string s(p_, n);
    p_ += n;
    left_ -= n;
    return s;
  }
  template <typename T>
  std::vector<T> Vector() {
    const std::uint64_t n = Pod<std::uint64_t>();
    if (!ok_ || n > left_ / sizeof(T)) return Fail<std::vector<T>>();
    std::vector<T> v(n);
    if (n > 0) Take(v.data(), n * sizeof(T));
    return v;
  }
  void Bytes(void* out, std::size_t n) {
    if (!Take(out, n)) Fail<int>();
  }
  bool ok() const { return ok_; }
  bool at_end() const { return left_ == 0; }
  std::size_t left() const { return left_; }

 private:
  bool Take(void* out, std::size_t n) {
    if (n > left_) return false;
    std::memcpy(out, p_, n);
    p_ += n;
    left_ -= n;
    return true;
  }
  template <typename T>
  T Fail() {
    ok_ = false;
    left_ = 0;
    return T();
  }

  const char* p_;
  std::size_t left_;
  bool ok_ = true;
};

void WritePayload(const CachedAtlasMesh& entry, Writer* w) {
  const Mesh& m = entry.mesh;
  w->Pod<std::uint64_t>(static_cast<std::uint64_t>(m.nodes.rows()));
  w->bytes().append(reinterpret_cast<const char*>(m.nodes.data()),
                    static_cast<std::size_t>(m.nodes.size()) * sizeof(double));
  w->Vector(m.tets);
  w->Vector(m.midside);
  w->Vector(m.hexes);
  w->Vector(m.element_region);
  w->Pod<std::uint64_t>(m.region_names.size());
  for (const std::string& name : m.region_names) w->String(name);
  w->Pod<std::uint64_t>(m.face_sets.size());
  for (const auto& [name, set] : m.face_sets) {
    w->String(name);
    w->Vector(set.triangles);
    w->Vector(set.triangle_midside);
    w->Vector(set.quads);
    w->Vector(set.nodes);
  }
  w->String(entry.description);
}

// Whether every index of the mesh is in range: a last guard (after the
// checksum) that a mesh read back is one the solver can index safely.
bool Consistent(const Mesh& m) {
  const int n = m.num_nodes();
  const auto in_range = [n](const auto& cells) {
    for (const auto& cell : cells) {
      for (int node : cell) {
        if (node < 0 || node >= n) return false;
      }
    }
    return true;
  };
  if (!in_range(m.tets) || !in_range(m.midside) || !in_range(m.hexes)) return false;
  if (!m.midside.empty() && m.midside.size() != m.tets.size()) return false;
  if (!m.element_region.empty() &&
      m.element_region.size() != static_cast<std::size_t>(m.num_elements())) {
    return false;
  }
  for (int r : m.element_region) {
    if (r < 0 || r >= static_cast<int>(m.region_names.size())) return false;
  }
  for (const auto& [name, set] : m.face_sets) {
    if (!in_range(set.triangles) || !in_range(set.triangle_midside) || !in_range(set.quads)) {
      return false;
    }
    for (int node : set.nodes) {
      if (node < 0 || node >= n) return false;
    }
  }
  return true;
}

bool ReadPayload(Reader* r, CachedAtlasMesh* entry) {
  Mesh& m = entry->mesh;
  const std::uint64_t rows = r->Pod<std::uint64_t>();
  if (!r->ok() || rows > r->left() / (3 * sizeof(double))) return false;
  m.nodes.resize(static_cast<Eigen::Index>(rows), 3);
  r->Bytes(m.nodes.data(), static_cast<std::size_t>(m.nodes.size()) * sizeof(double));
  m.tets = r->Vector<std::array<int, 4>>();
  m.midside = r->Vector<std::array<int, 6>>();
  m.hexes = r->Vector<std::array<int, 8>>();
  m.element_region = r->Vector<int>();
  const std::uint64_t regions = r->Pod<std::uint64_t>();
  for (std::uint64_t i = 0; i < regions && r->ok(); ++i) m.region_names.push_back(r->String());
  const std::uint64_t sets = r->Pod<std::uint64_t>();
  for (std::uint64_t i = 0; i < sets && r->ok(); ++i) {
    std::string name = r->String();
    FaceSet set;
    set.triangles = r->Vector<std::array<int, 3>>();
    set.triangle_midside = r->Vector<std::array<int, 3>>();
    set.quads = r->Vector<std::array<int, 4>>();
    set.nodes = r->Vector<int>();
    m.face_sets[std::move(name)] = std::move(set);
  }
  entry->description = r->String();
  return r->ok() && r->at_end() && Consistent(m);
}

bool IsKey(const std::string& key) {
  return key.size() == 2 * kDigestBytes && std::all_of(key.begin(), key.end(), [](char c) {
           return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f');
         });
}

fs::path EntryPath(const fs::path& dir, const std::string& key) {
  return dir / (key + kEntrySuffix);
}

}  // namespace

Status AtlasMeshCacheKey(const AtlasBuildOptions& options, std::string* key) {
  // Every option that can change the mesh, with the solver's version (a new
  // mesher or improvement pass makes different meshes from the same input).
  // The time limit counts too: a step it cuts short leaves a different mesh.
  // Paths do not (plates_dir is scratch space; the input's content counts).
  std::string text =
      Format("pba-atlas-mesh-key %d\nsolver %s\n", kKeyFormatVersion, SolverVersion());
  text += Format("source %d %s\n", static_cast<int>(options.source), SourceName(options.source));
  text += Format("synthetic_voxel_mm %.17g\nloft_voxel_mm %.17g\n", options.synthetic_voxel_mm,
                 options.loft_voxel_mm);
  text += Format("cell_size_mm %.17g\nfacet_size_mm %.17g\nfacet_distance_mm %.17g\n",
                 options.cell_size_mm, options.facet_size_mm, options.facet_distance_mm);
  text += Format("facets_per_section %.17g\nodt_iterations %d\nimprove_target_deg %.17g\n",
                 options.facets_per_section, options.odt_iterations, options.improve_target_deg);
  text += Format("improve_aspect_ratio %.17g\n", options.improve_aspect_ratio);
  text += Format("optimisation_time_limit_s %.17g\n", options.optimisation_time_limit_s);
  text += Format("roi_centre_mm %.17g %.17g %.17g\nroi_radius_mm %.17g\nroi_size_mm %.17g\n",
                 options.roi_centre_mm.x(), options.roi_centre_mm.y(), options.roi_centre_mm.z(),
                 options.roi_radius_mm, options.roi_size_mm);
  text += Format("island_share %.17g\nquality_rounds %d\n", options.island_share,
                 options.quality_rounds);
  // Said only when off, so the keys of meshes built before it existed hold.
  if (!options.remove_slivers) text += "remove_slivers 0\n";
  text += Format("quadratic %d\nmerge_rest %d\nstructures %zu\n", options.quadratic ? 1 : 0,
                 options.merge_rest ? 1 : 0, options.structures.size());
  for (const std::string& s : options.structures) text += "structure " + Quoted(s) + "\n";
  PBA_RETURN_IF_ERROR(DescribeSourceContent(options, &text));
  *key = HexOf(Sha256Of(text.data(), text.size()));
  return Status::Ok();
}

Status LoadCachedAtlasMesh(const fs::path& dir, const std::string& key, CachedAtlasMesh* entry,
                           bool* hit) {
  *hit = false;
  if (!IsKey(key)) return Status::InvalidArgument("key", "not an atlas mesh cache key: " + key);
  const fs::path path = EntryPath(dir, key);
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) return Status::Ok();  // no entry
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (in.bad()) return Status::Ok();
  }
  const auto damaged = [&] {
    // Another job may have replaced it with a good one meanwhile; removing
    // that costs one rebuild, and keeps this simple.
    std::error_code ignored;
    fs::remove(path, ignored);
    return Status::Ok();
  };
  if (bytes.size() < kHeaderBytes + kDigestBytes) return damaged();
  const std::size_t body = bytes.size() - kDigestBytes;
  const Digest digest = Sha256Of(bytes.data(), body);
  if (std::memcmp(digest.data(), bytes.data() + body, kDigestBytes) != 0) return damaged();
  Reader r(bytes.data(), body);
  char magic[sizeof(kMagic)];
  for (char& c : magic) c = r.Pod<char>();
  const auto version = r.Pod<std::uint32_t>();
  const auto mark = r.Pod<std::uint32_t>();
  if (std::memcmp(magic, kMagic, sizeof(kMagic)) != 0 || version != kFileFormatVersion ||
      mark != kByteOrderMark) {
    return damaged();
  }
  CachedAtlasMesh read;
  if (!ReadPayload(&r, &read)) return damaged();
  *entry = std::move(read);
  *hit = true;
  // Renew its place in the eviction order.
  std::error_code ignored;
  fs::last_write_time(path, fs::file_time_type::clock::now(), ignored);
  return Status::Ok();
}

Status StoreCachedAtlasMesh(const fs::path& dir, const std::string& key,
                            const CachedAtlasMesh& entry, std::uint64_t max_bytes) {
  if (!IsKey(key)) return Status::InvalidArgument("key", "not an atlas mesh cache key: " + key);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return Status::Io("cannot create " + dir.string() + ": " + ec.message());
  Writer w;
  w.bytes().append(kMagic, sizeof(kMagic));
  w.Pod(kFileFormatVersion);
  w.Pod(kByteOrderMark);
  WritePayload(entry, &w);
  const Digest digest = Sha256Of(w.bytes().data(), w.bytes().size());
  w.bytes().append(reinterpret_cast<const char*>(digest.data()), digest.size());
  const std::string& bytes = w.bytes();
  PBA_RETURN_IF_ERROR(AtomicWrite(EntryPath(dir, key), "", [&](int fd, const std::string& tmp) {
    return WriteAll(fd, bytes.data(), bytes.size(), tmp);
  }));
  EvictAtlasMeshCache(dir, max_bytes, key);
  return Status::Ok();
}

void EvictAtlasMeshCache(const fs::path& dir, std::uint64_t max_bytes, const std::string& keep) {
  EvictLeastRecentlyUsed(dir, kEntrySuffix, max_bytes, keep.empty() ? "" : keep + kEntrySuffix);
}

}  // namespace pba
