// Many people racing to edit one atlas structure through the real pba client
// and a real pba-server on loopback: every commit lands or is refused with
// the head (or the lock's holder) named, nothing is lost, the history stays
// one chain and the audit log records every lock and commit. Then a lock
// whose holder vanished: it lapses, someone else takes over, and the
// vanished client's checkout can no longer commit.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <openssl/evp.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/subprocess.h"
#include "integration/db_query.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using std::chrono::seconds;

// Exit codes of pba (client_cli/exit_codes.h, docs/cli.md).
constexpr int kConflict = 9;
constexpr int kDenied = 10;

constexpr int kClients = 20;
constexpr int kOperations = 50;
constexpr char kProject[] = "race";
constexpr char kStructure[] = "Hippocampus";

void WriteFile(const fs::path& path, const std::string& content) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << content;
}

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

// One plate whose square's side encodes `tag`, so that every edit anyone
// makes has content (and a SHA-256) of its own.
std::string Contours(int tag) {
  char side[32];
  std::snprintf(side, sizeof side, "%.4f", 1.0 + tag / 10000.0);
  std::ostringstream out;
  out << R"({"plates": [{"z_mm": 0, "polygons": [[[0, 0], [)" << side << ", 0], [" << side << ", "
      << side << "], [0, " << side << "]]]}]}\n";
  return out.str();
}

std::string UserName(int client) {
  char name[16];
  std::snprintf(name, sizeof name, "user%02d", client);
  return name;
}

// The value of "key": "value" (or a bare number) in one printed JSON object;
// empty when the field is absent (proto3 JSON leaves out zero values).
std::string JsonField(const std::string& object, const std::string& key) {
  std::smatch match;
  if (std::regex_search(object, match,
                        std::regex("\"" + key + "\": (?:\"([^\"]*)\"|([-0-9.]+))"))) {
    return match[1].matched ? match[1].str() : match[2].str();
  }
  return "";
}

// The objects of a printed JSON list, cut where each one's first field
// (`first_key`, the lowest field number, which protobuf prints first) begins.
std::vector<std::string> JsonObjects(const std::string& json, const std::string& first_key) {
  std::vector<std::string> out;
  const std::string marker = "\"" + first_key + "\": ";
  size_t at = json.find(marker);
  while (at != std::string::npos) {
    const size_t next = json.find(marker, at + marker.size());
    out.push_back(json.substr(at, next == std::string::npos ? std::string::npos : next - at));
    at = next;
  }
  return out;
}

struct RevisionRow {
  int64_t number = 0;
  int64_t parent = 0;
  std::string author, kind, sha256;
};

// What one client saw. Contents are SHA-256 hex of the file it committed.
struct ClientLog {
  int checkouts_locked = 0;    // checkout exit 0
  int checkouts_refused = 0;   // checkout exit 9, the holder named
  int commits_landed = 0;      // commit exit 0
  int stale_base_refused = 0;  // commit on an old base with a live lock: exit 9, the head named
  int released_refused = 0;    // commit with a lock given back: exit 9
  int lapsed_refused = 0;      // commit after the lease lapsed: exit 9
  int unlocks = 0;             // unlock exit 0
  int commits_keeping_lock = 0;
  std::map<int64_t, std::string> landed;  // revision -> content
  std::vector<std::string> refused;       // contents that must not be in the history
  std::vector<std::string> problems;      // anything outside the rules, with its output
};

class CliRaceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    data_ = dir_.path() / "data";
    fs::create_directories(dir_.path() / "config");
    server_ = std::make_unique<ServerProcess>(PBA_SERVER_BIN, data_);
    std::string log;
    ASSERT_TRUE(server_->Start(&log)) << "pba-server did not start:\n" << log;
    std::smatch token;
    const std::string admin = ReadFile(data_ / "admin.token");
    ASSERT_TRUE(std::regex_search(admin, token, std::regex("[0-9a-f]{64}"))) << admin;
    tokens_["admin"] = token.str();
  }

  void TearDown() override {
    if (HasFailure()) std::cerr << "server log:\n" << ReadFile(server_->log_path());
  }

  // Runs pba as `who` with their token in PBA_TOKEN (and an empty config
  // directory), so that threads need no shared credentials file.
  RunResult PbaAs(const std::string& who, std::vector<std::string> args,
                  seconds timeout = seconds(60)) {
    args.insert(args.begin(), {PBA_CLI_BIN, "--server", server_->address()});
    return RunProcess(args,
                      {"PBA_TOKEN=" + tokens_.at(who),
                       "XDG_CONFIG_HOME=" + (dir_.path() / "config").string(), "PBA_PROJECT="},
                      timeout);
  }

  // Creates `name` with `pba-server admin create-user` and keeps its token.
  void CreateUser(const std::string& name) {
    const RunResult created = RunProcess(
        {PBA_SERVER_BIN, "admin", "create-user", name, "--data", data_.string()}, seconds(30));
    ASSERT_EQ(created.exit_code, 0) << created.out << created.err;
    std::smatch token;
    ASSERT_TRUE(std::regex_search(created.out, token, std::regex("[0-9a-f]{64}"))) << created.out;
    tokens_[name] = token.str();
  }

  // Project `race` with `editors` as editors, and structure Hippocampus
  // (revision 1, by admin).
  void SetUpProject(const std::vector<std::string>& editors) {
    for (const auto& name : editors) ASSERT_NO_FATAL_FAILURE(CreateUser(name));
    const RunResult project = PbaAs("admin", {"project", "create", kProject});
    ASSERT_EQ(project.exit_code, 0) << project.out << project.err;
    for (const auto& name : editors) {
      const RunResult role = PbaAs("admin", {"project", "role", kProject, name, "editor"});
      ASSERT_EQ(role.exit_code, 0) << role.out << role.err;
    }
    const fs::path first = dir_.path() / "first.json";
    WriteFile(first, Contours(-1));
    const RunResult create = PbaAs(
        "admin", {"atlas", "create", "-p", kProject, kStructure, first.string(), "-m", "outline"});
    ASSERT_EQ(create.exit_code, 0) << create.out << create.err;
    first_sha_ = Sha256Hex(ReadFile(first));
  }

  // The structure's revisions by number, read with `pba atlas history --all`.
  std::map<int64_t, RevisionRow> History() {
    std::map<int64_t, RevisionRow> out;
    const RunResult history =
        PbaAs("admin", {"--json", "atlas", "history", "-p", kProject, kStructure, "--all"});
    EXPECT_EQ(history.exit_code, 0) << history.err;
    for (const std::string& object : JsonObjects(history.out, "project")) {
      RevisionRow row;
      row.number = std::stoll(JsonField(object, "number"));
      const std::string parent = JsonField(object, "parent");
      row.parent = parent.empty() ? 0 : std::stoll(parent);
      row.author = JsonField(object, "author");
      row.kind = JsonField(object, "kind");
      row.sha256 = JsonField(object, "content_sha256");
      EXPECT_TRUE(out.emplace(row.number, row).second) << "revision " << row.number << " twice";
    }
    return out;
  }

  // The project's audit log, read with `pba atlas audit --all`: action ->
  // entries (each the printed JSON object).
  std::map<std::string, std::vector<std::string>> Audit() {
    std::map<std::string, std::vector<std::string>> out;
    const RunResult audit = PbaAs("admin", {"--json", "atlas", "audit", "-p", kProject, "--all"});
    EXPECT_EQ(audit.exit_code, 0) << audit.err;
    for (const std::string& entry : JsonObjects(audit.out, "sequence")) {
      out[JsonField(entry, "action")].push_back(entry);
    }
    return out;
  }

  // One person's part in TwentyClientsFiftyOperationsOnOneStructure.
  void RunClient(int c, const std::string& me, ClientLog* log);

  TempDir dir_;
  fs::path data_;
  std::unique_ptr<ServerProcess> server_;
  std::map<std::string, std::string> tokens_;  // written before the threads start
  std::string first_sha_;
};

// The checkout file and what it names.
struct Checkout {
  fs::path file;
  int64_t base = 0;
};

std::string Describe(const std::string& what, const RunResult& run) {
  return what + " exited " + std::to_string(run.exit_code) + ": " + run.out + run.err;
}

// One person's kOperations operations of the race test below, on a thread of
// their own: check out (lock), edit, commit; what they saw goes into *log.
void CliRaceTest::RunClient(int c, const std::string& me, ClientLog* client_log) {
  ClientLog& log = *client_log;
  const std::regex holder_named("locked by '(user\\d\\d|admin)'");
  const std::regex revision_printed("revision (\\d+)");
  const fs::path file = dir_.path() / (me + ".json");
  const fs::path checkout_file = file.string() + ".pba-checkout";
  std::mt19937 random(c);
  // A refused person tries again a little later, as people do; without the
  // pause the 19 who wait would starve the one who holds the lock of CPU.
  std::uniform_int_distribution<int> backoff_ms(500, 1700);
  int locks = 0;
  // Every fifth person once lets a 1 s lease lapse, from the 25th
  // operation on.
  bool lapse_due = c % 5 == 0;
  for (int op = 0; op < kOperations; ++op) {
    const int tag = (c * kOperations + op) * 4;
    std::vector<std::string> checkout_args = {"atlas",    "checkout", "-p",         kProject,
                                              kStructure, "-o",       file.string()};
    const bool lapse = lapse_due && op >= kOperations / 2;
    if (lapse) checkout_args.insert(checkout_args.end(), {"--lease", "1"});
    const RunResult checkout = PbaAs(me, checkout_args);
    if (checkout.exit_code == kConflict) {
      std::smatch holder;
      if (std::regex_search(checkout.err, holder, holder_named) && holder[1].str() != me) {
        ++log.checkouts_refused;
      } else {
        log.problems.push_back(Describe("checkout (holder not named)", checkout));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(backoff_ms(random)));
      continue;
    }
    if (checkout.exit_code != 0) {
      log.problems.push_back(Describe("checkout", checkout));
      continue;
    }
    ++log.checkouts_locked;
    ++locks;
    if (lapse) lapse_due = false;
    // Of each person's locks the second, fifth, ... commit on a stale base
    // and the third, sixth, ... commit after giving the lock back.
    const bool stale_base = !lapse && locks % 3 == 2;
    const bool released = !lapse && locks % 3 == 0;
    const std::string saved_checkout = ReadFile(checkout_file);
    // Commits `content` from the checkout file as it now is.
    const auto commit = [&](const std::string& content, bool keep_lock) {
      WriteFile(file, content);
      std::vector<std::string> args = {"atlas", "commit", file.string(), "-m",
                                       me + " op " + std::to_string(op)};
      if (keep_lock) args.push_back("--keep-lock");
      return PbaAs(me, args);
    };
    const auto landed = [&](const std::string& content, const RunResult& run) {
      std::smatch number;
      if (run.exit_code != 0 || !std::regex_search(run.out, number, revision_printed)) {
        log.problems.push_back(Describe("commit", run));
        return false;
      }
      ++log.commits_landed;
      log.landed[std::stoll(number[1])] = Sha256Hex(content);
      return true;
    };

    if (stale_base) {
      // Lands with the lock kept; then the old checkout file (same live
      // lock, the old base) commits something else: refused, head named.
      const std::string first = Contours(tag);
      const RunResult kept = commit(first, true);
      if (!landed(first, kept)) continue;
      ++log.commits_keeping_lock;
      const int64_t head = log.landed.rbegin()->first;
      WriteFile(checkout_file, saved_checkout);
      const std::string second = Contours(tag + 1);
      const RunResult stale = commit(second, false);
      log.refused.push_back(Sha256Hex(second));
      if (stale.exit_code == kConflict &&
          stale.err.find("the head is revision " + std::to_string(head)) != std::string::npos) {
        ++log.stale_base_refused;
      } else {
        log.problems.push_back(Describe("stale-base commit", stale));
      }
      const RunResult unlock = PbaAs(me, {"atlas", "unlock", file.string()});
      if (unlock.exit_code == 0) {
        ++log.unlocks;
      } else {
        log.problems.push_back(Describe("unlock", unlock));
      }
    } else if (released) {
      // Gives the lock back, then commits from a copy of the checkout
      // file: whoever holds the lock now (or nobody), it must not land.
      const RunResult unlock = PbaAs(me, {"atlas", "unlock", file.string()});
      if (unlock.exit_code == 0) {
        ++log.unlocks;
      } else {
        log.problems.push_back(Describe("unlock", unlock));
      }
      WriteFile(checkout_file, saved_checkout);
      const std::string content = Contours(tag + 2);
      const RunResult late = commit(content, false);
      log.refused.push_back(Sha256Hex(content));
      if (late.exit_code == kConflict && late.err.find("lock") != std::string::npos) {
        ++log.released_refused;
      } else {
        log.problems.push_back(Describe("commit after unlock", late));
      }
      std::error_code ec;
      fs::remove(checkout_file, ec);
    } else if (lapse) {
      // Outlives a 1 s lease: refused whether or not someone took over.
      std::this_thread::sleep_for(std::chrono::milliseconds(1200));
      const std::string content = Contours(tag + 3);
      const RunResult late = commit(content, false);
      log.refused.push_back(Sha256Hex(content));
      if (late.exit_code == kConflict && (late.err.find("lapsed") != std::string::npos ||
                                          std::regex_search(late.err, holder_named) ||
                                          late.err.find("not locked") != std::string::npos)) {
        ++log.lapsed_refused;
      } else {
        log.problems.push_back(Describe("commit after the lease lapsed", late));
      }
      // Gives back the lapsed lock unless someone took it over already.
      const RunResult unlock = PbaAs(me, {"atlas", "unlock", file.string()});
      if (unlock.exit_code == 0) {
        ++log.unlocks;
      } else if (unlock.exit_code != kConflict) {
        log.problems.push_back(Describe("unlock of a lapsed lock", unlock));
      }
      std::error_code ec;
      fs::remove(checkout_file, ec);
    } else {
      const std::string content = Contours(tag);
      landed(content, commit(content, false));
    }
  }
}

// Prints each client's counts and checks each one kept to the rules; their
// totals, and in *landed: revision -> (user, content) as each client was told.
ClientLog SumUpClients(const std::vector<std::string>& users, const std::vector<ClientLog>& logs,
                       std::map<int64_t, std::pair<std::string, std::string>>* landed) {
  ClientLog total;
  std::printf("%-7s %9s %9s %7s %10s %9s %7s %7s\n", "client", "locked", "refused", "landed",
              "stale-base", "released", "lapsed", "unlocks");
  for (int c = 0; c < kClients; ++c) {
    const ClientLog& log = logs[c];
    std::printf("%-7s %9d %9d %7d %10d %9d %7d %7d\n", users[c].c_str(), log.checkouts_locked,
                log.checkouts_refused, log.commits_landed, log.stale_base_refused,
                log.released_refused, log.lapsed_refused, log.unlocks);
    for (const auto& problem : log.problems) ADD_FAILURE() << users[c] << ": " << problem;
    EXPECT_EQ(log.checkouts_locked + log.checkouts_refused, kOperations) << users[c];
    total.checkouts_locked += log.checkouts_locked;
    total.checkouts_refused += log.checkouts_refused;
    total.commits_landed += log.commits_landed;
    total.commits_keeping_lock += log.commits_keeping_lock;
    total.stale_base_refused += log.stale_base_refused;
    total.released_refused += log.released_refused;
    total.lapsed_refused += log.lapsed_refused;
    total.unlocks += log.unlocks;
    total.refused.insert(total.refused.end(), log.refused.begin(), log.refused.end());
    for (const auto& [number, sha] : log.landed) {
      EXPECT_TRUE(landed->emplace(number, std::make_pair(users[c], sha)).second)
          << "two commits were told they made revision " << number;
    }
  }
  return total;
}

// One chain 1..N, N - 1 landed commits, each with the content its client
// committed and the revision it was told; nothing refused made it in.
// `history` is not empty.
void CheckHistory(const std::map<int64_t, RevisionRow>& history, const ClientLog& total,
                  const std::map<int64_t, std::pair<std::string, std::string>>& landed,
                  const std::string& first_sha) {
  const int64_t n = history.rbegin()->first;
  EXPECT_EQ(static_cast<int64_t>(history.size()), n) << "gaps in the revision numbers";
  EXPECT_EQ(history.begin()->first, 1);
  EXPECT_EQ(n - 1, total.commits_landed);
  std::map<std::string, int> seen;  // content -> revisions carrying it
  for (const auto& [number, row] : history) {
    EXPECT_EQ(row.parent, number - 1) << "revision " << number;
    EXPECT_EQ(row.kind, number == 1 ? "create" : "commit") << "revision " << number;
    ++seen[row.sha256];
  }
  EXPECT_EQ(history.at(1).sha256, first_sha);
  for (const auto& [number, who] : landed) {
    ASSERT_TRUE(history.count(number)) << "revision " << number << " of " << who.first << " lost";
    EXPECT_EQ(history.at(number).author, who.first) << "revision " << number;
    EXPECT_EQ(history.at(number).sha256, who.second) << "revision " << number;
    EXPECT_EQ(seen[who.second], 1) << "content of revision " << number;
  }
  for (const auto& sha : total.refused) EXPECT_EQ(seen.count(sha), 0u) << sha << " was refused";
}

// The audit log: one commit entry per landed commit naming its revision,
// one lock entry per lock taken (a takeover when a lease had lapsed), one
// release per unlock and per commit that gave the lock back. `n`: the head.
void CheckAudit(std::map<std::string, std::vector<std::string>>& audit, const ClientLog& total,
                int64_t n) {
  ASSERT_EQ(static_cast<int>(audit["revision.commit"].size()), total.commits_landed);
  std::set<int64_t> audited;
  for (const auto& entry : audit["revision.commit"]) {
    audited.insert(std::stoll(JsonField(entry, "revision")));
  }
  EXPECT_EQ(static_cast<int>(audited.size()), total.commits_landed);
  EXPECT_EQ(audited.empty() ? 0 : *audited.begin(), 2);
  EXPECT_EQ(audited.empty() ? 0 : *audited.rbegin(), n);
  EXPECT_EQ(audit["lock.acquire"].size() + audit["lock.takeover"].size(),
            static_cast<size_t>(total.checkouts_locked));
  EXPECT_LE(audit["lock.takeover"].size(), static_cast<size_t>(kClients));
  EXPECT_EQ(static_cast<int>(audit["lock.release"].size()),
            total.commits_landed - total.commits_keeping_lock + total.unlocks);
  EXPECT_EQ(audit["structure.create"].size(), 1u);
}

// And the database itself, read directly: the same chain, the same audit
// counts, no lock left behind, and a sound file. `n`: the head.
void CheckDatabase(const fs::path& data, const ClientLog& total, int64_t n) {
  EXPECT_EQ(QueryOne(data,
                     "SELECT COUNT(*) FROM structure_revisions r JOIN structure_revisions p ON "
                     "p.id = r.parent WHERE p.number = r.number - 1 AND p.structure = r.structure"),
            std::to_string(n - 1));
  EXPECT_EQ(QueryOne(data, "SELECT MAX(number) || '/' || COUNT(*) FROM structure_revisions"),
            std::to_string(n) + "/" + std::to_string(n));
  EXPECT_EQ(QueryOne(data, "SELECT COUNT(*) FROM audit_log WHERE action = 'revision.commit'"),
            std::to_string(total.commits_landed));
  EXPECT_EQ(QueryOne(data,
                     "SELECT COUNT(*) FROM audit_log WHERE action IN ('lock.acquire', "
                     "'lock.takeover')"),
            std::to_string(total.checkouts_locked));
  EXPECT_EQ(QueryOne(data, "SELECT COUNT(*) FROM locks"), "0");
  EXPECT_EQ(QueryOne(data,
                     "SELECT COUNT(*) FROM structures s JOIN structure_revisions r ON "
                     "r.id = s.head_revision WHERE r.number = " +
                         std::to_string(n)),
            "1");
  EXPECT_EQ(QueryOne(data, "PRAGMA integrity_check"), "ok");
  EXPECT_TRUE(Query(data, "PRAGMA foreign_key_check").empty());
}

// 20 people, each 50 times: check out (lock), edit, commit. Many checkouts
// find the lock held and are turned away; of the locks taken, some on purpose
// commit on a stale base with a live lock, commit with a lock already given
// back, or let a short lease lapse before committing.
TEST_F(CliRaceTest, TwentyClientsFiftyOperationsOnOneStructure) {
  std::vector<std::string> users;
  for (int c = 0; c < kClients; ++c) users.push_back(UserName(c));
  ASSERT_NO_FATAL_FAILURE(SetUpProject(users));
  const auto started = Clock::now();

  std::vector<ClientLog> logs(kClients);
  std::vector<std::thread> threads;
  for (int c = 0; c < kClients; ++c) {
    threads.emplace_back([this, c, &users, &logs] { RunClient(c, users[c], &logs[c]); });
  }
  for (auto& thread : threads) thread.join();
  const double race_s = std::chrono::duration<double>(Clock::now() - started).count();

  // Outcomes per client.
  std::map<int64_t, std::pair<std::string, std::string>> landed;  // revision -> (user, content)
  const ClientLog total = SumUpClients(users, logs, &landed);
  std::printf(
      "%d clients x %d operations in %.1f s: %d checkouts locked, %d refused (holder named); "
      "%d commits landed; refused: %d on a stale base, %d after unlocking, %d after the lease "
      "lapsed\n",
      kClients, kOperations, race_s, total.checkouts_locked, total.checkouts_refused,
      total.commits_landed, total.stale_base_refused, total.released_refused, total.lapsed_refused);
  std::fflush(stdout);
  // The race is a race only if people were turned away, and the deliberate
  // stale commits were made.
  EXPECT_GT(total.checkouts_refused, 0);
  EXPECT_GT(total.stale_base_refused, 0);
  EXPECT_GT(total.released_refused, 0);

  const std::map<int64_t, RevisionRow> history = History();
  ASSERT_FALSE(history.empty());
  const int64_t n = history.rbegin()->first;
  ASSERT_NO_FATAL_FAILURE(CheckHistory(history, total, landed, first_sha_));

  std::map<std::string, std::vector<std::string>> audit = Audit();
  ASSERT_NO_FATAL_FAILURE(CheckAudit(audit, total, n));
  CheckDatabase(data_, total, n);
  std::printf("race and checks took %.1f s\n",
              std::chrono::duration<double>(Clock::now() - started).count());
}

// A pba process started in the background with its output in `out`.
pid_t Spawn(const std::vector<std::string>& argv, const std::vector<std::string>& env,
            const fs::path& out) {
  std::vector<char*> args;
  for (const auto& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
  args.push_back(nullptr);
  std::vector<std::string> environment;
  for (char** entry = environ; *entry != nullptr; ++entry) environment.push_back(*entry);
  environment.insert(environment.end(), env.begin(), env.end());
  std::vector<char*> envp;
  for (const auto& entry : environment) envp.push_back(const_cast<char*>(entry.c_str()));
  envp.push_back(nullptr);
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int fd = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(fd, STDOUT_FILENO);
    ::dup2(fd, STDERR_FILENO);
    ::execve(args[0], args.data(), envp.data());
    std::_Exit(127);
  }
  return pid;
}

// alice holds the lock with `checkout --hold` and vanishes (kill -9): the
// lease she kept renewing lapses, bob takes the lock over and commits, and
// alice's checkout file is refused before and after bob's commit.
TEST_F(CliRaceTest, ALockWhoseHolderVanishedLapsesAndItsCheckoutCannotCommit) {
  ASSERT_NO_FATAL_FAILURE(SetUpProject({"alice", "bob"}));
  const fs::path alice_file = dir_.path() / "alice.json";
  const fs::path alice_out = dir_.path() / "alice-hold.out";
  const pid_t holder =
      Spawn({PBA_CLI_BIN, "--server", server_->address(), "atlas", "checkout", "-p", kProject,
             kStructure, "-o", alice_file.string(), "--lease", "3", "--hold"},
            {"PBA_TOKEN=" + tokens_.at("alice")}, alice_out);
  ASSERT_GT(holder, 0);
  const auto deadline = Clock::now() + seconds(30);
  while (ReadFile(alice_out).find("Keeping the lock alive") == std::string::npos &&
         Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_NE(ReadFile(alice_out).find("Keeping the lock alive"), std::string::npos)
      << ReadFile(alice_out);
  // Past the first lease: --hold renewed it (every second), so bob is still
  // turned away.
  std::this_thread::sleep_for(std::chrono::milliseconds(3500));
  const fs::path bob_file = dir_.path() / "bob.json";
  const RunResult held =
      PbaAs("bob", {"atlas", "checkout", "-p", kProject, kStructure, "-o", bob_file.string()});
  EXPECT_EQ(held.exit_code, kConflict) << held.out << held.err;
  EXPECT_NE(held.err.find("locked by 'alice'"), std::string::npos) << held.err;
  ::kill(holder, SIGKILL);
  int status = 0;
  ASSERT_EQ(::waitpid(holder, &status, 0), holder);
  ASSERT_TRUE(fs::exists(alice_file.string() + ".pba-checkout"));
  const auto vanished = Clock::now();

  // Within a lease and a bit of the vanishing, bob gets the lock, told from
  // whom he took it over.
  RunResult taken;
  do {
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
    taken =
        PbaAs("bob", {"atlas", "checkout", "-p", kProject, kStructure, "-o", bob_file.string()});
  } while (taken.exit_code == kConflict && Clock::now() - vanished < seconds(20));
  ASSERT_EQ(taken.exit_code, 0) << taken.out << taken.err;
  EXPECT_NE(taken.out.find("taken over from alice"), std::string::npos) << taken.out;
  const double lapse_s = std::chrono::duration<double>(Clock::now() - vanished).count();
  // At most a lease after the last renewal, plus slack for a loaded machine.
  EXPECT_LE(lapse_s, 10.0) << "the 3 s lease outlived its holder by too long";
  std::printf("the lock lapsed %.1f s after its holder was killed\n", lapse_s);

  // alice's file, edited after she vanished: refused while bob holds the lock...
  WriteFile(alice_file, Contours(1));
  const RunResult while_held =
      PbaAs("alice", {"atlas", "commit", alice_file.string(), "-m", "from beyond"});
  EXPECT_EQ(while_held.exit_code, kConflict) << while_held.out << while_held.err;
  EXPECT_NE(while_held.err.find("locked by 'bob'"), std::string::npos) << while_held.err;

  WriteFile(bob_file, Contours(2));
  const RunResult bob_commit = PbaAs("bob", {"atlas", "commit", bob_file.string(), "-m", "bob"});
  ASSERT_EQ(bob_commit.exit_code, 0) << bob_commit.out << bob_commit.err;
  EXPECT_NE(bob_commit.out.find("revision 2"), std::string::npos) << bob_commit.out;

  // ...and after bob gave it back (no lock at all, and a newer head).
  const RunResult after = PbaAs("alice", {"atlas", "commit", alice_file.string(), "-m", "again"});
  EXPECT_TRUE(after.exit_code == kConflict || after.exit_code == kDenied) << after.out << after.err;
  EXPECT_NE(after.err.find("not locked"), std::string::npos) << after.err;
  // Her old lock id cannot be given back either: it is no longer held.
  const RunResult unlock = PbaAs("alice", {"atlas", "unlock", alice_file.string()});
  EXPECT_EQ(unlock.exit_code, kConflict) << unlock.out << unlock.err;
  EXPECT_NE(unlock.err.find("no longer held"), std::string::npos) << unlock.err;

  const std::map<int64_t, RevisionRow> history = History();
  ASSERT_EQ(history.size(), 2u);
  EXPECT_EQ(history.at(2).author, "bob");
  EXPECT_EQ(history.at(2).parent, 1);
  EXPECT_EQ(history.at(2).sha256, Sha256Hex(Contours(2)));
  std::map<std::string, std::vector<std::string>> audit = Audit();
  ASSERT_EQ(audit["lock.takeover"].size(), 1u);
  EXPECT_EQ(JsonField(audit["lock.takeover"][0], "user"), "bob");
  EXPECT_NE(audit["lock.takeover"][0].find("took over from alice"), std::string::npos)
      << audit["lock.takeover"][0];
  EXPECT_EQ(audit["lock.acquire"].size(), 1u);
  EXPECT_GE(audit["lock.renew"].size(), 1u);
  EXPECT_EQ(audit["revision.commit"].size(), 1u);
  EXPECT_EQ(QueryOne(data_, "PRAGMA integrity_check"), "ok");
}

// A commit that landed is never reported as refused: run again from the
// same checkout after its first run gave the lock back (that run's output
// lost, say), it exits 0 with the revision it made; nothing lands twice.
TEST_F(CliRaceTest, ACommitRunAgainAfterItsLockWasGivenBackExitsZeroWithItsRevision) {
  ASSERT_NO_FATAL_FAILURE(SetUpProject({"alice"}));
  const fs::path file = dir_.path() / "alice.json";
  const fs::path checkout_file = file.string() + ".pba-checkout";
  const RunResult checkout =
      PbaAs("alice", {"atlas", "checkout", "-p", kProject, kStructure, "-o", file.string()});
  ASSERT_EQ(checkout.exit_code, 0) << checkout.out << checkout.err;
  const std::string saved_checkout = ReadFile(checkout_file);
  WriteFile(file, Contours(7));
  const RunResult first = PbaAs("alice", {"atlas", "commit", file.string(), "-m", "once"});
  ASSERT_EQ(first.exit_code, 0) << first.out << first.err;
  EXPECT_NE(first.out.find("revision 2; unlocked"), std::string::npos) << first.out;
  WriteFile(checkout_file, saved_checkout);
  const RunResult again = PbaAs("alice", {"atlas", "commit", file.string(), "-m", "once"});
  EXPECT_EQ(again.exit_code, 0) << again.out << again.err;
  EXPECT_NE(again.out.find("revision 2; the lock was no longer held"), std::string::npos)
      << again.out;
  EXPECT_FALSE(fs::exists(checkout_file));
  EXPECT_EQ(History().size(), 2u);
  // Other content from that old checkout is still refused.
  WriteFile(checkout_file, saved_checkout);
  WriteFile(file, Contours(8));
  const RunResult other = PbaAs("alice", {"atlas", "commit", file.string(), "-m", "twice"});
  EXPECT_EQ(other.exit_code, kConflict) << other.out << other.err;
  EXPECT_EQ(History().size(), 2u);
}

}  // namespace
}  // namespace pba::testing
