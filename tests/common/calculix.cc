#include "common/calculix.h"

#include <cctype>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace pba::testing {
namespace fs = std::filesystem;

std::string FindCcx() {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (!dir.empty() && fs::exists(fs::path(dir) / "ccx")) return (fs::path(dir) / "ccx").string();
  }
  return "";
}

CcxRun RunCcx(const std::string& ccx, const fs::path& dir, const std::string& job, int threads,
              std::chrono::seconds timeout) {
  CcxRun result;
  const auto start = std::chrono::steady_clock::now();
  // ccx writes next to its input; run it from a shell in that folder.
  result.process =
      RunProcess({"/bin/sh", "-c",
                  "cd '" + dir.string() + "' && OMP_NUM_THREADS=" + std::to_string(threads) +
                      " exec '" + ccx + "' -i '" + job + "'"},
                 timeout);
  result.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

CcxResult ParseDat(const fs::path& dat) {
  CcxResult result;
  std::ifstream in(dat);
  std::string line;
  enum { kNone, kTotal, kDisplacement } block = kNone;
  std::string set;
  while (std::getline(in, line)) {
    if (line.find("total force (fx,fy,fz) for set") != std::string::npos) {
      std::istringstream words(line.substr(line.find("set") + 4));
      words >> set;
      block = kTotal;
      continue;
    }
    if (line.find("displacements (vx,vy,vz) for set") != std::string::npos) {
      block = kDisplacement;
      continue;
    }
    std::istringstream values(line);
    if (block == kTotal) {
      std::array<double, 3> f;
      if (values >> f[0] >> f[1] >> f[2]) {
        result.totals[set] = f;
        block = kNone;
      }
    } else if (block == kDisplacement) {
      int node;
      std::array<double, 3> u;
      if (values >> node >> u[0] >> u[1] >> u[2]) result.displacement[node] = u;
    }
  }
  return result;
}

std::string CcxSetName(const std::string& set) {
  std::string name = set;
  for (char& c : name) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return name;
}

}  // namespace pba::testing
