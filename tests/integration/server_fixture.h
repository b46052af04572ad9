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
#include <sstream>
#include <string>
#include <vector>

#include "common/subprocess.h"

namespace pba::testing {

class ServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    server_ = std::make_unique<ServerProcess>(PBA_SERVER_BIN, dir_.path() / "data");
    std::string log;
    ASSERT_TRUE(server_->Start(&log)) << "pba-server did not start:\n" << log;
    // Jobs need a user: the admin the first start created.
    std::ifstream token(dir_.path() / "data" / "admin.token");
    std::string admin;
    ASSERT_TRUE(token >> admin);
    ::setenv("PBA_TOKEN", admin.c_str(), 1);
  }

  void TearDown() override {
    if (HasFailure()) std::cerr << "server log:\n" << ReadFile(server_->log_path());
  }

  // `pba --server ADDRESS args...`.
  RunResult Pba(std::vector<std::string> args,
                std::chrono::seconds timeout = std::chrono::seconds(120)) {
    args.insert(args.begin(), {PBA_CLI_BIN, "--server", server_->address()});
    return RunProcess(args, timeout);
  }

  // Jobs the server holds, of every state.
  size_t JobCount() {
    const RunResult list = Pba({"--json", "job", "list", "--all"});
    size_t jobs = 0;
    for (size_t at = list.out.find("\"id\""); at != std::string::npos;
         at = list.out.find("\"id\"", at + 1)) {
      ++jobs;
    }
    return jobs;
  }

  TempDir dir_;
  std::unique_ptr<ServerProcess> server_;
};

}  // namespace pba::testing
