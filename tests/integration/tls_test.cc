// TLS end to end: pba-server with a certificate and key, the pba client
// trusting that certificate; a plaintext client, or one trusting another
// certificate, does not get through.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/subprocess.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;

constexpr int kUnavailable = 3;  // pba's exit code when it cannot reach the server

// A self-signed certificate for 127.0.0.1 (and localhost), by the openssl
// command (scripts/deps.sh installs it).
bool MakeCertificate(const fs::path& dir, const std::string& name) {
  const RunResult made = RunProcess(
      {"/usr/bin/openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "2", "-subj",
       "/CN=localhost", "-addext", "subjectAltName=IP:127.0.0.1,DNS:localhost", "-keyout",
       (dir / (name + ".key")).string(), "-out", (dir / (name + ".pem")).string()});
  if (made.exit_code != 0) std::cerr << made.out << made.err;
  return made.exit_code == 0;
}

std::string ReadToken(const fs::path& file) {
  std::ifstream in(file);
  std::string token;
  in >> token;
  return token;
}

TEST(TlsTest, OnlyAClientTrustingTheCertificateGetsThrough) {
  TempDir dir;
  ASSERT_TRUE(MakeCertificate(dir.path(), "server"));
  ASSERT_TRUE(MakeCertificate(dir.path(), "other"));
  ServerProcess server(PBA_SERVER_BIN, dir.path() / "data");
  std::string log;
  ASSERT_TRUE(server.Start(&log, {"--tls-cert", (dir.path() / "server.pem").string(), "--tls-key",
                                  (dir.path() / "server.key").string()}))
      << log;
  ::setenv("PBA_TOKEN", ReadToken(dir.path() / "data" / "admin.token").c_str(), 1);
  ::unsetenv("PBA_TLS_CA");

  const auto pba = [&](std::vector<std::string> args) {
    args.insert(args.begin(), {PBA_CLI_BIN, "--server", server.address(), "--timeout", "10"});
    return RunProcess(args);
  };
  const RunResult trusted = pba({"--tls-ca", (dir.path() / "server.pem").string(), "whoami"});
  EXPECT_EQ(trusted.exit_code, 0) << trusted.out << trusted.err;
  EXPECT_NE(trusted.out.find("admin"), std::string::npos) << trusted.out;
  const RunResult job = pba({"--tls-ca", (dir.path() / "server.pem").string(), "job", "submit",
                             std::string(PBA_EXAMPLES_DIR) + "/quickstart.yaml", "--wait"});
  EXPECT_EQ(job.exit_code, 0) << job.out << job.err;

  const RunResult plaintext = pba({"whoami"});
  EXPECT_EQ(plaintext.exit_code, kUnavailable) << plaintext.out << plaintext.err;
  const RunResult stranger = pba({"--tls-ca", (dir.path() / "other.pem").string(), "whoami"});
  EXPECT_EQ(stranger.exit_code, kUnavailable) << stranger.out << stranger.err;
}

TEST(TlsTest, AnIncompleteOrUnreadableTlsSetupIsNamedAndNothingListens) {
  TempDir dir;
  ASSERT_TRUE(MakeCertificate(dir.path(), "server"));
  {
    ServerProcess server(PBA_SERVER_BIN, dir.path() / "data");
    std::string log;
    EXPECT_FALSE(server.Start(&log, {"--tls-cert", (dir.path() / "server.pem").string()}));
    EXPECT_NE(log.find("tls_key"), std::string::npos) << log;
  }
  {
    // A key given as the certificate: no CERTIFICATE block in it.
    ServerProcess server(PBA_SERVER_BIN, dir.path() / "data2");
    std::string log;
    EXPECT_FALSE(server.Start(&log, {"--tls-cert", (dir.path() / "server.key").string(),
                                     "--tls-key", (dir.path() / "server.key").string()}));
    EXPECT_NE(log.find("tls_cert"), std::string::npos) << log;
  }
}

}  // namespace
}  // namespace pba::testing
