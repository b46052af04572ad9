// Files that appear whole or not at all: written to a temporary sibling,
// fsynced, renamed over the destination, and the directory fsynced, so a crash
// leaves either the old content or the new one.
#pragma once

#include <filesystem>
#include <string_view>

#include "pba/status.h"

namespace pba {

Status WriteFileAtomically(const std::filesystem::path& path, std::string_view content);

// Makes a rename in `dir` durable (fsync of the directory). Best effort: the
// rename itself has happened either way.
void SyncDirectory(const std::filesystem::path& dir);

}  // namespace pba
