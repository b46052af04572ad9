#include "files.h"

#include <cerrno>
#include <cstdio>
#include <fstream>
#include <vector>

#include "core/atomic_write.h"
#include "core/sha256.h"

namespace pba::cli {

std::string Sha256File(const std::filesystem::path& path) {
  std::string hex;
  return FileSha256Hex(path, &hex).ok() ? hex : "";
}

bool WriteFileAtomically(const std::filesystem::path& path, const std::string& content,
                         unsigned mode) {
  return AtomicWriteText(path, content, mode).ok();
}

std::string UnsafeFileNameReason(const std::string& name) {
  if (name.empty()) return "it is empty";
  if (name == "." || name == "..") return "it names a directory, not a file";
  if (name.size() > kMaxFileNameBytes) {
    return "it is " + std::to_string(name.size()) + " bytes long (at most " +
           std::to_string(kMaxFileNameBytes) + ")";
  }
  for (unsigned char c : name) {
    if (c == '/' || c == '\\') return "it has a directory separator ('/' or '\\')";
    if (c == 0) return "it has a NUL byte";
    if (c < 0x20 || c == 0x7f) return "it has a control character";
  }
  return "";
}

std::string QuotedName(const std::string& name) {
  std::string out = "\"";
  for (unsigned char c : name) {
    if (c < 0x20 || c == 0x7f || c == '"' || c == '\\') {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\x%02x", c);
      out += escaped;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out + "\"";
}

std::string FoldCase(const std::string& name) {
  std::string folded = name;
  for (char& c : folded) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return folded;
}

bool RenameNoReplace(const std::filesystem::path& from, const std::filesystem::path& to) {
  const Status moved = MoveIntoPlace(from, to, /*never_replace=*/true);
  if (!moved.ok()) errno = moved.code() == Status::Code::kAlreadyExists ? EEXIST : EIO;
  return moved.ok();
}

}  // namespace pba::cli
