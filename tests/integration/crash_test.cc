// Reliability of the store and the job service: the real pba-server killed
// with SIGKILL while it commits atlas revisions and while it runs a job, then
// restarted on the same data directory, and a batch of 200 small jobs. After
// each crash the database and the files beside it are read directly (SQLite C
// API, SHA-256 of the files) rather than through the server, so that a server
// that hides damage cannot pass.

#include <gtest/gtest.h>
#include <openssl/evp.h>
#include <sqlite3.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/subprocess.h"
#include "integration/block_scene.h"
#include "integration/db_query.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;
using std::chrono::milliseconds;
using std::chrono::seconds;
using Clock = std::chrono::steady_clock;

std::string Sha256Hex(const std::string& bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_Digest(bytes.data(), bytes.size(), digest, &length, EVP_sha256(), nullptr);
  static constexpr char kHex[] = "0123456789abcdef";
  std::string hex;
  for (unsigned int i = 0; i < length; ++i) {
    hex.push_back(kHex[digest[i] >> 4]);
    hex.push_back(kHex[digest[i] & 0xf]);
  }
  return hex;
}

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The whole file is sound and every reference resolves.
void ExpectDatabaseSound(const fs::path& data_dir) {
  const Rows integrity = Query(data_dir, "PRAGMA integrity_check");
  ASSERT_EQ(integrity.size(), 1u);
  EXPECT_EQ(integrity[0][0], "ok");
  const Rows dangling = Query(data_dir, "PRAGMA foreign_key_check");
  for (const auto& row : dangling) {
    ADD_FAILURE() << "foreign key broken: table " << row[0] << " rowid " << row[1] << " -> "
                  << row[2];
  }
}

// What the atlas part of the data directory holds.
struct BlobCensus {
  int referenced = 0;
  int orphans = 0;  // blobs no revision names
  int temp_files = 0;
};

// Every revision's blob exists under blobs/ab/cdef..., hashes to its name and
// has the revision's size; the blobs no revision names are counted.
BlobCensus CheckRevisionBlobs(const fs::path& data_dir) {
  BlobCensus census;
  std::set<std::string> referenced;
  for (const auto& row : Query(data_dir,
                               "SELECT content_sha256, size_bytes, structure, number "
                               "FROM structure_revisions")) {
    const std::string& hash = row[0];
    referenced.insert(hash);
    const fs::path path = data_dir / "blobs" / hash.substr(0, 2) / hash.substr(2);
    if (!fs::exists(path)) {
      ADD_FAILURE() << "revision " << row[3] << " of structure " << row[2] << ": blob " << hash
                    << " is missing";
      continue;
    }
    const std::string content = ReadFile(path);
    EXPECT_EQ(Sha256Hex(content), hash) << path;
    EXPECT_EQ(std::to_string(content.size()), row[1]) << path;
  }
  census.referenced = static_cast<int>(referenced.size());
  for (const auto& dir : fs::directory_iterator(data_dir / "blobs")) {
    const std::string dir_name = dir.path().filename().string();
    if (!dir.is_directory()) {
      ++census.temp_files;
      continue;
    }
    for (const auto& file : fs::directory_iterator(dir.path())) {
      const std::string name = file.path().filename().string();
      if (name[0] == '.') {
        ++census.temp_files;
      } else if (referenced.count(dir_name + name) == 0) {
        ++census.orphans;
      }
    }
  }
  return census;
}

// The revisions of structure `id` are numbered 1..n without a gap or a
// repeat, each one's parent is the one before, and the head is the last.
// Returns n.
int64_t ExpectRevisionChain(const fs::path& data_dir, const std::string& id) {
  const Rows rows = Query(data_dir,
                          "SELECT r.number, COALESCE(p.number, 0) FROM structure_revisions r "
                          "LEFT JOIN structure_revisions p ON p.id = r.parent "
                          "WHERE r.structure = " +
                              id + " ORDER BY r.number");
  for (size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(rows[i][0], std::to_string(i + 1)) << "revision numbers of structure " << id;
    EXPECT_EQ(rows[i][1], std::to_string(i)) << "parent of revision " << rows[i][0];
  }
  EXPECT_EQ(QueryOne(data_dir,
                     "SELECT r.number FROM structures s JOIN structure_revisions r "
                     "ON r.id = s.head_revision WHERE s.id = " +
                         id),
            std::to_string(rows.size()))
      << "the head is not the last revision";
  return static_cast<int64_t>(rows.size());
}

// Plate contours: a square of `side_mm`, written with three decimals so
// that every commit of the loop below has content of its own (and so a blob
// of its own).
std::string Contours(double side_mm) {
  char side[32];
  std::snprintf(side, sizeof side, "%.3f", side_mm);
  const std::string s = side;
  return R"({"plates":[{"z_mm":0,"polygons":[[[0,0],[)" + s + ",0],[" + s + "," + s + "],[0," + s +
         "]]]}]}";
}

// pba-solve processes anywhere on the machine whose command line names `dir`.
std::vector<pid_t> SolversUsing(const fs::path& dir) {
  std::vector<pid_t> out;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string pid = entry.path().filename().string();
    if (pid.find_first_not_of("0123456789") != std::string::npos) continue;
    std::string cmdline = ReadFile(entry.path() / "cmdline");
    std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
    if (cmdline.find("pba-solve") != std::string::npos &&
        cmdline.find(dir.string()) != std::string::npos) {
      out.push_back(static_cast<pid_t>(std::stol(pid)));
    }
  }
  return out;
}

class CrashTest : public ::testing::Test {
 protected:
  void SetUp() override {
    data_ = dir_.path() / "data";
    server_ = std::make_unique<ServerProcess>(PBA_SERVER_BIN, data_);
    // The client's own configuration stays inside the test's directory.
    ::setenv("XDG_CONFIG_HOME", dir_.path().c_str(), 1);
    ::unsetenv("PBA_PROJECT");
  }

  void TearDown() override {
    if (HasFailure()) std::cerr << "server log:\n" << ReadFile(server_->log_path());
    ::unsetenv("PBA_TOKEN");
  }

  // Starts (or restarts) the server; the first start's admin token is the
  // client's from then on.
  void StartServer(const std::vector<std::string>& extra_args = {}) {
    std::string log;
    ASSERT_TRUE(server_->Start(&log, extra_args)) << "pba-server did not start:\n" << log;
    std::string token = ReadFile(data_ / "admin.token");
    while (!token.empty() && std::isspace(static_cast<unsigned char>(token.back()))) {
      token.pop_back();
    }
    ASSERT_EQ(token.size(), 64u);
    ::setenv("PBA_TOKEN", token.c_str(), 1);
  }

  RunResult Pba(std::vector<std::string> args, seconds timeout = seconds(60)) {
    args.insert(args.begin(), {PBA_CLI_BIN, "--server", server_->address()});
    return RunProcess(args, timeout);
  }

  fs::path Write(const std::string& name, const std::string& content) {
    const fs::path path = dir_.path() / name;
    std::ofstream(path, std::ios::binary | std::ios::trunc) << content;
    return path;
  }

  std::string JobStatusJson(const std::string& id) {
    return Pba({"--json", "job", "status", id}).out;
  }

  // Polls the job's status every `period` until `pattern` matches it (each
  // poll is a pba process, which takes CPU from the solve it waits for).
  bool WaitForStatus(const std::string& id, const std::regex& pattern, seconds timeout,
                     milliseconds period = milliseconds(50)) {
    const auto deadline = Clock::now() + timeout;
    while (Clock::now() < deadline) {
      if (std::regex_search(JobStatusJson(id), pattern)) return true;
      std::this_thread::sleep_for(period);
    }
    return false;
  }

  TempDir dir_;
  fs::path data_;
  std::unique_ptr<ServerProcess> server_;
};

// --- 1. kill -9 while commits land --------------------------------------

// One structure's commits as its client saw them.
struct CommitLog {
  std::string name;
  std::string id;  // structures.id
  std::mutex mutex;
  // Revision number -> SHA-256 of what the client was told was committed as
  // it. Every one must survive every later crash.
  std::map<int64_t, std::string> acknowledged;
  // Revisions that landed while their client was told the commit failed (the
  // server died before it answered).
  int64_t landed_unacknowledged = 0;

  size_t Acknowledged() {
    std::lock_guard lock(mutex);
    return acknowledged.size();
  }
};

// Two clients commit to two structures of one project in checkout/commit
// cycles while the server is killed five times, each time at a random
// moment after commits have started to land.
TEST_F(CrashTest, KilledDuringCommitsTheStoreStaysWholeAndKeepsAcknowledgedCommits) {
  StartServer();
  ASSERT_EQ(Pba({"project", "create", "crash"}).exit_code, 0);
  CommitLog logs[2];
  logs[0].name = "Putamen";
  logs[1].name = "Caudate";
  for (CommitLog& log : logs) {
    const RunResult created = Pba({"atlas", "create", "-p", "crash", log.name,
                                   Write(log.name + ".json", Contours(5)).string()});
    ASSERT_EQ(created.exit_code, 0) << created.out << created.err;
    log.id = QueryOne(data_, "SELECT id FROM structures WHERE name = '" + log.name + "'");
    ASSERT_FALSE(log.id.empty());
  }

  std::atomic<int> cycles{0};
  const std::regex committed_revision("revision (\\d+)");
  // One checkout/commit cycle; true if the commit was acknowledged.
  auto commit_once = [&](CommitLog& log, bool must_succeed) {
    const int cycle = ++cycles;
    const fs::path file = dir_.path() / ("cycle" + std::to_string(cycle) + ".json");
    const RunResult checkout =
        Pba({"atlas", "checkout", "-p", "crash", log.name, "-o", file.string()}, seconds(30));
    if (must_succeed) {
      EXPECT_EQ(checkout.exit_code, 0) << checkout.out << checkout.err;
    }
    if (checkout.exit_code != 0) return false;
    // Content of its own, so a blob of its own.
    const std::string content = Contours(100 + 0.001 * cycle);
    std::ofstream(file, std::ios::trunc) << content;
    const RunResult commit = Pba(
        {"atlas", "commit", file.string(), "-m", "cycle " + std::to_string(cycle)}, seconds(30));
    if (must_succeed) {
      EXPECT_EQ(commit.exit_code, 0) << commit.out << commit.err;
    }
    std::smatch number;
    if (commit.exit_code != 0 || !std::regex_search(commit.out, number, committed_revision)) {
      return false;
    }
    std::lock_guard lock(log.mutex);
    EXPECT_EQ(log.acknowledged.count(std::stoll(number[1])), 0u) << "acknowledged twice";
    log.acknowledged[std::stoll(number[1])] = Sha256Hex(content);
    return true;
  };

  const unsigned seed = std::random_device()();
  std::printf("[ crash    ] kill delays drawn with seed %u\n", seed);
  std::mt19937 random(seed);
  constexpr int kKills = 5;
  int broken_locks = 0;
  int max_orphans = 0;
  const auto start = Clock::now();
  for (int kill = 0; kill < kKills; ++kill) {
    std::atomic<bool> stop{false};
    std::vector<std::thread> committers;
    std::vector<size_t> before;
    for (CommitLog& log : logs) {
      before.push_back(log.Acknowledged());
      committers.emplace_back([&] {
        while (!stop) commit_once(log, false);
      });
    }
    // Commits must be flowing before the kill; then it lands anywhere in a
    // cycle: in a checkout, an upload, a commit, between them.
    const auto flowing_deadline = Clock::now() + seconds(30);
    while ((logs[0].Acknowledged() == before[0] || logs[1].Acknowledged() == before[1]) &&
           Clock::now() < flowing_deadline) {
      std::this_thread::sleep_for(milliseconds(10));
    }
    const int delay_ms = std::uniform_int_distribution<int>(0, 1500)(random);
    std::this_thread::sleep_for(milliseconds(delay_ms));
    server_->Kill();
    stop = true;
    for (std::thread& committer : committers) committer.join();
    for (int i = 0; i < 2; ++i) {
      ASSERT_GT(logs[i].Acknowledged(), before[i]) << "no commit landed before kill " << kill + 1;
    }

    StartServer();
    ASSERT_NO_FATAL_FAILURE(ExpectDatabaseSound(data_));
    int64_t revisions = 0;
    for (CommitLog& log : logs) {
      const int64_t count = ExpectRevisionChain(data_, log.id);
      revisions += count;
      // Each acknowledged commit is there with the content it was sent with.
      for (const auto& [number, hash] : log.acknowledged) {
        EXPECT_EQ(QueryOne(data_,
                           "SELECT content_sha256 FROM structure_revisions WHERE "
                           "structure = " +
                               log.id + " AND number = " + std::to_string(number)),
                  hash)
            << log.name << " revision " << number << " (acknowledged) lost or changed by kill "
            << kill + 1;
      }
      // Besides those, at most the one commit in flight when the server died
      // landed unknown to its client.
      const int64_t unknown = count - 1 - static_cast<int64_t>(log.acknowledged.size());
      EXPECT_GE(unknown, log.landed_unacknowledged) << log.name;
      EXPECT_LE(unknown, log.landed_unacknowledged + 1) << log.name << " after kill " << kill + 1;
      log.landed_unacknowledged = unknown;
    }
    // A blob written just before the server died, for a revision that never
    // committed, is an orphan (the blob goes first so that no row can name a
    // missing blob); the server sweeps them at start, and nothing commits
    // while this looks.
    const BlobCensus census = CheckRevisionBlobs(data_);
    // Both revisions 1 have the same content.
    EXPECT_EQ(census.referenced, revisions - 1) << "each commit has content of its own";
    EXPECT_EQ(census.orphans, 0) << "after kill " << kill + 1;
    max_orphans = std::max(max_orphans, census.orphans);

    // A killed session's lock is still there with its five-minute lease: an
    // admin breaks it, and commits go on.
    for (CommitLog& log : logs) {
      if (!Query(data_, "SELECT 1 FROM locks WHERE structure = " + log.id).empty()) {
        const RunResult broken =
            Pba({"atlas", "break", "-p", "crash", log.name, "--reason", "server crash test"});
        EXPECT_EQ(broken.exit_code, 0) << broken.out << broken.err;
        ++broken_locks;
        EXPECT_TRUE(Query(data_, "SELECT 1 FROM locks WHERE structure = " + log.id).empty());
      }
      EXPECT_TRUE(commit_once(log, true)) << log.name << ": no commit after restart " << kill + 1;
    }
  }
  const double elapsed = SecondsSince(start);

  // A clean stop, then the file on its own (no server) once more.
  EXPECT_EQ(server_->Stop(), 0);
  ASSERT_NO_FATAL_FAILURE(ExpectDatabaseSound(data_));
  int64_t landed = 0, acknowledged = 0;
  for (CommitLog& log : logs) {
    const int64_t revisions = ExpectRevisionChain(data_, log.id);
    EXPECT_EQ(revisions - 1,
              static_cast<int64_t>(log.acknowledged.size()) + log.landed_unacknowledged);
    landed += revisions - 1;
    acknowledged += static_cast<int64_t>(log.acknowledged.size());
  }
  std::printf(
      "[ crash    ] %d kills in %.1f s; %lld commits landed on 2 structures (%lld acknowledged, "
      "%lld landed while their client was told of a failure) in %d checkout/commit cycles; "
      "%d stale locks broken; at most %d orphan blob(s) after a restart\n",
      kKills, elapsed, static_cast<long long>(landed), static_cast<long long>(acknowledged),
      static_cast<long long>(landed - acknowledged), cycles.load(), broken_locks, max_orphans);
}

// --- 2. kill -9 while a job runs ------------------------------------------

// Long enough to be killed in its factorization.
const std::string kMediumScene = BlockSceneYaml("crash-medium", 30);

// RunningJobIsRequeuedAfterServerCrash (cli_server_test.cc) shows the re-queue
// and cancels; this one lets the second attempt finish and checks what it
// leaves behind.
TEST_F(CrashTest, KilledDuringASolveTheJobRunsAgainAndItsResultIsWhole) {
  StartServer();
  const RunResult submitted = Pba({"job", "submit", Write("medium.yaml", kMediumScene).string()});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.err;
  std::smatch match;
  ASSERT_TRUE(std::regex_search(submitted.out, match, std::regex("Submitted job (j[0-9a-f]+)")))
      << submitted.out;
  const std::string id = match[1];
  // Killed past its assembly: in the factorization (most of the run), or
  // later if this machine is faster than the polling.
  const std::regex late_phase("\"phase\": \"(factorize|solve|recover|estimate|write)\"");
  ASSERT_TRUE(WaitForStatus(id, late_phase, seconds(60))) << JobStatusJson(id);
  server_->Kill();
  const auto killed = Clock::now();
  // The solver goes with its server; an orphan would write into the job's
  // folder under the second attempt.
  while (!SolversUsing(data_).empty() && SecondsSince(killed) < 5) {
    std::this_thread::sleep_for(milliseconds(20));
  }
  EXPECT_TRUE(SolversUsing(data_).empty()) << "pba-solve outlived its server";

  StartServer();
  ASSERT_TRUE(WaitForStatus(id, std::regex("\"state\": \"(SUCCEEDED|FAILED|CANCELLED)\""),
                            seconds(120), milliseconds(500)))
      << JobStatusJson(id);
  const double rerun_s = SecondsSince(killed);
  const std::string status = JobStatusJson(id);
  EXPECT_NE(status.find("\"state\": \"SUCCEEDED\""), std::string::npos) << status;
  EXPECT_NE(status.find("\"attempts\": 2"), std::string::npos) << status;

  ASSERT_NO_FATAL_FAILURE(ExpectDatabaseSound(data_));
  const Rows job = Query(data_, "SELECT state, attempts FROM jobs WHERE id = '" + id + "'");
  ASSERT_EQ(job.size(), 1u);
  EXPECT_EQ(job[0], (std::vector<std::string>{"SUCCEEDED", "2"}));
  // In the order of their numbers (which have gaps: live-only progress is
  // not stored), its stored events are in time order, and the crash shows
  // as a RUNNING followed by the re-queue at start, RUNNING again, the end.
  const Rows events =
      Query(data_, "SELECT sequence, time_us, state, message FROM job_events WHERE job_id = '" +
                       id + "' ORDER BY sequence");
  std::string states;
  for (size_t i = 0; i < events.size(); ++i) {
    if (i > 0) {
      EXPECT_LE(std::stoll(events[i - 1][1]), std::stoll(events[i][1]))
          << "event " << events[i][0] << " is older than the one numbered before it";
    }
    if (states.empty() || states.substr(states.rfind(' ') + 1) != events[i][2]) {
      states += " " + events[i][2];
    }
  }
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events[0][0], "1");
  EXPECT_EQ(states, " QUEUED RUNNING QUEUED RUNNING SUCCEEDED");
  const bool requeued_at_start =
      std::any_of(events.begin(), events.end(), [](const std::vector<std::string>& e) {
        return e[2] == "QUEUED" && e[3].find("re-queued") != std::string::npos;
      });
  EXPECT_TRUE(requeued_at_start);

  // The result folder holds exactly the recorded files, each whole.
  const fs::path job_dir = data_ / "jobs" / id;
  const Rows files =
      Query(data_, "SELECT name, size, sha256 FROM result_files WHERE job_id = '" + id + "'");
  std::set<std::string> recorded;
  for (const auto& file : files) {
    recorded.insert(file[0]);
    const std::string content = ReadFile(job_dir / "result" / file[0]);
    EXPECT_EQ(std::to_string(content.size()), file[1]) << file[0];
    EXPECT_EQ(Sha256Hex(content), file[2]) << file[0];
  }
  for (const char* name : {"result.h5", "result.xdmf", "summary.json"}) {
    EXPECT_EQ(recorded.count(name), 1u) << name;
  }
  std::set<std::string> on_disk;
  for (const auto& entry : fs::directory_iterator(job_dir / "result")) {
    on_disk.insert(entry.path().filename().string());
  }
  EXPECT_EQ(on_disk, recorded);
  for (const auto& entry : fs::directory_iterator(job_dir)) {
    EXPECT_NE(entry.path().filename().string().rfind(".result.", 0), 0u)
        << "staging left behind: " << entry.path();
  }
  const std::string log = ReadFile(job_dir / "solve.log");
  EXPECT_NE(log.find("=== attempt 1,"), std::string::npos) << log;
  EXPECT_NE(log.find("=== attempt 2,"), std::string::npos) << log;

  // The client's download checks the same hashes.
  const RunResult fetched = Pba({"job", "fetch", id, "-o", (dir_.path() / "fetched").string()});
  EXPECT_EQ(fetched.exit_code, 0) << fetched.out << fetched.err;
  for (const auto& file : files) {
    EXPECT_EQ(Sha256Hex(ReadFile(dir_.path() / "fetched" / file[0])), file[2]) << file[0];
  }
  std::printf("[ crash    ] job %s killed after its assembly; SUCCEEDED %.1f s after the kill\n",
              id.c_str(), rerun_s);
}

// --- 3. a batch of 200 ------------------------------------------------------

constexpr int kMembers = 200;

std::vector<std::string> JobIds(const std::string& text) {
  std::vector<std::string> ids;
  static const std::regex kId("\"id\": \"(j[0-9a-f]+)\"");
  for (std::sregex_iterator it(text.begin(), text.end(), kId), end; it != end; ++it) {
    ids.push_back((*it)[1]);
  }
  return ids;
}

TEST_F(CrashTest, BatchOf200RunsEachMemberOnce) {
  // The default is one job at a time; two is what two cores allow.
  StartServer({"--max-running", "2"});
  const std::string base = R"(
name: load-block
geometry: {box: {size_mm: [10, 10, 10]}}
mesh: {element_size_mm: 5}
material: {linear_elastic: {youngs_modulus_pa: 3000, poissons_ratio: 0.45}}
boundary_conditions:
  - {set: bottom, fixed: {}}
  - {set: top, displacement: {x_mm: 0, y_mm: 0, z_mm: -1}}
)";
  Write("base.yaml", base);
  std::string moduli;
  for (int i = 0; i < kMembers; ++i) moduli += (i ? ", " : "") + std::to_string(1000 + 10 * i);
  const fs::path batch = Write("load.yaml",
                               "name: load\nscene: base.yaml\nparallel: 8\nsweep:\n"
                               "  material.linear_elastic.youngs_modulus_pa: [" +
                                   moduli +
                                   "]\noutputs:\n"
                                   "  - results.reactions[1].force_n[2]\n");

  const auto start = Clock::now();
  const RunResult run = Pba({"batch", "run", batch.string()}, seconds(280));
  const double elapsed = SecondsSince(start);
  ASSERT_EQ(run.exit_code, 0) << run.out.substr(0, 4000) << run.err;

  // One row per member: its modulus, a job of its own, SUCCEEDED, and a
  // reaction proportional to its modulus (the displacement is prescribed),
  // which a member given another's result would break.
  const std::string csv = ReadFile(dir_.path() / "load.csv");
  static const std::regex kRow("^[^\\n]*?,(\\d+),(j[0-9a-f]+),(\\w+),([^,\\n]+)$");
  std::set<std::string> batch_ids;
  std::set<std::string> moduli_seen;
  double force_per_pa = 0;
  int rows = 0;
  std::stringstream lines(csv);
  std::string line;
  std::getline(lines, line);  // the header
  while (std::getline(lines, line)) {
    ++rows;
    std::smatch cells;
    if (!std::regex_match(line, cells, kRow)) {
      ADD_FAILURE() << "not a member row: " << line;
      continue;
    }
    moduli_seen.insert(cells[1]);
    batch_ids.insert(cells[2]);
    EXPECT_EQ(cells[3], "SUCCEEDED") << line;
    const double ratio = std::stod(cells[4]) / std::stod(cells[1]);
    if (force_per_pa == 0) force_per_pa = ratio;
    EXPECT_NEAR(ratio, force_per_pa, 1e-9 * std::abs(force_per_pa)) << line;
  }
  EXPECT_EQ(rows, kMembers);
  EXPECT_EQ(moduli_seen.size(), static_cast<size_t>(kMembers));
  EXPECT_EQ(batch_ids.size(), static_cast<size_t>(kMembers));
  EXPECT_NE(force_per_pa, 0);

  // The server has exactly those jobs, each once.
  const RunResult listed = Pba({"--json", "job", "list", "--all"});
  ASSERT_EQ(listed.exit_code, 0) << listed.err;
  const std::vector<std::string> listed_ids = JobIds(listed.out);
  EXPECT_EQ(listed_ids.size(), static_cast<size_t>(kMembers));
  EXPECT_EQ(std::set<std::string>(listed_ids.begin(), listed_ids.end()), batch_ids);
  EXPECT_EQ(QueryOne(data_, "SELECT COUNT(*) FROM jobs WHERE state = 'SUCCEEDED'"),
            std::to_string(kMembers));

  // A rerun finds every member's job and submits nothing.
  const RunResult again = Pba({"batch", "run", batch.string()}, seconds(120));
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.out.find("200 from an earlier run, 0 to submit"), std::string::npos)
      << again.out.substr(0, 2000);
  EXPECT_EQ(QueryOne(data_, "SELECT COUNT(*) FROM jobs"), std::to_string(kMembers));

  // One member's scene submitted twice under one request id: one new job.
  std::string member = base;
  member.replace(member.find("3000"), 4, "1000");
  const fs::path scene = Write("member.yaml", member);
  const RunResult first = Pba({"job", "submit", scene.string(), "--request-id", "load-repeat"});
  const RunResult second = Pba({"job", "submit", scene.string(), "--request-id", "load-repeat"});
  ASSERT_EQ(first.exit_code, 0) << first.err;
  ASSERT_EQ(second.exit_code, 0) << second.err;
  std::smatch first_id, second_id;
  ASSERT_TRUE(std::regex_search(first.out, first_id, std::regex("job (j[0-9a-f]+)"))) << first.out;
  ASSERT_TRUE(std::regex_search(second.out, second_id, std::regex("job (j[0-9a-f]+)")))
      << second.out;
  EXPECT_EQ(first_id[1], second_id[1]);
  EXPECT_EQ(batch_ids.count(first_id[1]), 0u) << "another request id, so not the batch's job";
  const std::vector<std::string> after = JobIds(Pba({"--json", "job", "list", "--all"}).out);
  EXPECT_EQ(after.size(), static_cast<size_t>(kMembers + 1));

  ASSERT_NO_FATAL_FAILURE(ExpectDatabaseSound(data_));
  std::printf(
      "[ load     ] %d jobs in %.1f s: %.0f jobs/minute (batch parallel 8, server "
      "--max-running 2)\n",
      kMembers, elapsed, kMembers / elapsed * 60);
}

}  // namespace
}  // namespace pba::testing
