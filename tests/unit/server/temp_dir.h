// A temporary directory for the pba-server tests, apart from
// server_test_support.h so that tests of the proto-free store layer can use
// it without protobuf.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <random>
#include <string>

namespace pba::testing {

// A fresh directory under the system temp dir, removed with its content.
class TempDir {
 public:
  TempDir() {
    std::random_device random;
    path_ = std::filesystem::temp_directory_path() /
            ("pba-server-test-" + std::to_string(::getpid()) + "-" + std::to_string(random()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace pba::testing
