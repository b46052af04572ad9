// The real pba client against a hostile fake server: a small gRPC server in
// this process (JobService and AtlasService from the generated code, on
// 127.0.0.1 with an ephemeral port) that names its files "../escaped.txt",
// an absolute path, "../../x" and the like. The client must write nothing
// outside the directory it was given, follow no link, overwrite no file of
// the user's without --force and remove nothing it did not make.

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "atlas/structure_set.h"
#include "common/subprocess.h"
#include "core/sha256.h"
#include "pba/v1/atlas.grpc.pb.h"
#include "pba/v1/job.grpc.pb.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;

constexpr int kExitError = 1;
constexpr int kExitInvalid = 5;
constexpr int kExitConflict = 9;

void WriteFile(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

// Every path under `root` (links not followed), to see what a run wrote.
std::set<std::string> Tree(const fs::path& root) {
  std::set<std::string> paths;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    paths.insert(fs::relative(entry.path(), root).string());
  }
  return paths;
}

// Streams `content` from `offset` as one chunk.
grpc::Status Stream(const std::string& content, int64_t offset,
                    grpc::ServerWriter<v1::DataChunk>* writer) {
  if (offset < 0 || offset > static_cast<int64_t>(content.size())) {
    return grpc::Status(grpc::OUT_OF_RANGE, "offset");
  }
  v1::DataChunk chunk;
  chunk.set_offset(offset);
  chunk.set_data(content.substr(static_cast<size_t>(offset)));
  chunk.set_total_size(static_cast<int64_t>(content.size()));
  writer->Write(chunk);
  return grpc::Status::OK;
}

// One succeeded job whose result files are whatever the test says.
class FakeJobs final : public v1::JobService::Service {
 public:
  void SetFiles(std::map<std::string, std::string> files) {
    std::lock_guard<std::mutex> lock(mutex_);
    files_ = std::move(files);
  }

  grpc::Status GetJob(grpc::ServerContext*, const v1::GetJobRequest* request,
                      v1::Job* job) override {
    std::lock_guard<std::mutex> lock(mutex_);
    job->set_id(request->id());
    job->set_name("hostile");
    job->set_state(v1::Job::SUCCEEDED);
    for (const auto& [name, content] : files_) {
      v1::ResultFile* file = job->add_result_files();
      file->set_name(name);
      file->set_size_bytes(static_cast<int64_t>(content.size()));
      file->set_sha256(Sha256Hex(content));
    }
    return grpc::Status::OK;
  }

  grpc::Status DownloadResult(grpc::ServerContext*, const v1::DownloadResultRequest* request,
                              grpc::ServerWriter<v1::DataChunk>* writer) override {
    std::string content;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const auto it = files_.find(request->file());
      if (it == files_.end()) return grpc::Status(grpc::NOT_FOUND, "no such file");
      content = it->second;
    }
    return Stream(content, request->offset(), writer);
  }

 private:
  std::mutex mutex_;
  std::map<std::string, std::string> files_;
};

// One snapshot (id 1) of project "p" whose members, their names and
// contents, are whatever the test says; each structure has one revision.
class FakeAtlas final : public v1::AtlasService::Service {
 public:
  void SetStructures(std::map<std::string, std::string> structures) {
    std::lock_guard<std::mutex> lock(mutex_);
    structures_ = std::move(structures);
  }

  grpc::Status GetSnapshot(grpc::ServerContext*, const v1::GetSnapshotRequest* request,
                           v1::Snapshot* snapshot) override {
    std::lock_guard<std::mutex> lock(mutex_);
    snapshot->set_project(request->project());
    snapshot->set_id(1);
    for (const auto& entry : structures_) {
      v1::Snapshot::Member* member = snapshot->add_members();
      member->set_structure(entry.first);
      member->set_revision(1);
    }
    return grpc::Status::OK;
  }

  grpc::Status GetRevision(grpc::ServerContext*, const v1::GetRevisionRequest* request,
                           v1::Revision* revision) override {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = structures_.find(request->structure());
    if (it == structures_.end()) return grpc::Status(grpc::NOT_FOUND, "no such structure");
    Describe(it->first, it->second, revision);
    return grpc::Status::OK;
  }

  grpc::Status ListRevisions(grpc::ServerContext*, const v1::ListRevisionsRequest* request,
                             v1::ListRevisionsResponse* response) override {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = structures_.find(request->structure());
    if (it == structures_.end()) return grpc::Status(grpc::NOT_FOUND, "no such structure");
    Describe(it->first, it->second, response->add_revisions());
    return grpc::Status::OK;
  }

  grpc::Status DownloadGeometry(grpc::ServerContext*, const v1::DownloadGeometryRequest* request,
                                grpc::ServerWriter<v1::DataChunk>* writer) override {
    std::string content;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      const auto it = structures_.find(request->structure());
      if (it == structures_.end()) return grpc::Status(grpc::NOT_FOUND, "no such structure");
      content = it->second;
    }
    return Stream(content, request->offset(), writer);
  }

  grpc::Status AcquireLock(grpc::ServerContext*, const v1::AcquireLockRequest* request,
                           v1::Lock* lock) override {
    lock->set_project(request->project());
    lock->set_structure(request->structure());
    lock->set_holder("me");
    lock->set_lock_id("lock-1");
    return grpc::Status::OK;
  }

  grpc::Status ReleaseLock(grpc::ServerContext*, const v1::ReleaseLockRequest*,
                           v1::ReleaseLockResponse*) override {
    return grpc::Status::OK;
  }

 private:
  static void Describe(const std::string& name, const std::string& content,
                       v1::Revision* revision) {
    revision->set_project("p");
    revision->set_structure(name);
    revision->set_number(1);
    revision->set_format(v1::CONTOURS_JSON);
    revision->set_size_bytes(static_cast<int64_t>(content.size()));
    revision->set_content_sha256(Sha256Hex(content));
    // A colour of its own per name (a structure set needs distinct ones).
    int red = 0;
    for (unsigned char c : name) red = (red * 31 + c) % 240;
    revision->mutable_metadata()->mutable_colour()->set_r(10 + red);
    revision->mutable_metadata()->mutable_colour()->set_g(20);
    revision->mutable_metadata()->mutable_colour()->set_b(30);
  }

  std::mutex mutex_;
  std::map<std::string, std::string> structures_;
};

// A 20 x 20 x 10 mm box at x .. x + 20 as plate contours at z = 0 and 10.
std::string Contours(int x) {
  const std::string square = "[[[" + std::to_string(x) + ", 0], [" + std::to_string(x + 20) +
                             ", 0], [" + std::to_string(x + 20) + ", 20], [" + std::to_string(x) +
                             ", 20]]]";
  return R"({"plates": [{"z_mm": 0, "polygons": )" + square + R"(}, {"z_mm": 10, "polygons": )" +
         square + "}]}";
}

class HostileServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    grpc::ServerBuilder builder;
    int port = 0;
    builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
    builder.RegisterService(&jobs_);
    builder.RegisterService(&atlas_);
    server_ = builder.BuildAndStart();
    ASSERT_NE(server_, nullptr);
    ASSERT_GT(port, 0);
    address_ = "127.0.0.1:" + std::to_string(port);
    work_ = dir_.path() / "work";
    fs::create_directories(work_);
    fs::create_directories(dir_.path() / "home");
  }

  void TearDown() override { server_->Shutdown(); }

  // `pba --server ADDRESS args...`, with a home of its own (no kept token).
  RunResult Pba(std::vector<std::string> args) {
    args.insert(args.begin(), {PBA_CLI_BIN, "--server", address_});
    return RunProcess(args,
                      {"HOME=" + (dir_.path() / "home").string(),
                       "XDG_CONFIG_HOME=" + (dir_.path() / "home").string(), "PBA_TOKEN=token"});
  }

  TempDir dir_;
  fs::path work_;  // everything the client may touch is under here
  FakeJobs jobs_;
  FakeAtlas atlas_;
  std::unique_ptr<grpc::Server> server_;
  std::string address_;
};

TEST_F(HostileServerTest, FetchRefusesResultFileNamesThatAreNotPlainNames) {
  const fs::path out = work_ / "a" / "out";
  const fs::path absolute = work_ / "absolute.txt";
  const std::vector<std::string> hostile = {"../escaped.txt",
                                            absolute.string(),
                                            "../../escaped-too.txt",
                                            "sub/dir.txt",
                                            "..",
                                            ".",
                                            "",
                                            "back\\slash.txt",
                                            "bell\x07.txt",
                                            "esc\x1b[31mred.txt",
                                            std::string(300, 'n')};
  for (const std::string& name : hostile) {
    SCOPED_TRACE(name);
    jobs_.SetFiles({{"summary.json", "{}"}, {name, "pwned"}});
    const std::set<std::string> before = Tree(dir_.path());
    const RunResult run = Pba({"job", "fetch", "j1", "-o", out.string()});
    EXPECT_EQ(run.exit_code, kExitInvalid) << run.out << run.err;
    EXPECT_NE(run.err.find("not a plain file name"), std::string::npos) << run.err;
    // Nothing at all was written, not even the good file, nor the directory.
    EXPECT_EQ(Tree(dir_.path()), before);
    // A control character is shown escaped, never sent to the terminal.
    EXPECT_EQ(run.err.find('\x1b'), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(absolute));
  EXPECT_FALSE(fs::exists(work_ / "a" / "escaped.txt"));
  EXPECT_FALSE(fs::exists(work_ / "escaped-too.txt"));

  // Two names that are one file where case is folded.
  jobs_.SetFiles({{"Summary.json", "a"}, {"summary.json", "b"}});
  const RunResult twice = Pba({"job", "fetch", "j1", "-o", out.string()});
  EXPECT_EQ(twice.exit_code, kExitInvalid) << twice.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(HostileServerTest, FetchKeepsTheUsersFilesAndFollowsNoLink) {
  jobs_.SetFiles({{"summary.json", "{\"from\": \"server\"}"}, {"result.h5", "HDF5 bytes"}});
  const fs::path out = work_ / "out";
  fs::create_directories(out);
  WriteFile(out / "summary.json", "the user's own notes");

  // Refused before anything is downloaded, naming the file.
  const RunResult refused = Pba({"job", "fetch", "j1", "-o", out.string()});
  EXPECT_EQ(refused.exit_code, kExitConflict) << refused.out << refused.err;
  EXPECT_NE(refused.err.find("summary.json"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("--force"), std::string::npos) << refused.err;
  EXPECT_EQ(ReadFile(out / "summary.json"), "the user's own notes");
  EXPECT_FALSE(fs::exists(out / "result.h5"));

  // With --force the files are replaced.
  const RunResult forced = Pba({"job", "fetch", "j1", "-o", out.string(), "--force"});
  ASSERT_EQ(forced.exit_code, 0) << forced.out << forced.err;
  EXPECT_EQ(ReadFile(out / "summary.json"), "{\"from\": \"server\"}");
  EXPECT_EQ(ReadFile(out / "result.h5"), "HDF5 bytes");

  // A .part planted as a link to another file: not appended to, even with
  // --force; and a link where the file goes is replaced, not written through.
  const fs::path linked = work_ / "linked";
  fs::create_directories(linked);
  const fs::path victim = work_ / "victim.txt";
  WriteFile(victim, "precious");
  fs::create_symlink(victim, linked / "result.h5.part");
  const RunResult part = Pba({"job", "fetch", "j1", "-o", linked.string(), "--force"});
  EXPECT_EQ(part.exit_code, kExitError) << part.out << part.err;
  EXPECT_NE(part.err.find("symbolic link"), std::string::npos) << part.err;
  EXPECT_EQ(ReadFile(victim), "precious");
  fs::remove(linked / "result.h5.part");
  fs::create_symlink(victim, linked / "result.h5");
  const RunResult through = Pba({"job", "fetch", "j1", "-o", linked.string(), "--force"});
  ASSERT_EQ(through.exit_code, 0) << through.out << through.err;
  EXPECT_EQ(ReadFile(victim), "precious");
  EXPECT_FALSE(fs::is_symlink(linked / "result.h5"));
  EXPECT_EQ(ReadFile(linked / "result.h5"), "HDF5 bytes");
}

TEST_F(HostileServerTest, SnapshotExportRefusesStructureNamesThatLeaveTheDirectory) {
  const fs::path out = work_ / "a" / "b" / "out";
  fs::create_directories(out.parent_path());
  for (const std::string& name :
       {std::string("../../escaped-structure"), std::string("/abs"), std::string("sub/x"),
        std::string(".."), std::string("nul\x01")}) {
    SCOPED_TRACE(name);
    atlas_.SetStructures({{"Putamen", Contours(0)}, {name, Contours(10)}});
    const std::set<std::string> before = Tree(dir_.path());
    const RunResult run = Pba({"atlas", "snapshot", "export", "-p", "p", "1", "-o", out.string()});
    EXPECT_EQ(run.exit_code, kExitInvalid) << run.out << run.err;
    EXPECT_NE(run.err.find("cannot be a file name"), std::string::npos) << run.err;
    EXPECT_EQ(Tree(dir_.path()), before);
  }
  EXPECT_FALSE(fs::exists(work_ / "escaped-structure.json"));
}

TEST_F(HostileServerTest, SnapshotExportLeavesTheUsersPartDirectoryAlone) {
  atlas_.SetStructures({{"Putamen", Contours(0)}});
  const fs::path out = work_ / "export";
  // What an earlier client used as its staging directory, now the user's.
  fs::create_directories(work_ / "export.part");
  WriteFile(work_ / "export.part" / "keep.txt", "mine");
  const RunResult run = Pba({"atlas", "export", "-p", "p", "1", "-o", out.string()});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  EXPECT_EQ(ReadFile(work_ / "export.part" / "keep.txt"), "mine");
  EXPECT_EQ(ReadFile(out / "Putamen.json"), Contours(0));
  // Nothing of the export's own staging is left beside it.
  EXPECT_EQ(Tree(work_),
            (std::set<std::string>{"export", "export/Putamen.json", "export/manifest.json",
                                   "export.part", "export.part/keep.txt"}));
}

// A structure named "manifest" (a legal name) and two names that differ
// only in case: each gets a file of its own, the export reads back as a
// structure set with every SHA-256 matching, and pba-solve runs on it.
TEST_F(HostileServerTest, SnapshotExportGivesAStructureNamedManifestAFileOfItsOwn) {
  atlas_.SetStructures({{"manifest", Contours(0)}, {"Foo", Contours(10)}, {"foo", Contours(20)}});
  const fs::path out = work_ / "export";
  const RunResult run = Pba({"atlas", "export", "-p", "p", "1", "-o", out.string()});
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;
  StructureSet set;
  const Status read = ReadStructureSet(out, &set);
  ASSERT_TRUE(read.ok()) << read.ToString();
  std::map<std::string, std::string> files;
  for (const StructureEntry& e : set.structures) files[e.name] = e.file;
  EXPECT_EQ(files["manifest"], "manifest_2.json");
  EXPECT_EQ(files["Foo"], "Foo.json");
  EXPECT_EQ(files["foo"], "foo_2.json");
  EXPECT_EQ(ReadFile(out / "manifest_2.json"), Contours(0));

  // And it solves: pba-solve builds the structure named "manifest" from
  // the export (before, its file was the manifest and the SHA-256 failed).
  const fs::path scene = work_ / "scene.yaml";
  WriteFile(scene,
            "name: manifest-push\n"
            "geometry:\n"
            "  atlas:\n"
            "    voxel_size_mm: 2\n"
            "    source: " +
                out.string() +
                "\n"
                "    structures: [manifest]\n"
                "  patches:\n"
                "    - {name: low, set: \"surface:manifest\", plane_point_mm: [0, 0, 0], "
                "plane_normal: [0, 0, -1]}\n"
                "    - {name: high, set: \"surface:manifest\", plane_point_mm: [0, 0, 10], "
                "plane_normal: [0, 0, 1]}\n"
                "mesh: {element_size_mm: 4}\n"
                "material:\n"
                "  name: tissue\n"
                "  linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}\n"
                "boundary_conditions:\n"
                "  - {set: low, fixed: {}}\n"
                "  - {set: high, displacement: {z_mm: 0.5}}\n");
  const RunResult solved = RunProcess(
      {PBA_SOLVE_BIN, scene.string(), "--out", (work_ / "solved").string(), "--progress", "none"},
      std::chrono::seconds(300));
  ASSERT_EQ(solved.exit_code, 0) << solved.out << solved.err;
  EXPECT_TRUE(fs::exists(work_ / "solved" / "summary.json"));
}

// A checkout again after a refused commit (as docs/cli.md advises) keeps
// the edit as FILE.mine; a file the server has is simply replaced; --force
// overwrites.
TEST_F(HostileServerTest, ACheckoutAgainKeepsTheUsersEditAsMine) {
  atlas_.SetStructures({{"Putamen", Contours(0)}});
  const fs::path file = work_ / "putamen.json";
  WriteFile(file, "my edit");
  const RunResult first = Pba({"atlas", "checkout", "-p", "p", "Putamen", "-o", file.string()});
  ASSERT_EQ(first.exit_code, 0) << first.out << first.err;
  EXPECT_EQ(ReadFile(file), Contours(0));
  EXPECT_EQ(ReadFile(file.string() + ".mine"), "my edit");
  EXPECT_NE(first.err.find(file.string() + ".mine"), std::string::npos) << first.err;

  // The head itself is nothing to keep.
  const RunResult again = Pba({"atlas", "checkout", "-p", "p", "Putamen", "-o", file.string()});
  ASSERT_EQ(again.exit_code, 0) << again.out << again.err;
  EXPECT_FALSE(fs::exists(file.string() + ".mine.2"));

  // A second edit goes beside the first, not over it.
  WriteFile(file, "my second edit");
  ASSERT_EQ(Pba({"atlas", "checkout", "-p", "p", "Putamen", "-o", file.string()}).exit_code, 0);
  EXPECT_EQ(ReadFile(file.string() + ".mine"), "my edit");
  EXPECT_EQ(ReadFile(file.string() + ".mine.2"), "my second edit");

  WriteFile(file, "thrown away");
  const RunResult forced =
      Pba({"atlas", "checkout", "-p", "p", "Putamen", "-o", file.string(), "--force"});
  ASSERT_EQ(forced.exit_code, 0) << forced.out << forced.err;
  EXPECT_EQ(ReadFile(file), Contours(0));
  EXPECT_FALSE(fs::exists(file.string() + ".mine.3"));
}

}  // namespace
}  // namespace pba::testing
