// pba-server's offline administration and first start, as a user runs them:
// `pba-server admin create-user` and the admin token of a first start.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <regex>
#include <string>

#include "common/subprocess.h"

namespace pba::testing {
namespace {

const std::regex kToken("[0-9a-f]{64}\n");

TEST(ServerAdminTest, CreateUserPrintsTheTokenOnceAndRefusesDuplicates) {
  TempDir dir;
  const std::string data = (dir.path() / "data").string();
  RunResult result = RunProcess({PBA_SERVER_BIN, "admin", "create-user", "eve", "--data", data});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_TRUE(std::regex_match(result.out, kToken)) << result.out;
  EXPECT_NE(result.err.find("Bearer"), std::string::npos) << result.err;

  result = RunProcess({PBA_SERVER_BIN, "admin", "create-user", "eve", "--data", data});
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.err.find("already exists"), std::string::npos) << result.err;
  EXPECT_TRUE(result.out.empty());
  result = RunProcess({PBA_SERVER_BIN, "admin", "create-user", "a/b", "--data", data});
  EXPECT_NE(result.exit_code, 0);
  EXPECT_NE(result.err.find("'/'"), std::string::npos) << result.err;
  // The server itself still wants --data.
  EXPECT_EQ(RunProcess({PBA_SERVER_BIN}).exit_code, 2);
}

TEST(ServerAdminTest, AFirstStartWritesTheAdminTokenAndSaysWhere) {
  TempDir dir;
  ServerProcess server(PBA_SERVER_BIN, dir.path() / "data");
  std::string log;
  ASSERT_TRUE(server.Start(&log)) << log;
  const std::filesystem::path file = dir.path() / "data" / "admin.token";
  struct stat info {};
  ASSERT_EQ(::stat(file.c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0600u);
  std::ifstream in(file);
  const std::string token((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_TRUE(std::regex_match(token, kToken)) << token;
  EXPECT_EQ(server.Stop(), 0);
  std::ifstream server_log(server.log_path());
  const std::string text((std::istreambuf_iterator<char>(server_log)),
                         std::istreambuf_iterator<char>());
  EXPECT_NE(text.find(file.string()), std::string::npos) << text;
  EXPECT_EQ(text.find(token.substr(0, 64)), std::string::npos) << "the token must not be logged";
}

}  // namespace
}  // namespace pba::testing
