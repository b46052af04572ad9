// SurfaceViews (service/surface_views.h) with a stand-in for pba-solve, a
// shell script whose behaviour a file beside it chooses: an entry is built
// once and found after; the key follows the shapes, not their colours or
// revision numbers; a solver's error, a build past its time and a caller
// gone each end with a clear status and leave nothing in the cache; the
// child runs under the address-space bound; the cache keeps to its size.
#include "service/surface_views.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <thread>

#include "core/sha256.h"
#include "unit/server/temp_dir.h"

namespace pba {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// The stand-in: writes <out>/surfaces.glb (a 12-byte glTF header) and
// appends a line to `calls`, or does what `mode` says first.
constexpr char kScript[] = R"(#!/bin/sh
here=$(dirname "$0")
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift ;;
    --atlas-surfaces) set="$2"; shift ;;
  esac
  shift
done
echo call >> "$here/calls"
cp "$set/manifest.json" "$here/manifest.json"
mode=$(cat "$here/mode" 2>/dev/null)
case "$mode" in
  error)
    echo '{"kind":"ERROR","code":"INVALID_ARGUMENT","message":"structures: Slab has no plates"}'
    echo 'pba-solve: error: structures: Slab has no plates' >&2
    exit 5 ;;
  crash) kill -SEGV $$ ;;
  sleep) sleep 30 ;;
  limit) ulimit -v > "$here/limit" ;;
esac
mkdir -p "$out"
printf 'glTF\002\000\000\000\014\000\000\000' > "$out/surfaces.glb"
)";

class SurfaceViewsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    solver_ = dir_.path() / "fake-solve";
    std::ofstream(solver_) << kScript;
    ::chmod(solver_.c_str(), 0755);
    options_.solver = solver_;
    options_.cache_dir = dir_.path() / "cache";
    options_.time_limit = std::chrono::seconds(30);
    for (const char* name : {"Block", "Slab"}) files_.push_back(File(name, name));
  }

  // A structure `name` whose geometry is the text `content`.
  SnapshotFile File(const std::string& name, const std::string& content) {
    SnapshotFile file;
    file.blob = dir_.path() / ("blob-" + name + "-" + std::to_string(files_.size()));
    const std::string json = "{\"plates\": [], \"x\": \"" + content + "\"}";
    std::ofstream(file.blob) << json;
    file.revision.structure = name;
    file.revision.number = 1;
    file.revision.format = StructureFormat::kContours;
    file.revision.content_sha256 = Sha256Hex(json);
    file.revision.metadata.colour = {200, 10, static_cast<int>(files_.size()) + 1};
    return file;
  }

  void Mode(const std::string& mode) { std::ofstream(dir_.path() / "mode") << mode; }
  int Calls() {
    std::ifstream in(dir_.path() / "calls");
    std::string line;
    int n = 0;
    while (std::getline(in, line)) ++n;
    return n;
  }
  // What the cache directory holds: entries and anything else.
  std::pair<int, int> CacheContents() {
    int entries = 0, others = 0;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(options_.cache_dir, ec)) {
      (e.path().extension() == ".glb" ? entries : others) += 1;
    }
    return {entries, others};
  }

  TempDir dir_;
  fs::path solver_;
  SurfaceViewOptions options_;
  std::vector<SnapshotFile> files_;
};

TEST_F(SurfaceViewsTest, BuildsOnceAndFindsTheEntryAfter) {
  SurfaceViews views(options_);
  SurfaceView first, second;
  ASSERT_TRUE(views.Get("demo", 3, files_, {}, &first).ok());
  EXPECT_FALSE(first.cached);
  EXPECT_EQ(first.bytes.substr(0, 4), "glTF");
  EXPECT_EQ(first.glb, options_.cache_dir / (first.key + ".glb"));
  ASSERT_TRUE(views.Get("demo", 3, files_, {}, &second).ok());
  EXPECT_TRUE(second.cached);
  EXPECT_EQ(second.bytes, first.bytes);
  EXPECT_EQ(Calls(), 1);
  EXPECT_EQ(CacheContents(), std::make_pair(1, 0)) << "no scratch folder is left";
  // An entry whose length is not its header's (cut short, or added to) is
  // built again, not sent.
  std::ofstream(first.glb, std::ios::app) << "more";
  SurfaceView third;
  ASSERT_TRUE(views.Get("demo", 3, files_, {}, &third).ok());
  EXPECT_FALSE(third.cached);
  EXPECT_EQ(third.bytes, first.bytes);
  EXPECT_EQ(Calls(), 2);
  // The solver was given the structures as a set naming the project.
  std::ifstream manifest(dir_.path() / "manifest.json");
  const std::string text((std::istreambuf_iterator<char>(manifest)),
                         std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"Slab\""), std::string::npos) << text;
  EXPECT_NE(text.find("\"demo\""), std::string::npos) << text;
}

TEST_F(SurfaceViewsTest, TheKeyIsTheShapesNotTheirColoursOrRevisions) {
  SurfaceViews views(options_);
  const std::string key = views.KeyOf(files_);
  std::vector<SnapshotFile> recoloured = files_;
  recoloured[1].revision.metadata.colour = {1, 2, 3};
  recoloured[1].revision.number = 7;
  recoloured[1].revision.metadata.material_json = "{\"mu_pa\": 1}";
  EXPECT_EQ(views.KeyOf(recoloured), key);
  std::vector<SnapshotFile> reshaped = files_;
  reshaped[1] = File("Slab", "wider");
  EXPECT_NE(views.KeyOf(reshaped), key);
  std::vector<SnapshotFile> renamed = files_;
  renamed[1].revision.structure = "Slab2";
  EXPECT_NE(views.KeyOf(renamed), key);
  std::vector<SnapshotFile> alone = {files_[1]};
  EXPECT_NE(views.KeyOf(alone), key);
  SurfaceViewOptions finer = options_;
  finer.facet_mm = 2;
  EXPECT_NE(SurfaceViews(finer).KeyOf(files_), key);
}

TEST_F(SurfaceViewsTest, ASolversErrorIsItsMessageAndNothingIsKept) {
  Mode("error");
  SurfaceViews views(options_);
  SurfaceView view;
  const Status status = views.Get("demo", 0, files_, {}, &view);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_NE(status.message().find("Slab has no plates"), std::string::npos) << status.ToString();
  EXPECT_EQ(CacheContents(), std::make_pair(0, 0));
  Mode("crash");
  const Status crashed = views.Get("demo", 0, files_, {}, &view);
  EXPECT_FALSE(crashed.ok());
  EXPECT_NE(crashed.message().find("signal"), std::string::npos) << crashed.ToString();
  EXPECT_EQ(CacheContents(), std::make_pair(0, 0));
}

TEST_F(SurfaceViewsTest, ABuildPastItsTimeOrWhoseCallerWentIsKilled) {
  Mode("sleep");
  options_.time_limit = std::chrono::seconds(1);
  SurfaceViews views(options_);
  SurfaceView view;
  auto start = std::chrono::steady_clock::now();
  const Status late = views.Get("demo", 0, files_, {}, &view);
  EXPECT_EQ(late.code(), Status::Code::kInvalidArgument);
  EXPECT_NE(late.message().find("longer than 1 s"), std::string::npos) << late.ToString();
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));

  options_.time_limit = std::chrono::seconds(60);
  SurfaceViews patient(options_);
  std::atomic<bool> gone{false};
  std::thread leave([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    gone = true;
  });
  start = std::chrono::steady_clock::now();
  const Status cancelled = patient.Get(
      "demo", 0, files_, [&] { return gone.load(); }, &view);
  leave.join();
  EXPECT_EQ(cancelled.code(), Status::Code::kCancelled) << cancelled.ToString();
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  EXPECT_EQ(CacheContents(), std::make_pair(0, 0));
}

// One build at a time: a caller that finds the turn taken past its
// patience is told the server is busy meshing, naming the bound.
TEST_F(SurfaceViewsTest, ACallerWaitingPastItsPatienceIsToldTheServerIsBusy) {
  Mode("sleep");
  options_.time_limit = std::chrono::seconds(2);
  options_.patience = std::chrono::milliseconds(300);
  SurfaceViews views(options_);
  std::thread first([&] {
    SurfaceView view;
    (void)views.Get("demo", 0, files_, {}, &view);
  });
  while (Calls() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  SurfaceView view;
  const Status busy = views.Get("demo", 0, {File("Other", "other")}, {}, &view);
  first.join();
  EXPECT_EQ(busy.code(), Status::Code::kResourceExhausted) << busy.ToString();
  EXPECT_EQ(busy.field(), "surface_builds");
  EXPECT_NE(busy.message().find("meshing other structures' surfaces"), std::string::npos)
      << busy.ToString();
}

TEST_F(SurfaceViewsTest, TheChildRunsUnderTheMemoryBound) {
  Mode("limit");
  options_.memory_bytes = int64_t{3} << 30;
  SurfaceViews views(options_);
  SurfaceView view;
  ASSERT_TRUE(views.Get("demo", 0, files_, {}, &view).ok());
  std::ifstream limit(dir_.path() / "limit");
  int64_t kib = 0;
  ASSERT_TRUE(limit >> kib);
  EXPECT_EQ(kib, options_.memory_bytes / 1024);
}

TEST_F(SurfaceViewsTest, TheCacheKeepsToItsBoundDroppingTheLeastRecentlyUsed) {
  options_.cache_bytes = 2500;
  fs::create_directories(options_.cache_dir);
  const auto now = fs::file_time_type::clock::now();
  for (int i = 0; i < 4; ++i) {
    const fs::path entry = options_.cache_dir / ("entry" + std::to_string(i) + ".glb");
    std::ofstream(entry) << std::string(1000, 'x');
    fs::last_write_time(entry, now - std::chrono::hours(4 - i));
  }
  SurfaceViews views(options_);
  // The oldest is kept when it is the one just used.
  views.Prune(options_.cache_dir / "entry0.glb");
  EXPECT_TRUE(fs::exists(options_.cache_dir / "entry0.glb"));
  EXPECT_FALSE(fs::exists(options_.cache_dir / "entry1.glb"));
  EXPECT_FALSE(fs::exists(options_.cache_dir / "entry2.glb"));
  EXPECT_TRUE(fs::exists(options_.cache_dir / "entry3.glb"));
  // A build's scratch folder a killed server left goes at the next start.
  fs::create_directories(options_.cache_dir / ".build-123-0" / "set");
  SurfaceViews restarted(options_);
  EXPECT_FALSE(fs::exists(options_.cache_dir / ".build-123-0"));
}

}  // namespace
}  // namespace pba
