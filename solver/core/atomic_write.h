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

// How AtomicWrite treats what is at the target, and the file's mode.
struct AtomicWriteOptions {
  // Never replace anything at the target (a dangling symbolic link counts):
  // kAlreadyExists naming it, which stays untouched, and no temporary file
  // is left. The check is the rename itself (renameat2 RENAME_NOREPLACE, or
  // link() and unlink() where the file system refuses the flag), so a file
  // that appears meanwhile is never replaced either.
  bool never_replace = false;
  // The file's permissions (the umask does not apply).
  unsigned mode = 0600;
};

// Writes `file` atomically: write(fd, temporary path) fills a temporary file
// (a hidden name beginning "." + file name, ending in `suffix`) in the same
// directory, which is then synced and renamed over `file` (or, with
// options.never_replace, to `file` only when nothing is there); on failure
// the temporary file is removed. The callback may write through `fd` or
// reopen the path by name (e.g. a library that opens files itself). kIo when
// the directory does not exist or any step fails.
Status AtomicWrite(const std::filesystem::path& file, const std::string& suffix,
                   const std::function<Status(int fd, const std::string& temporary)>& write,
                   const AtomicWriteOptions& options = {});

// write(2) of all `size` bytes, retrying on EINTR; `path` names the file in
// the error.
Status WriteAll(int fd, const void* data, std::size_t size, const std::string& path);

// AtomicWrite of a text. The file gets `mode` (0600, as the temporary file
// is made, unless another is asked for; the umask does not apply): whatever
// is at `file` is replaced, a symbolic link there included, never followed.
Status AtomicWriteText(const std::filesystem::path& file, std::string_view text,
                       unsigned mode = 0600);
// The same with every option (never_replace: kAlreadyExists when something
// is at `file`).
Status AtomicWriteText(const std::filesystem::path& file, std::string_view text,
                       const AtomicWriteOptions& options);

// The last step of AtomicWrite for a file written and synced elsewhere (a
// download resumed across runs keeps one temporary name): renames `from` to
// `to` (with `never_replace` as AtomicWriteOptions::never_replace) and
// syncs the directory of `to`. kAlreadyExists "<to> already exists" when
// `never_replace` finds something there; kIo "cannot move <to> into place:
// <why>" when the rename fails otherwise.
Status MoveIntoPlace(const std::filesystem::path& from, const std::filesystem::path& to,
                     bool never_replace);

// Whether `name` is one of AtomicWrite's temporary files
// (".NAME.partial-XXXXXX", then any suffix): what a crash between the write
// and the rename leaves, for a sweep to remove.
bool IsAtomicWriteTemporary(std::string_view name);

// Makes a rename in `dir` durable (fsync of the directory). Best effort: the
// rename itself has happened either way.
void SyncDirectory(const std::filesystem::path& dir);

// A new directory `dir`, whole or not at all: fill(temporary) writes into a
// hidden directory beside it ("." + its name + ".partial-XXXXXX"), which is
// then synced and renamed to `dir` (MoveDirectoryIntoPlace), and the parent
// synced; on failure the temporary directory is removed and `dir` is as it
// was. The files `fill` writes must be durable on their own
// (AtomicWriteText's are). Without `replace`, kIo when `dir` exists and is
// not an empty directory; with it, whatever is at `dir` is replaced whole.
// kIo when its parent is not a directory.
Status AtomicWriteDirectory(const std::filesystem::path& dir,
                            const std::function<Status(const std::filesystem::path&)>& fill,
                            bool replace = false);

// The last step of AtomicWriteDirectory for a directory filled and synced
// elsewhere (StagingDir): renames `filled` to `dir` (which replaces an
// empty directory) and syncs the parent. With `replace`, whatever is at
// `dir` (a non-empty directory too) is first renamed aside (".NAME.old-XXXXXX"
// beside it), removed once `filled` is in place, and renamed back when that
// fails: `dir` holds the old content or the new, never a mix, and a crash
// between the renames leaves the old content under the hidden name. kIo
// "cannot replace <dir>: <why>" when it cannot be moved aside, "cannot move
// <dir> into place: <why>" when `filled` cannot be moved in.
Status MoveDirectoryIntoPlace(const std::filesystem::path& filled, const std::filesystem::path& dir,
                              bool replace);

}  // namespace pba
