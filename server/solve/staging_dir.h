// StagingDir: a result directory that appears whole or not at all.
// Files are written into a hidden sibling of the destination; Commit() fsyncs
// them and renames the sibling onto the destination (replacing an older
// result); a StagingDir destroyed before Commit() removes what it wrote.
#pragma once

#include <filesystem>

#include "pba/status.h"

namespace pba {

class StagingDir {
 public:
  // Creates the hidden sibling of `destination` (and destination's parent).
  static Status Create(const std::filesystem::path& destination, StagingDir* out);

  StagingDir() = default;
  StagingDir(StagingDir&& other) noexcept;
  StagingDir& operator=(StagingDir&& other) noexcept;
  StagingDir(const StagingDir&) = delete;
  StagingDir& operator=(const StagingDir&) = delete;
  ~StagingDir();

  // Where to write the files.
  const std::filesystem::path& path() const { return staging_; }
  Status Commit();

 private:
  void Discard();
  std::filesystem::path destination_;
  std::filesystem::path staging_;
  bool committed_ = false;
};

}  // namespace pba
