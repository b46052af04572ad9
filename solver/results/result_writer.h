// The result files of a solution (WriteResultFiles in pba/solve.h is the
// public entry, which resolves a scene's outputs and calls this).
#pragma once

#include <filesystem>
#include <string>

#include "pba/solve.h"
#include "scene/problem.h"

namespace pba {

// Writes result.h5, result.xdmf and the tables (history.csv and .png,
// sensors.csv, profile_<name>.csv) of `solution` into the existing
// directory `dir`, with the fields `outputs` asks for; `scene_name` names
// the grid and the file's attribute. Appends the write phase to
// solution->summary.
Status WriteResults(const std::string& scene_name, const OutputOptions& outputs, Solution* solution,
                    const std::filesystem::path& dir);

}  // namespace pba
