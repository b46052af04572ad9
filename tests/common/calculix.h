// Running the peer code, CalculiX (Debian package calculix-ccx, installed by
// scripts/deps.sh), on a deck written by ExportAbaqusInput, and reading its
// answer back: shared by calculix_peer_test and peer_bench.
#pragma once

#include <array>
#include <chrono>
#include <filesystem>
#include <map>
#include <string>

#include "common/subprocess.h"

namespace pba::testing {

// The path of `ccx` on PATH (or in /usr/bin when PATH is unset); empty if absent.
std::string FindCcx();

struct CcxRun {
  RunResult process;        // exit code and captured output of ccx
  double wall_seconds = 0;  // the whole ccx process: read, solve, write the .dat
};

// Runs `ccx -i <job>` in `dir`, where <job>.inp must be, with OMP_NUM_THREADS
// set to `threads`; ccx writes <job>.dat, <job>.frd and <job>.sta beside it.
CcxRun RunCcx(const std::string& ccx, const std::filesystem::path& dir,
              const std::string& job = "model", int threads = 2,
              std::chrono::seconds timeout = std::chrono::seconds(300));

struct CcxResult {
  std::map<std::string, std::array<double, 3>> totals;  // set name (upper case) -> force [N]
  std::map<int, std::array<double, 3>> displacement;    // node number (1-based) -> u [m]
};

// Reads the reactions (*NODE PRINT, TOTALS=ONLY) and displacements (*NODE
// PRINT of U) of a CalculiX .dat file; where ccx printed every increment, the
// last one wins. A missing file gives an empty result.
CcxResult ParseDat(const std::filesystem::path& dat);

// A PBA face set name as CalculiX prints it in the .dat (upper case).
std::string CcxSetName(const std::string& set);

}  // namespace pba::testing
