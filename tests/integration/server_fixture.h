// A real pba-server on loopback with the admin's token in PBA_TOKEN, and the
// real client binary run against it: the fixture the client's integration
// tests share.
#pragma once

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/subprocess.h"

namespace pba::testing {

class ServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    server_ = std::make_unique<ServerProcess>(PBA_SERVER_BIN, dir_.path() / "data");
    std::string log;
    ASSERT_TRUE(server_->Start(&log, ServerArgs())) << "pba-server did not start:\n" << log;
    // Jobs need a user: the admin the first start created.
    std::ifstream token(dir_.path() / "data" / "admin.token");
    std::string admin;
    ASSERT_TRUE(token >> admin);
    ::setenv("PBA_TOKEN", admin.c_str(), 1);
  }

  // pba-server's options beyond the fixture's own.
  virtual std::vector<std::string> ServerArgs() const { return {}; }

  void TearDown() override {
    if (HasFailure()) std::cerr << "server log:\n" << ReadFile(server_->log_path());
  }

  // `pba --server ADDRESS args...`.
  RunResult Pba(std::vector<std::string> args,
                std::chrono::seconds timeout = std::chrono::seconds(120)) {
    args.insert(args.begin(), {PBA_CLI_BIN, "--server", server_->address()});
    return RunProcess(args, timeout);
  }

  std::filesystem::path WriteScene(const std::string& name, const std::string& yaml) {
    const std::filesystem::path path = dir_.path() / name;
    std::ofstream(path) << yaml;
    return path;
  }

  static std::string JobId(const RunResult& submitted) {
    std::smatch match;
    static const std::regex kPattern("Submitted job (\\S+)");
    return std::regex_search(submitted.out, match, kPattern) ? match[1].str() : "";
  }

  // Polls `pba job status --json` until its "state" is `state`.
  bool WaitForState(const std::string& id, const std::string& state, std::chrono::seconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      const RunResult status = Pba({"--json", "job", "status", id});
      if (status.out.find("\"state\": \"" + state + "\"") != std::string::npos) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return false;
  }

  // Jobs the server holds, of every state.
  size_t JobCount() { return CountOf(Pba({"--json", "job", "list", "--all"}).out, "\"id\""); }

  TempDir dir_;
  std::unique_ptr<ServerProcess> server_;
};

}  // namespace pba::testing
