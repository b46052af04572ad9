// Atomic file writes: the content goes into a temporary file in the target
// directory, which is synced and renamed over the target, so a reader sees
// the old file or the whole new one, and a failed write leaves nothing.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>

#include "pba/status.h"

namespace pba {

// Writes `file` atomically: write(fd, temporary path) fills a temporary file
// (a hidden name beginning "." + file name, ending in `suffix`) in the same
// directory, which is then synced and renamed over `file`; on failure the
// temporary file is removed. The callback may write through `fd` or reopen
// the path by name (e.g. a library that opens files itself). kIo when the
// directory does not exist or any step fails.
Status AtomicWrite(const std::filesystem::path& file, const std::string& suffix,
                   const std::function<Status(int fd, const std::string& temporary)>& write);

// write(2) of all `size` bytes, retrying on EINTR; `path` names the file in
// the error.
Status WriteAll(int fd, const void* data, std::size_t size, const std::string& path);

// AtomicWrite of a text. The file gets `mode` (0600, as the temporary file
// is made, unless another is asked for; the umask does not apply): whatever
// is at `file` is replaced, a symbolic link there included, never followed.
Status AtomicWriteText(const std::filesystem::path& file, std::string_view text,
                       unsigned mode = 0600);

// Whether `name` is one of AtomicWrite's temporary files
// (".NAME.partial-XXXXXX", then any suffix): what a crash between the write
// and the rename leaves, for a sweep to remove.
bool IsAtomicWriteTemporary(std::string_view name);

// Makes a rename in `dir` durable (fsync of the directory). Best effort: the
// rename itself has happened either way.
void SyncDirectory(const std::filesystem::path& dir);

// A new directory `dir`, whole or not at all: fill(temporary) writes into a
// hidden directory beside it ("." + its name + ".partial-XXXXXX"), which is
// then synced and renamed to `dir` (replacing an empty directory), and the
// parent synced; on failure the temporary directory is removed. The files
// `fill` writes must be durable on their own (AtomicWriteText's are). kIo when `dir` exists and is
// not an empty directory, or its parent is not a directory.
Status AtomicWriteDirectory(const std::filesystem::path& dir,
                            const std::function<Status(const std::filesystem::path&)>& fill);

}  // namespace pba
