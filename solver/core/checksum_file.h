// A result folder's list of its own files and their SHA-256 digests,
// written by the program that made the folder, last, and checked by
// whoever collects it: a file lost, cut short or changed on the way (a
// shared filesystem between a compute node and the server, a disk that
// filled) is found by name before anyone is given the result.
//
// The list is SHA256SUMS in coreutils' format, one "<hex>  <path>" line
// per file, so `sha256sum -c SHA256SUMS` checks a folder by hand too.
// Part of pba_base.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "pba/status.h"

namespace pba {

inline constexpr char kChecksumFileName[] = "SHA256SUMS";

// Bounds on what a folder's list may hold, and on the entries (files and
// folders) a folder may have (a hostile or broken folder cannot make its
// reader hold more).
inline constexpr int64_t kMaxChecksumFileBytes = 16 << 20;
inline constexpr std::size_t kMaxChecksummedFiles = 100000;

// One file of a checked folder.
struct ChecksummedFile {
  std::string path;    // relative to the folder, '/' between its parts
  std::string sha256;  // lowercase hex
  int64_t size = 0;
};

// Writes <dir>/SHA256SUMS (created as any file, the umask applying; `dir`
// is a staging folder that appears whole) listing every regular file under `dir`
// (subfolders too, sorted by path), the list itself excepted. kIo naming
// the entry when `dir` holds anything but regular files and folders (a
// symbolic link, say) or a name sha256sum would have to escape (a
// newline, a backslash), or when a file cannot be read or the list
// written.
Status WriteChecksumFile(const std::filesystem::path& dir);

// Checks `dir` against its SHA256SUMS: every file it lists is there, a
// regular file with that digest, and nothing else is (no unlisted file,
// no symbolic link, no other kind of entry). kIo naming the first file
// found wrong: "has no SHA256SUMS", "lacks X, which the list names", "X
// is damaged: its SHA-256 is ..., the list says ...", "holds X, which
// the list does not name", "line N of SHA256SUMS is not ..." (a list
// past the bounds above too). *files, on success: every file listed, with
// its digest and size, sorted by path; the list itself is not among them.
Status VerifyChecksumFile(const std::filesystem::path& dir, std::vector<ChecksummedFile>* files);

// The cheap part of that: SHA256SUMS is there and well formed, and every
// file it names is there, no digest computed. What a shared filesystem
// that shows another machine's writes late may not show yet.
Status ChecksumFileComplete(const std::filesystem::path& dir);

}  // namespace pba
