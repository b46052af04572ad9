// The atlas mesh cache: entries read back bit for bit, damaged entries are
// misses (and go), keys follow content and options but not timestamps,
// and the directory keeps its most recently used entries within its bound.
#include "atlas/atlas_mesh_cache.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "atlas/structure_set.h"
#include "mesh/quadratic.h"

namespace pba {
namespace {

namespace fs = std::filesystem;

// Two tetrahedra sharing a face, in two regions, with a surface set and an
// interface set.
Mesh TwoTets() {
  Mesh m;
  m.nodes.resize(5, 3);
  m.nodes << 0, 0, 0, 1e-3, 0, 0, 0, 1e-3, 0, 0, 0, 1e-3, 1e-3 / 3, 1e-3 / 7, -1e-3 * 0.1;
  m.tets = {{0, 1, 2, 3}, {0, 2, 1, 4}};
  m.region_names = {"Putamen", "Globus pallidus lateralis"};
  m.element_region = {1, 0};
  FaceSet surface;
  surface.triangles = {{0, 3, 1}, {1, 3, 2}, {0, 2, 3}, {0, 1, 4}, {1, 2, 4}, {2, 0, 4}};
  CollectFaceSetNodes(&surface);
  m.face_sets["surface"] = surface;
  FaceSet between;
  between.triangles = {{0, 1, 2}};
  CollectFaceSetNodes(&between);
  m.face_sets["interface:Globus pallidus lateralis|Putamen"] = between;
  return m;
}

void ExpectIdentical(const Mesh& a, const Mesh& b) {
  ASSERT_EQ(a.nodes.rows(), b.nodes.rows());
  EXPECT_EQ(std::memcmp(a.nodes.data(), b.nodes.data(), a.nodes.size() * sizeof(double)), 0);
  EXPECT_EQ(a.tets, b.tets);
  EXPECT_EQ(a.midside, b.midside);
  EXPECT_EQ(a.hexes, b.hexes);
  EXPECT_EQ(a.element_region, b.element_region);
  EXPECT_EQ(a.region_names, b.region_names);
  ASSERT_EQ(a.face_sets.size(), b.face_sets.size());
  for (const auto& [name, set] : a.face_sets) {
    ASSERT_TRUE(b.face_sets.count(name)) << name;
    const FaceSet& other = b.face_sets.at(name);
    EXPECT_EQ(set.triangles, other.triangles) << name;
    EXPECT_EQ(set.triangle_midside, other.triangle_midside) << name;
    EXPECT_EQ(set.quads, other.quads) << name;
    EXPECT_EQ(set.nodes, other.nodes) << name;
  }
}

class AtlasMeshCacheTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("pba_atlas_mesh_cache_test_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
    cache_ = root_ / "cache";
  }
  void TearDown() override { fs::remove_all(root_); }

  static void WriteFile(const fs::path& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
  }

  fs::path root_, cache_;
  const std::string key_ = std::string(64, 'a');
};

TEST_F(AtlasMeshCacheTest, RoundTripIsBitIdentical) {
  CachedAtlasMesh stored{TwoTets(), "synthetic atlas, 2 structures; 2 tetrahedra"};
  ASSERT_TRUE(StoreCachedAtlasMesh(cache_, key_, stored).ok());
  CachedAtlasMesh loaded;
  bool hit = false;
  ASSERT_TRUE(LoadCachedAtlasMesh(cache_, key_, &loaded, &hit).ok());
  ASSERT_TRUE(hit);
  ExpectIdentical(stored.mesh, loaded.mesh);
  EXPECT_EQ(loaded.description, stored.description);
  // Another key is a miss.
  bool other = true;
  ASSERT_TRUE(LoadCachedAtlasMesh(cache_, std::string(64, 'b'), &loaded, &other).ok());
  EXPECT_FALSE(other);
}

TEST_F(AtlasMeshCacheTest, QuadraticRoundTripIsBitIdentical) {
  CachedAtlasMesh stored{MakeQuadratic(TwoTets()), "10-node"};
  ASSERT_TRUE(stored.mesh.quadratic());
  ASSERT_FALSE(stored.mesh.face_sets.at("surface").triangle_midside.empty());
  ASSERT_TRUE(StoreCachedAtlasMesh(cache_, key_, stored).ok());
  CachedAtlasMesh loaded;
  bool hit = false;
  ASSERT_TRUE(LoadCachedAtlasMesh(cache_, key_, &loaded, &hit).ok());
  ASSERT_TRUE(hit);
  ExpectIdentical(stored.mesh, loaded.mesh);
}

TEST_F(AtlasMeshCacheTest, ATruncatedOrAlteredEntryIsAMissAndIsRemoved) {
  const CachedAtlasMesh stored{TwoTets(), "two tets"};
  const fs::path file = cache_ / (key_ + ".mesh");
  ASSERT_TRUE(StoreCachedAtlasMesh(cache_, key_, stored).ok());
  const auto size = fs::file_size(file);
  // Every truncation, and a flipped byte anywhere (magic, version, payload,
  // checksum).
  for (std::uintmax_t cut : {std::uintmax_t{0}, std::uintmax_t{5}, size / 2, size - 1}) {
    ASSERT_TRUE(StoreCachedAtlasMesh(cache_, key_, stored).ok());
    fs::resize_file(file, cut);
    CachedAtlasMesh loaded;
    bool hit = true;
    ASSERT_TRUE(LoadCachedAtlasMesh(cache_, key_, &loaded, &hit).ok());
    EXPECT_FALSE(hit) << "cut at " << cut;
    EXPECT_FALSE(fs::exists(file)) << "cut at " << cut;
  }
  for (std::uintmax_t at : {std::uintmax_t{0}, std::uintmax_t{9}, size / 2, size - 1}) {
    ASSERT_TRUE(StoreCachedAtlasMesh(cache_, key_, stored).ok());
    {
      std::fstream f(file, std::ios::binary | std::ios::in | std::ios::out);
      f.seekg(static_cast<std::streamoff>(at));
      const char c = static_cast<char>(f.get());
      f.seekp(static_cast<std::streamoff>(at));
      f.put(static_cast<char>(c ^ 0x10));
    }
    CachedAtlasMesh loaded;
    bool hit = true;
    ASSERT_TRUE(LoadCachedAtlasMesh(cache_, key_, &loaded, &hit).ok());
    EXPECT_FALSE(hit) << "byte " << at;
    EXPECT_FALSE(fs::exists(file)) << "byte " << at;
  }
  // A key that is not one names no file at all.
  bool hit = true;
  CachedAtlasMesh loaded;
  EXPECT_FALSE(LoadCachedAtlasMesh(cache_, "../escape", &loaded, &hit).ok());
  EXPECT_FALSE(hit);
}

// Jobs storing and loading the same key at once: every load is a miss or
// the whole mesh, never a damaged entry (which would be removed), and no
// temporary file is left.
TEST_F(AtlasMeshCacheTest, ConcurrentStoresAndLoadsOfOneKeyAreSafe) {
  const CachedAtlasMesh stored{MakeQuadratic(TwoTets()), std::string(100000, 'q')};
  std::vector<std::thread> jobs;
  std::vector<int> hits(4, 0), bad(4, 0);
  for (int j = 0; j < 4; ++j) {
    jobs.emplace_back([&, j] {
      for (int i = 0; i < 25; ++i) {
        if (!StoreCachedAtlasMesh(cache_, key_, stored).ok()) ++bad[j];
        CachedAtlasMesh loaded;
        bool hit = false;
        if (!LoadCachedAtlasMesh(cache_, key_, &loaded, &hit).ok()) ++bad[j];
        if (!hit) continue;
        ++hits[j];
        if (loaded.mesh.midside != stored.mesh.midside ||
            loaded.description != stored.description) {
          ++bad[j];
        }
      }
    });
  }
  for (std::thread& job : jobs) job.join();
  for (int j = 0; j < 4; ++j) {
    EXPECT_EQ(bad[j], 0) << "job " << j;
    EXPECT_EQ(hits[j], 25) << "job " << j;  // nothing was ever damaged
  }
  int files = 0;
  for (const auto& entry : fs::directory_iterator(cache_)) {
    ++files;
    EXPECT_EQ(entry.path().filename(), key_ + ".mesh");
  }
  EXPECT_EQ(files, 1);
}

TEST_F(AtlasMeshCacheTest, KeyFollowsOptionsAndContentNotTimestamps) {
  const fs::path plates = root_ / "plates";
  fs::create_directories(plates / "sub");
  WriteFile(plates / "plates.csv", "z_mm,file\n0,a.png\n");
  WriteFile(plates / "a.png", std::string(1000, 'x'));
  WriteFile(plates / "sub" / "b.txt", "b");
  AtlasBuildOptions options;
  options.source = AtlasBuildOptions::Source::kPlates;
  options.input = plates;
  std::string key;
  ASSERT_TRUE(AtlasMeshCacheKey(options, &key).ok());
  EXPECT_EQ(key.size(), 64u);
  EXPECT_EQ(key.find_first_not_of("0123456789abcdef"), std::string::npos) << key;
  const auto key_of = [](const AtlasBuildOptions& o) {
    std::string k;
    EXPECT_TRUE(AtlasMeshCacheKey(o, &k).ok());
    return k;
  };
  EXPECT_EQ(key_of(options), key);  // deterministic

  // Options.
  AtlasBuildOptions changed = options;
  changed.cell_size_mm += 1e-12;
  EXPECT_NE(key_of(changed), key);
  changed = options;
  changed.structures = {"Putamen"};
  EXPECT_NE(key_of(changed), key);
  changed = options;
  changed.optimisation_time_limit_s = 20;
  EXPECT_NE(key_of(changed), key);
  changed = options;
  changed.plates_dir = root_ / "elsewhere";  // scratch space, not input
  EXPECT_EQ(key_of(changed), key);

  // Timestamps and the directory's place do not count.
  fs::last_write_time(plates / "a.png",
                      fs::last_write_time(plates / "a.png") - std::chrono::hours(48));
  EXPECT_EQ(key_of(options), key);
  const fs::path copy = root_ / "copy";
  fs::copy(plates, copy, fs::copy_options::recursive);
  changed = options;
  changed.input = copy;
  EXPECT_EQ(key_of(changed), key);

  // One byte of one file, a file renamed, a file added.
  WriteFile(copy / "a.png", std::string(999, 'x') + "y");
  EXPECT_NE(key_of(changed), key);
  WriteFile(copy / "a.png", std::string(1000, 'x'));
  EXPECT_EQ(key_of(changed), key);
  fs::rename(copy / "sub" / "b.txt", copy / "sub" / "c.txt");
  EXPECT_NE(key_of(changed), key);
  fs::rename(copy / "sub" / "c.txt", copy / "sub" / "b.txt");
  WriteFile(copy / "manifest.json", "{}");
  EXPECT_NE(key_of(changed), key);

  // A label volume and its colour table.
  const fs::path volume = root_ / "atlas.nii", table = root_ / "labels.csv";
  WriteFile(volume, std::string(352, '\0') + "voxels");
  WriteFile(table, "1,Putamen\n");
  AtlasBuildOptions labels;
  labels.source = AtlasBuildOptions::Source::kLabelVolume;
  labels.input = volume;
  const std::string built_in = key_of(labels);
  labels.colour_table = table;
  const std::string with_table = key_of(labels);
  EXPECT_NE(with_table, built_in);
  WriteFile(table, "1,Putamem\n");
  EXPECT_NE(key_of(labels), with_table);
  WriteFile(table, "1,Putamen\n");
  EXPECT_EQ(key_of(labels), with_table);
  WriteFile(volume, std::string(352, '\0') + "voxelz");
  EXPECT_NE(key_of(labels), with_table);
  // A source that cannot be read has no key (the build reports it).
  labels.input = root_ / "missing.nii";
  std::string none;
  EXPECT_EQ(AtlasMeshCacheKey(labels, &none).code(), Status::Code::kIo);

  // The synthetic atlas: the options alone.
  AtlasBuildOptions synthetic;
  EXPECT_EQ(key_of(synthetic), key_of(synthetic));
  synthetic.synthetic_voxel_mm = 2;
  EXPECT_NE(key_of(synthetic), key_of(AtlasBuildOptions()));
}

TEST_F(AtlasMeshCacheTest, EvictionKeepsTheMostRecentlyUsedWithinTheBound) {
  const CachedAtlasMesh entry{TwoTets(), std::string(4000, 'd')};
  const auto key = [](char c) { return std::string(64, c); };
  const auto file = [&](char c) { return cache_ / (key(c) + ".mesh"); };
  ASSERT_TRUE(StoreCachedAtlasMesh(cache_, key('a'), entry).ok());
  const std::uint64_t size = fs::file_size(file('a'));
  ASSERT_TRUE(StoreCachedAtlasMesh(cache_, key('b'), entry).ok());
  ASSERT_TRUE(StoreCachedAtlasMesh(cache_, key('c'), entry).ok());
  // a used an hour ago, b two hours ago, c three.
  const auto now = fs::file_time_type::clock::now();
  fs::last_write_time(file('a'), now - std::chrono::hours(1));
  fs::last_write_time(file('b'), now - std::chrono::hours(2));
  fs::last_write_time(file('c'), now - std::chrono::hours(3));
  // A hit renews c.
  CachedAtlasMesh loaded;
  bool hit = false;
  ASSERT_TRUE(LoadCachedAtlasMesh(cache_, key('c'), &loaded, &hit).ok());
  ASSERT_TRUE(hit);
  // Room for three: storing d evicts the least recently used, b.
  ASSERT_TRUE(StoreCachedAtlasMesh(cache_, key('d'), entry, 3 * size + size / 2).ok());
  EXPECT_TRUE(fs::exists(file('a')));
  EXPECT_FALSE(fs::exists(file('b')));
  EXPECT_TRUE(fs::exists(file('c')));
  EXPECT_TRUE(fs::exists(file('d')));
  // Room for less than one: the new entry stays, alone.
  WriteFile(cache_ / "notes.txt", "not an entry");
  ASSERT_TRUE(StoreCachedAtlasMesh(cache_, key('e'), entry, size / 2).ok());
  EXPECT_TRUE(fs::exists(file('e')));
  EXPECT_FALSE(fs::exists(file('a')));
  EXPECT_FALSE(fs::exists(file('c')));
  EXPECT_FALSE(fs::exists(file('d')));
  EXPECT_TRUE(fs::exists(cache_ / "notes.txt"));  // not ours to remove
}

// A structure set (a snapshot staged or exported) is keyed by its
// structures, not by the snapshot it came from: two snapshots pinning the
// same revisions share one mesh; a changed structure does not.
TEST_F(AtlasMeshCacheTest, AStructureSetIsKeyedByItsStructuresNotItsSnapshot) {
  const auto write_set = [&](const std::string& dir, int64_t snapshot, const std::string& x) {
    const fs::path d = root_ / dir;
    fs::create_directories(d);
    WriteFile(d / "a.json",
              "{\"plates\": [{\"z_mm\": 0, \"polygons\": [[[0, 0], [" + x + ", 0], [0, 5]]]}]}");
    StructureSet set;
    set.project = "demo";
    set.snapshot = snapshot;
    StructureEntry entry;
    entry.name = "A";
    entry.file = "a.json";
    entry.r = 10;
    set.structures.push_back(entry);
    EXPECT_TRUE(WriteStructureSet(set, d).ok());
    AtlasBuildOptions options;
    options.source = AtlasBuildOptions::Source::kStructures;
    options.input = d;
    std::string key;
    EXPECT_TRUE(AtlasMeshCacheKey(options, &key).ok());
    return key;
  };
  const std::string first = write_set("s1", 1, "5");
  EXPECT_EQ(write_set("s2", 2, "5"), first);
  EXPECT_NE(write_set("s3", 3, "6"), first);
}

}  // namespace
}  // namespace pba
