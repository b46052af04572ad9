// TLS end to end: pba-server with a certificate and key, the pba client
// trusting that certificate; a plaintext client, or one trusting another
// certificate, does not get through. The same for the web view
// (--http), whose session cookie is then Secure.
#include <gtest/gtest.h>
#include <httplib.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
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

// pba-server --http with the gRPC certificate: the page and its API over
// HTTPS to a client trusting the certificate, the session cookie marked
// Secure; a plaintext request and a client trusting another certificate
// get nothing.
TEST(TlsTest, TheWebViewIsServedOverHttpsWithASecureCookie) {
  TempDir dir;
  ASSERT_TRUE(MakeCertificate(dir.path(), "server"));
  ASSERT_TRUE(MakeCertificate(dir.path(), "other"));
  ServerProcess server(PBA_SERVER_BIN, dir.path() / "data");
  std::string log;
  ASSERT_TRUE(server.Start(&log, {"--tls-cert", (dir.path() / "server.pem").string(), "--tls-key",
                                  (dir.path() / "server.key").string(), "--http", "127.0.0.1:0"}))
      << log;
  std::ifstream info(dir.path() / "data" / "server.json");
  const std::string json((std::istreambuf_iterator<char>(info)), std::istreambuf_iterator<char>());
  std::smatch match;
  ASSERT_TRUE(std::regex_search(json, match, std::regex("\"http\":\"127.0.0.1:([0-9]+)\"")))
      << json;
  const int port = std::stoi(match[1].str());
  const std::string admin = ReadToken(dir.path() / "data" / "admin.token");
  const std::string origin = "https://127.0.0.1:" + std::to_string(port);

  httplib::SSLClient trusting("127.0.0.1", port);
  trusting.set_ca_cert_path((dir.path() / "server.pem").c_str());
  trusting.enable_server_certificate_verification(true);
  const auto page = trusting.Get("/");
  ASSERT_TRUE(page) << httplib::to_string(page.error());
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("/app/app.js"), std::string::npos);
  const auto signed_in = trusting.Post("/api/session", {{"Origin", origin}},
                                       "{\"token\":\"" + admin + "\"}", "application/json");
  ASSERT_TRUE(signed_in) << httplib::to_string(signed_in.error());
  ASSERT_EQ(signed_in->status, 200) << signed_in->body;
  const std::string cookie = signed_in->get_header_value("Set-Cookie");
  EXPECT_NE(cookie.find("; Secure"), std::string::npos) << cookie;
  EXPECT_NE(cookie.find("HttpOnly"), std::string::npos) << cookie;
  std::smatch csrf, token;
  ASSERT_TRUE(std::regex_search(signed_in->body, csrf, std::regex("\"csrf\":\"([0-9a-f]{64})\"")));
  ASSERT_TRUE(std::regex_search(cookie, token, std::regex("^(pba_token=[^;]+)")));
  const auto who =
      trusting.Post("/api/v1/AtlasService/WhoAmI",
                    {{"Cookie", token[1].str()}, {"X-PBA-CSRF", csrf[1].str()}, {"Origin", origin}},
                    "{}", "application/json");
  ASSERT_TRUE(who);
  EXPECT_EQ(who->status, 200) << who->body;
  EXPECT_NE(who->body.find("\"name\":\"admin\""), std::string::npos) << who->body;
  // An http:// origin is another site's to an https:// server.
  const auto downgraded = trusting.Post("/api/v1/AtlasService/WhoAmI",
                                        {{"Cookie", token[1].str()},
                                         {"X-PBA-CSRF", csrf[1].str()},
                                         {"Origin", "http://127.0.0.1:" + std::to_string(port)}},
                                        "{}", "application/json");
  ASSERT_TRUE(downgraded);
  EXPECT_EQ(downgraded->status, 403);

  httplib::Client plaintext("127.0.0.1", port);
  plaintext.set_read_timeout(5, 0);
  const auto clear = plaintext.Get("/");
  EXPECT_TRUE(!clear || clear->status >= 400) << clear->status;
  httplib::SSLClient stranger("127.0.0.1", port);
  stranger.set_ca_cert_path((dir.path() / "other.pem").c_str());
  stranger.enable_server_certificate_verification(true);
  const auto refused = stranger.Get("/");
  EXPECT_FALSE(refused);
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
