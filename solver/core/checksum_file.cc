#include "core/checksum_file.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <system_error>

#include "core/sha256.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

// Subfolders deeper than this are refused (a result has one level).
constexpr int kMaxDepth = 16;

// Every regular file under `dir` but the list, by path relative to it;
// kIo naming any other kind of entry, or past the bounds.
Status FilesUnder(const fs::path& dir, std::vector<std::string>* paths) {
  paths->clear();
  std::error_code ec;
  fs::recursive_directory_iterator it(dir, fs::directory_options::none, ec);
  if (ec) return Status::Io("cannot list " + dir.string() + ": " + ec.message());
  std::size_t entries = 0;  // folders count too: a folder of empty folders is bounded
  for (; it != fs::recursive_directory_iterator(); it.increment(ec)) {
    if (++entries > kMaxChecksummedFiles) {
      return Status::Io(dir.string() + " holds more than " + std::to_string(kMaxChecksummedFiles) +
                        " entries");
    }
    const fs::path relative = it->path().lexically_relative(dir);
    const std::string name = relative.generic_string();
    const fs::file_type type = it->symlink_status(ec).type();
    if (ec) return Status::Io("cannot read " + it->path().string() + ": " + ec.message());
    if (type == fs::file_type::directory) {
      if (it.depth() >= kMaxDepth) return Status::Io(dir.string() + " is nested too deep");
      continue;
    }
    if (type != fs::file_type::regular) {
      return Status::Io(dir.string() + " holds " + name + ", which is not a regular file" +
                        (type == fs::file_type::symlink ? " (a symbolic link)" : ""));
    }
    if (name.find_first_of("\n\\") != std::string::npos) {
      return Status::Io(dir.string() + " holds a file whose name has a newline or a backslash");
    }
    if (name == kChecksumFileName) continue;
    paths->push_back(name);
  }
  if (ec) return Status::Io("cannot list " + dir.string() + ": " + ec.message());
  std::sort(paths->begin(), paths->end());
  return Status::Ok();
}

// A path a list may name: relative, '/' between non-empty parts, none of
// them "." or "..".
bool PlainRelativePath(const std::string& path) {
  if (path.empty() || path.front() == '/' || path.back() == '/') return false;
  if (path.find('\0') != std::string::npos || path.find('\\') != std::string::npos) return false;
  std::size_t start = 0;
  while (start <= path.size()) {
    const std::size_t end = std::min(path.find('/', start), path.size());
    const std::string part = path.substr(start, end - start);
    if (part.empty() || part == "." || part == "..") return false;
    start = end + 1;
  }
  return true;
}

// The list's lines as path -> digest; kIo naming the first bad line.
Status ReadList(const fs::path& dir, std::map<std::string, std::string>* listed) {
  const fs::path list = dir / kChecksumFileName;
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(list, ec);
  if (status.type() == fs::file_type::not_found) {
    return Status::Io(dir.string() + " has no " + kChecksumFileName +
                      ", the list of its files written last: the result is incomplete");
  }
  if (status.type() != fs::file_type::regular) {
    return Status::Io(list.string() + " is not a regular file");
  }
  const uintmax_t bytes = fs::file_size(list, ec);
  if (ec || bytes > static_cast<uintmax_t>(kMaxChecksumFileBytes)) {
    return Status::Io(list.string() + " is larger than " +
                      std::to_string(kMaxChecksumFileBytes >> 20) + " MiB");
  }
  std::ifstream in(list, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.eof() && in.fail()) return Status::Io("cannot read " + list.string());
  if (!text.empty() && text.back() != '\n') {
    return Status::Io(list.string() + " does not end with a whole line: it was cut short");
  }
  std::size_t start = 0;
  for (int number = 1; start < text.size(); ++number) {
    const std::size_t end = text.find('\n', start);
    const std::string line = text.substr(start, end - start);
    start = end + 1;
    const std::string where = "line " + std::to_string(number) + " of " + list.string();
    // "<64 hex>  <path>" (or " *<path>", sha256sum's binary mode).
    std::string hex = line.substr(0, 64);
    std::transform(hex.begin(), hex.end(), hex.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (line.size() < 67 || !IsSha256Hex(hex) || line[64] != ' ' ||
        (line[65] != ' ' && line[65] != '*')) {
      return Status::Io(where + " is not \"<SHA-256 in hex>  <file>\"");
    }
    const std::string path = line.substr(66);
    if (!PlainRelativePath(path) || path == kChecksumFileName) {
      return Status::Io(where + " names a path outside the folder or not a file's");
    }
    if (listed->size() >= kMaxChecksummedFiles) {
      return Status::Io(list.string() + " names more than " + std::to_string(kMaxChecksummedFiles) +
                        " files");
    }
    if (!listed->emplace(path, hex).second) return Status::Io(where + " names " + path + " again");
  }
  return Status::Ok();
}

}  // namespace

Status WriteChecksumFile(const fs::path& dir) {
  std::vector<std::string> paths;
  PBA_RETURN_IF_ERROR(FilesUnder(dir, &paths));
  std::ostringstream list;
  for (const std::string& path : paths) {
    std::string hex;
    PBA_RETURN_IF_ERROR(FileSha256Hex(dir / path, &hex));
    list << hex << "  " << path << '\n';
  }
  // Created as the folder's other files are (the umask applies: a
  // server's results stay private); a write cut short leaves a list that
  // does not end with a whole line, which no check takes.
  std::ofstream out(dir / kChecksumFileName, std::ios::binary | std::ios::trunc);
  out << list.str();
  out.close();
  if (!out) return Status::Io("cannot write " + (dir / kChecksumFileName).string());
  return Status::Ok();
}

Status ChecksumFileComplete(const fs::path& dir) {
  std::map<std::string, std::string> listed;
  PBA_RETURN_IF_ERROR(ReadList(dir, &listed));
  for (const auto& entry : listed) {
    std::error_code ec;
    if (fs::symlink_status(dir / entry.first, ec).type() != fs::file_type::regular) {
      return Status::Io(dir.string() + " lacks " + entry.first + ", which " + kChecksumFileName +
                        " names");
    }
  }
  return Status::Ok();
}

Status VerifyChecksumFile(const fs::path& dir, std::vector<ChecksummedFile>* files) {
  files->clear();
  std::map<std::string, std::string> listed;
  PBA_RETURN_IF_ERROR(ReadList(dir, &listed));
  std::vector<std::string> present;
  PBA_RETURN_IF_ERROR(FilesUnder(dir, &present));
  const std::set<std::string> there(present.begin(), present.end());
  for (const std::string& path : present) {
    if (listed.count(path) == 0) {
      return Status::Io(dir.string() + " holds " + path + ", which " + kChecksumFileName +
                        " does not name");
    }
  }
  for (const auto& [path, expected] : listed) {
    if (there.count(path) == 0) {
      return Status::Io(dir.string() + " lacks " + path + ", which " + kChecksumFileName +
                        " names");
    }
    ChecksummedFile file;
    file.path = path;
    PBA_RETURN_IF_ERROR(FileSha256Hex(dir / path, &file.sha256, &file.size));
    if (file.sha256 != expected) {
      return Status::Io(dir.string() + "/" + path + " is damaged: its SHA-256 is " + file.sha256 +
                        ", " + kChecksumFileName + " says " + expected + " (" +
                        std::to_string(file.size) + " bytes now)");
    }
    files->push_back(std::move(file));
  }
  return Status::Ok();
}

}  // namespace pba
