// End to end through the real pba-server (with the real pba-solve) and the
// real pba client: an atlas imported into a project as a job, a scene run
// against the snapshot the import made, the project's watchers told of the
// job, the snapshot exported and solved again locally to the same mesh; a
// label volume imported, and a second import of the same structures failing
// without writing anything; AAL, a real atlas, imported, checked against at
// the submit and exported whole; a derived structure made in a job's atlas.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <future>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <thread>

#include "atlas/structure_set.h"
#include "common/subprocess.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;
using std::chrono::seconds;

constexpr int kJobFailed = 6;

// The first match of `pattern`'s group 1 in `text`, or "".
std::string Find(const std::string& text, const std::string& pattern) {
  std::smatch match;
  return std::regex_search(text, match, std::regex(pattern)) ? match[1].str() : "";
}

class CliAtlasJobsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    data_ = dir_.path() / "data";
    server_ = std::make_unique<ServerProcess>(PBA_SERVER_BIN, data_);
    std::string log;
    ASSERT_TRUE(server_->Start(&log)) << "pba-server did not start:\n" << log;
    token_ = ReadFile(data_ / "admin.token");
    while (!token_.empty() && token_.back() == '\n') token_.pop_back();
    ASSERT_EQ(Pba({"project", "create", "demo"}).exit_code, 0);
  }

  void TearDown() override {
    if (HasFailure()) std::cerr << "server log:\n" << ReadFile(server_->log_path());
  }

  RunResult Pba(std::vector<std::string> args, seconds timeout = seconds(300)) {
    args.insert(args.begin(), {PBA_CLI_BIN, "--server", server_->address()});
    return RunProcess(args, {"PBA_TOKEN=" + token_}, timeout);
  }

  TempDir dir_;
  fs::path data_;
  std::unique_ptr<ServerProcess> server_;
  std::string token_;
};

TEST_F(CliAtlasJobsTest, ImportRunAgainstTheSnapshotExportAndReproduce) {
  const std::string scene = std::string(PBA_EXAMPLES_DIR) + "/basal_ganglia_push.yaml";
  const RunResult imported =
      Pba({"atlas", "import", "-p", "demo", "--synthetic", "--structure", "Putamen", "--structure",
           "Globus pallidus lateralis", "--snapshot-name", "basal ganglia"});
  ASSERT_EQ(imported.exit_code, 0) << imported.out << imported.err;
  EXPECT_NE(imported.out.find("Imported into demo: snapshot 1"), std::string::npos) << imported.out;
  const RunResult listed = Pba({"atlas", "list", "-p", "demo"});
  EXPECT_NE(listed.out.find("Putamen"), std::string::npos) << listed.out;
  EXPECT_NE(listed.out.find("Globus pallidus lateralis"), std::string::npos) << listed.out;

  // A watcher of the project (for the tag below and the job's three
  // states), then a job against the snapshot.
  std::promise<RunResult> watched;
  std::thread watcher([&] {
    watched.set_value(Pba({"atlas", "watch", "-p", "demo", "--count", "4"}, seconds(300)));
  });
  // Joined however the test leaves (the watch ends at its own timeout).
  struct Joiner {
    std::thread& thread;
    ~Joiner() {
      if (thread.joinable()) thread.join();
    }
  } joiner{watcher};
  std::this_thread::sleep_for(std::chrono::seconds(2));
  // A snapshot is named by the name it was given, its id or a tag.
  const RunResult job =
      Pba({"--json", "job", "submit", scene, "--snapshot", "demo/basal ganglia", "--wait"});
  ASSERT_EQ(job.exit_code, 0) << job.out << job.err;

  // The job names the snapshot it ran against, by id.
  EXPECT_NE(job.out.find(R"("project": "demo")"), std::string::npos) << job.out;
  EXPECT_NE(job.out.find(R"("snapshot": "1")"), std::string::npos) << job.out;
  EXPECT_NE(job.out.find("atlas of snapshot 1 of project demo (2 structures)"), std::string::npos)
      << job.out;
  const std::string elements = Find(job.out, R"re("elements": "([0-9]+)")re");
  ASSERT_FALSE(elements.empty()) << job.out;
  EXPECT_NE(job.out.find("built, cached as"), std::string::npos) << job.out;

  // The same atlas again, by a tag: its mesh from the cache.
  const RunResult tag = Pba({"atlas", "tag", "-p", "demo", "1", "basal"});
  ASSERT_EQ(tag.exit_code, 0) << tag.out << tag.err;
  const RunResult again =
      Pba({"--json", "job", "submit", scene, "--snapshot", "demo/basal", "--wait"});
  ASSERT_EQ(again.exit_code, 0) << again.out << again.err;
  EXPECT_NE(again.out.find("atlas mesh from the cache"), std::string::npos) << again.out;
  EXPECT_EQ(Find(again.out, R"re("elements": "([0-9]+)")re"), elements);

  // The watcher's four events: the first job's three states and the tag,
  // in that order. (One that subscribed late on a loaded machine misses
  // the first states; the second job's, after the tag, make up its count.)
  watcher.join();
  const RunResult watch = watched.get_future().get();
  EXPECT_EQ(watch.exit_code, 0) << watch.out << watch.err;
  const std::size_t queued = watch.out.find("job queued"), running = watch.out.find("job running"),
                    succeeded = watch.out.find("job succeeded"),
                    tagged = watch.out.find("snapshot tagged    snapshot 1: basal");
  EXPECT_NE(tagged, std::string::npos) << watch.out;
  EXPECT_LT(succeeded, tagged) << watch.out;
  if (queued < tagged) {
    EXPECT_LT(queued, running) << watch.out;
  }
  if (running < tagged) {
    EXPECT_LT(running, succeeded) << watch.out;
  }

  // Anyone can rebuild it from an export of the snapshot.
  const fs::path exported = dir_.path() / "exported";
  const RunResult exporting = Pba({"atlas", "export", "-p", "demo", "1", "-o", exported.string()});
  ASSERT_EQ(exporting.exit_code, 0) << exporting.out << exporting.err;
  std::string local_scene = ReadFile(scene);
  local_scene = std::regex_replace(local_scene, std::regex("voxel_size_mm: 2"),
                                   "voxel_size_mm: 2\n    source: " + exported.string());
  const fs::path local = dir_.path() / "local.yaml";
  std::ofstream(local) << local_scene;
  const RunResult solved = RunProcess({PBA_SOLVE_BIN, local.string(), "--out",
                                       (dir_.path() / "local").string(), "--progress", "none"},
                                      seconds(300));
  ASSERT_EQ(solved.exit_code, 0) << solved.out << solved.err;
  const std::string summary = ReadFile(dir_.path() / "local" / "summary.json");
  EXPECT_EQ(Find(summary, R"re("elements": "([0-9]+)")re"), elements) << summary;
  EXPECT_NE(summary.find("atlas of snapshot 1 of project demo"), std::string::npos) << summary;
}

// A derived structure in the store: created with the real client from a
// recipe, refused when it reads a structure the project lacks, pinned by a
// snapshot and made when a job's atlas is composed; the structures its
// merge takes are gone from that atlas, and a scene naming one fails
// saying so.
TEST_F(CliAtlasJobsTest, ADerivedStructureIsMadeWhenASnapshotIsMeshed) {
  const RunResult imported =
      Pba({"atlas", "import", "-p", "demo", "--synthetic", "--structure", "Putamen", "--structure",
           "Globus pallidus lateralis", "--structure", "Nucleus caudatus"});
  ASSERT_EQ(imported.exit_code, 0) << imported.out << imported.err;
  const fs::path recipe = dir_.path() / "lentiform.yaml";
  std::ofstream(recipe) << "merge: [Putamen, Globus pallidus lateralis]\n";
  const fs::path bad = dir_.path() / "bad.yaml";
  std::ofstream(bad) << "merge: [Putamen, Pallidum]\n";
  const RunResult refused =
      Pba({"atlas", "create", "-p", "demo", "Bad", bad.string(), "--colour", "1,2,3"});
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.err.find("reads 'Pallidum', which is not among the structures"),
            std::string::npos)
      << refused.err;
  const RunResult created = Pba({"atlas", "create", "-p", "demo", "Lentiform nucleus",
                                 recipe.string(), "--colour", "200,120,40"});
  ASSERT_EQ(created.exit_code, 0) << created.out << created.err;
  const RunResult listed = Pba({"atlas", "list", "-p", "demo"});
  EXPECT_NE(listed.out.find("Lentiform nucleus"), std::string::npos) << listed.out;
  EXPECT_EQ(listed.out.find("Bad"), std::string::npos) << listed.out;
  const RunResult snapshot = Pba({"atlas", "snapshot", "create", "-p", "demo", "--name", "lent"});
  ASSERT_EQ(snapshot.exit_code, 0) << snapshot.out << snapshot.err;

  // The lentiform nucleus pushed as one structure.
  const fs::path scene = dir_.path() / "lentiform_push.yaml";
  std::string text = ReadFile(std::string(PBA_EXAMPLES_DIR) + "/basal_ganglia_push.yaml");
  text =
      std::regex_replace(text, std::regex("structures: \\[Putamen, Globus pallidus lateralis\\]"),
                         "structures: [Lentiform nucleus]");
  text = std::regex_replace(text, std::regex("surface:Putamen"), "surface:Lentiform nucleus");
  std::ofstream(scene) << text;
  const RunResult job =
      Pba({"--json", "job", "submit", scene.string(), "--snapshot", "demo/lent", "--wait"});
  ASSERT_EQ(job.exit_code, 0) << job.out << job.err;
  EXPECT_NE(job.out.find("(4 structures)"), std::string::npos) << job.out;
  EXPECT_NE(job.out.find("derived structure 'Lentiform nucleus' (merge)"), std::string::npos)
      << job.out;

  // The putamen is part of it now: a scene naming it fails at the build,
  // naming it.
  const RunResult putamen =
      Pba({"--json", "job", "submit", std::string(PBA_EXAMPLES_DIR) + "/basal_ganglia_push.yaml",
           "--snapshot", "demo/lent", "--wait"});
  EXPECT_EQ(putamen.exit_code, kJobFailed) << putamen.out << putamen.err;
  EXPECT_TRUE(
      std::regex_search(putamen.out + putamen.err,
                        std::regex(R"(the atlas \(2 structures\) has no structure \\?"Putamen)")))
      << putamen.out << putamen.err;
  // The reason says where once.
  EXPECT_EQ(putamen.out.find("structures[0]: geometry.atlas.structures[0]"), std::string::npos)
      << putamen.out;

  // Exported, the recipe travels as a file of the set.
  const fs::path exported = dir_.path() / "exported";
  ASSERT_EQ(Pba({"atlas", "export", "-p", "demo", "lent", "-o", exported.string()}).exit_code, 0);
  StructureSet set;
  ASSERT_TRUE(ReadStructureSet(exported, &set).ok());
  const auto lentiform =
      std::find_if(set.structures.begin(), set.structures.end(),
                   [](const StructureEntry& e) { return e.name == "Lentiform nucleus"; });
  ASSERT_NE(lentiform, set.structures.end());
  EXPECT_EQ(lentiform->format, StructureFormat::kDerived);
  EXPECT_EQ(ReadFile(exported / lentiform->file), ReadFile(recipe));
}

TEST_F(CliAtlasJobsTest, ALabelVolumeImportAndARepeatThatFailsWritingNothing) {
  const fs::path plates = dir_.path() / "plates";
  const RunResult written = RunProcess({PBA_ATLAS_BIN, "plates", "-o", plates.string()});
  ASSERT_EQ(written.exit_code, 0) << written.out << written.err;
  const std::string labels = (plates / "labels.nii.gz").string();
  const RunResult imported = Pba({"atlas", "import", "-p", "demo", "--labels", labels,
                                  "--structure", "Putamen", "--structure", "Ventricles"});
  ASSERT_EQ(imported.exit_code, 0) << imported.out << imported.err;
  const RunResult shown = Pba({"atlas", "show", "-p", "demo", "Ventricles"});
  EXPECT_NE(shown.out.find("nifti"), std::string::npos) << shown.out;

  // The same structures again: the job fails naming one, and nothing is written.
  const RunResult repeat =
      Pba({"atlas", "import", "-p", "demo", "--labels", labels, "--structure", "Putamen"});
  EXPECT_EQ(repeat.exit_code, kJobFailed) << repeat.out << repeat.err;
  EXPECT_NE(repeat.err.find("'Putamen'"), std::string::npos) << repeat.err;
  const RunResult snapshots = Pba({"--json", "atlas", "snapshot", "list", "-p", "demo"});
  EXPECT_EQ(Find(snapshots.out, R"re("id": "?([0-9]+))re"), "1") << snapshots.out;
  EXPECT_EQ(snapshots.out.find(R"("id": "2")"), std::string::npos) << snapshots.out;
  const RunResult history = Pba({"atlas", "history", "-p", "demo", "Putamen"});
  EXPECT_EQ(history.exit_code, 0);
  EXPECT_EQ(history.out.find("\n2 "), std::string::npos) << history.out;

  // A label volume import needs its volume.
  const RunResult bad =
      Pba({"atlas", "import", "-p", "demo", "--plates", plates.string(), "--structure", "Putamen"});
  EXPECT_NE(bad.exit_code, 0);
}

// structures.csv of pba-atlas labels: each structure's volume [mm^3].
std::map<std::string, double> StructureVolumesMm3(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  std::map<std::string, double> volumes;
  while (std::getline(in, line)) {
    const std::size_t first = line.find(','), last = line.rfind(',');
    const std::size_t voxels = line.rfind(',', last - 1);
    volumes[line.substr(first + 1, voxels - first - 1)] = 1000 * std::stod(line.substr(last + 1));
  }
  return volumes;
}

// AAL as Debian ships it, its white matter filled by pba-atlas, through the
// server: imported with its table under a snapshot name, all 117 structures
// in the project; a scene against the snapshot, named by that name, naming
// a structure AAL lacks is refused at the submit with the nearest names;
// the snapshot exported holds every structure with the volume it had.
TEST_F(CliAtlasJobsTest, AalImportedIntoASnapshotAndExportedKeepsEveryStructure) {
  const fs::path t = "/usr/share/mricron/templates";
  const fs::path local = dir_.path() / "aal";
  RunResult run =
      RunProcess({PBA_ATLAS_BIN, "labels", "-o", local.string(), "--labels",
                  (t / "aal.nii.gz").string(), "--colour-table", (t / "aal.nii.txt").string(),
                  "--fill", "White matter", "--closing-mm", "7"});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  const std::map<std::string, double> volumes = StructureVolumesMm3(local / "structures.csv");
  ASSERT_EQ(volumes.size(), 117u);

  run = Pba({"atlas", "import", "-p", "demo", "--labels", (local / "labels.nii.gz").string(),
             "--colour-table", (local / "labels.csv").string(), "--snapshot-name", "AAL filled"});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_NE(run.out.find("Imported into demo: snapshot 1"), std::string::npos) << run.out;
  const RunResult listed = Pba({"atlas", "list", "-p", "demo", "--all"});
  for (const auto& [name, volume] : volumes)
    EXPECT_NE(listed.out.find(name), std::string::npos) << name << " is not in the project";

  const fs::path scene = dir_.path() / "aal_scene.yaml";
  std::ofstream(scene)
      << "geometry:\n  atlas: {}\n"
         "mesh: {element_size_mm: 8}\n"
         "material: {neo_hookean: {shear_modulus_pa: 1000, bulk_modulus_pa: 1e6}}\n"
         "boundary_conditions: [{set: 'surface:Precentral_R', fixed: {}}]\n"
         "outputs: {structure_displacements: [Caudate_L, Caudate_Left]}\n"
         "analysis: {type: NONLINEAR_STATIC}\n";
  run = Pba({"job", "submit", scene.string(), "--snapshot", "demo/AAL filled"});
  EXPECT_EQ(run.exit_code, 5) << run.out << run.err;
  EXPECT_NE(run.err.find("has no structure \"Caudate_Left\"; nearest names: \"Caudate_L\""),
            std::string::npos)
      << run.err;
  const RunResult jobs = Pba({"job", "list"});
  EXPECT_EQ(jobs.out.find("aal_scene"), std::string::npos) << jobs.out;

  const fs::path exported = dir_.path() / "exported";
  run = Pba({"atlas", "export", "-p", "demo", "AAL filled", "-o", exported.string()});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  // Composed again from the export at its masks' own voxels, each
  // structure's volume is the local one, voxel for voxel, and no two
  // structures overlap.
  StructureSet set;
  ASSERT_TRUE(ReadStructureSet(exported, &set).ok());
  EXPECT_EQ(set.snapshot_name, "AAL filled");
  ComposeOptions compose;
  compose.voxel_size_mm = 0;
  ComposedAtlas again;
  const Status composed = ComposeStructureSet(exported, set, compose, &again);
  ASSERT_TRUE(composed.ok()) << composed.ToString();
  EXPECT_TRUE(again.overlaps.empty());
  ASSERT_EQ(again.structure_mm3.size(), volumes.size());
  for (const auto& [name, volume] : volumes) {
    ASSERT_TRUE(again.structure_mm3.count(name)) << name;
    EXPECT_NEAR(again.structure_mm3.at(name), volume, 1e-6 * volume) << name;
  }
}

}  // namespace
}  // namespace pba::testing
