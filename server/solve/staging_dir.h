// StagingDir: a result directory that appears whole or not at all.
// Files are written into a hidden sibling of the destination; Commit() fsyncs
// them and renames the sibling onto the destination (replacing an older
// result: check it with CheckOutputDir first); a StagingDir destroyed
// before Commit() removes what it wrote.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

#include "pba/status.h"

namespace pba {

// Whether a tool's result may go to `out`, which StagingDir::Commit would
// replace whole: yes when nothing is there or an empty directory; with
// `force` also a directory holding nothing but an earlier result of the
// tool (`ours` says whether an entry is something the tool writes). A
// file, a symbolic link, or a directory holding anything else is refused
// even with `force`: what the tool did not write is not its to delete.
// Refusals are kInvalidArgument naming the field "--out" and the tool
// (`tool`, e.g. "pba-solve") and say what to do.
using OutputEntryTest = std::function<bool(const std::filesystem::directory_entry& entry)>;
Status CheckOutputDir(const std::filesystem::path& out, bool force, const std::string& tool,
                      const OutputEntryTest& ours);

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
