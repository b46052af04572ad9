// pba-server's trust boundaries as an operator meets them (issue 18): a user
// disabled offline while the server runs, a member removed with the pba
// client, plaintext refused off loopback, and the data directory private
// (0700, files 0600) after a server run and a real job.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>

#include "common/subprocess.h"
#include "integration/server_fixture.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;

constexpr int kNotFound = 4;
constexpr int kConflict = 9;
constexpr int kDenied = 10;

mode_t ModeOf(const fs::path& path) {
  struct stat info {};
  EXPECT_EQ(::lstat(path.c_str(), &info), 0) << path;
  return info.st_mode & 07777;
}

class ServerTrustTest : public ServerTest {
 protected:
  fs::path data() const { return dir_.path() / "data"; }

  // A new user's token, made offline by `pba-server admin create-user`.
  std::string CreateUser(const std::string& name) {
    const RunResult made =
        RunProcess({PBA_SERVER_BIN, "admin", "create-user", name, "--data", data().string()});
    EXPECT_EQ(made.exit_code, 0) << made.err;
    std::string token = made.out;
    while (!token.empty() && token.back() == '\n') token.pop_back();
    return token;
  }

  // `pba --server ADDRESS args...` as the user whose token is `token`.
  RunResult PbaAs(const std::string& token, std::vector<std::string> args) {
    args.insert(args.begin(), {PBA_CLI_BIN, "--server", server_->address()});
    return RunProcess(args, {"PBA_TOKEN=" + token});
  }
};

TEST_F(ServerTrustTest, AUserDisabledOfflineIsRefusedByTheRunningServer) {
  const std::string bob = CreateUser("bob");
  ASSERT_EQ(PbaAs(bob, {"whoami"}).exit_code, 0);
  RunResult admin =
      RunProcess({PBA_SERVER_BIN, "admin", "disable-user", "bob", "--data", data().string()});
  ASSERT_EQ(admin.exit_code, 0) << admin.err;
  EXPECT_NE(admin.err.find("disabled user 'bob'"), std::string::npos) << admin.err;
  // No restart: the very next call is refused.
  const RunResult refused = PbaAs(bob, {"whoami"});
  EXPECT_EQ(refused.exit_code, kDenied) << refused.out << refused.err;
  EXPECT_NE(refused.err.find("disabled"), std::string::npos) << refused.err;
  EXPECT_EQ(PbaAs(bob, {"job", "list"}).exit_code, kDenied);

  admin = RunProcess({PBA_SERVER_BIN, "admin", "enable-user", "bob", "--data", data().string()});
  ASSERT_EQ(admin.exit_code, 0) << admin.err;
  EXPECT_EQ(PbaAs(bob, {"whoami"}).exit_code, 0);
  admin =
      RunProcess({PBA_SERVER_BIN, "admin", "disable-user", "nobody", "--data", data().string()});
  EXPECT_EQ(admin.exit_code, 1);
  EXPECT_NE(admin.err.find("'nobody' does not exist"), std::string::npos) << admin.err;
}

TEST_F(ServerTrustTest, AProjectAdminRemovesAMember) {
  const std::string bob = CreateUser("bob");
  ASSERT_EQ(Pba({"project", "create", "brain"}).exit_code, 0);
  ASSERT_EQ(Pba({"project", "role", "brain", "bob", "editor"}).exit_code, 0);
  ASSERT_NE(PbaAs(bob, {"project", "list"}).out.find("brain"), std::string::npos);
  // Only admins remove; the last admin cannot go.
  EXPECT_EQ(PbaAs(bob, {"project", "remove-member", "brain", "admin"}).exit_code, kDenied);
  const RunResult last = Pba({"project", "remove-member", "brain", "admin"});
  EXPECT_EQ(last.exit_code, kConflict) << last.err;
  EXPECT_NE(last.err.find("last admin"), std::string::npos) << last.err;

  const RunResult removed = Pba({"project", "remove-member", "brain", "bob"});
  ASSERT_EQ(removed.exit_code, 0) << removed.err;
  EXPECT_NE(removed.out.find("bob is no longer a member of brain"), std::string::npos)
      << removed.out;
  EXPECT_EQ(PbaAs(bob, {"project", "list"}).out.find("brain"), std::string::npos);
  EXPECT_EQ(Pba({"project", "remove-member", "brain", "bob"}).exit_code, kNotFound);
}

TEST_F(ServerTrustTest, PlaintextOffLoopbackIsRefusedUnlessInsecure) {
  const fs::path other = dir_.path() / "other";
  const RunResult refused =
      RunProcess({PBA_SERVER_BIN, "--data", other.string(), "--listen", "0.0.0.0:0"});
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.err.find("not a loopback address"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("--insecure"), std::string::npos) << refused.err;
  EXPECT_FALSE(fs::exists(other));
}

TEST_F(ServerTrustTest, TheDataDirectoryIsPrivateAfterARunAndAJob) {
  const RunResult submitted =
      Pba({"job", "submit", std::string(PBA_EXAMPLES_DIR) + "/quickstart.yaml", "--wait"});
  ASSERT_EQ(submitted.exit_code, 0) << submitted.out << submitted.err;
  CreateUser("carol");  // the offline tool writes pba.db too
  ASSERT_EQ(server_->Stop(), 0);

  EXPECT_EQ(ModeOf(data()), 0700u);
  EXPECT_EQ(ModeOf(data() / "pba.db"), 0600u);
  int files = 0, job_files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(data())) {
    const fs::path& path = entry.path();
    // The server's stdout and stderr as the fixture captures them
    // (server-test.out, server-test.log) are the test's files, not the server's.
    if (path.filename().string().rfind("server-test.", 0) == 0) continue;
    const mode_t mode = ModeOf(path);
    if (entry.is_symlink()) continue;
    EXPECT_EQ(mode & 077, 0u) << path << " is readable by others: " << std::oct << mode;
    if (entry.is_regular_file()) {
      ++files;
      if (path.string().find("/jobs/") != std::string::npos) ++job_files;
    }
  }
  EXPECT_GT(job_files, 2) << "the job's files (result.h5, summary.json, ...) were checked";
  EXPECT_GT(files, job_files);
}

TEST(ServerTrustAdminTest, CreateUserOnAFreshDirectoryMakesItPrivate) {
  TempDir dir;
  const fs::path data = dir.path() / "data";
  const RunResult made = RunProcess(
      {PBA_SERVER_BIN, "admin", "create-user", "root", "--server-admin", "--data", data.string()});
  ASSERT_EQ(made.exit_code, 0) << made.err;
  EXPECT_NE(made.err.find("created server admin 'root'"), std::string::npos) << made.err;
  EXPECT_EQ(ModeOf(data), 0700u);
  EXPECT_EQ(ModeOf(data / "pba.db"), 0600u);
}

}  // namespace
}  // namespace pba::testing
