#include "credentials.h"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "core/atomic_write.h"
#include "files.h"

namespace pba::cli {
namespace fs = std::filesystem;
namespace {

std::map<std::string, std::string> ReadAll() {
  std::map<std::string, std::string> tokens;
  std::ifstream in(CredentialsPath());
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string server, token;
    if (words >> server >> token) tokens[server] = token;
  }
  return tokens;
}

bool WriteAll(const std::map<std::string, std::string>& tokens, std::string* error) {
  const fs::path path = CredentialsPath();
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  if (ec) {
    *error = "cannot create " + path.parent_path().string() + ": " + ec.message();
    return false;
  }
  std::string content;
  for (const auto& [server, token] : tokens) content += server + " " + token + "\n";
  if (const Status written = AtomicWriteText(path, content, 0600); !written.ok()) {
    *error = written.message();
    return false;
  }
  return true;
}

}  // namespace

fs::path CredentialsPath() {
  if (const char* xdg = std::getenv("XDG_CONFIG_HOME"); xdg != nullptr && *xdg != '\0')
    return fs::path(xdg) / "pba" / "credentials";
  const char* home = std::getenv("HOME");
  return fs::path(home != nullptr ? home : ".") / ".config" / "pba" / "credentials";
}

std::string FindToken(const std::string& server) {
  if (const char* env = std::getenv("PBA_TOKEN"); env != nullptr && *env != '\0') return env;
  const auto tokens = ReadAll();
  const auto it = tokens.find(server);
  return it == tokens.end() ? "" : it->second;
}

bool StoreToken(const std::string& server, const std::string& token, std::string* error) {
  auto tokens = ReadAll();
  tokens[server] = token;
  return WriteAll(tokens, error);
}

bool ForgetToken(const std::string& server, std::string* error) {
  auto tokens = ReadAll();
  if (tokens.erase(server) == 0) return false;
  return WriteAll(tokens, error);
}

}  // namespace pba::cli
