// Abaqus/CalculiX input deck of a resolved problem (ExportAbaqusInput in
// pba/solve.h is the public entry, from a scene).
#pragma once

#include <filesystem>
#include <string>

#include "pba/status.h"
#include "scene/problem.h"

namespace pba {

// Writes the problem's model (mesh, node sets named as the face sets, one
// element set, material and section per material, resolved constraints,
// pressures, tractions and gravity, one static step printing reactions and
// displacements) as an input deck that CalculiX runs (`ccx -i NAME`). SI
// units. kIo when it cannot write.
Status WriteAbaqusDeck(const Problem& problem, const std::filesystem::path& file);

// The widest a number may be in a deck: CalculiX reads every number of a
// data line in a field of at most 20 characters, and a longer one stops it
// (exit 201 on *NODE) or is silently cut.
constexpr int kAbaqusFieldWidth = 20;

// `value` for a data line of a deck: at most kAbaqusFieldWidth characters,
// the shortest text that reads back as `value` when one fits (0.45, not
// 0.45000000000000001; 17 significant digits at most), else as many
// significant digits as fit (13 for -1.2345678901234567e+200).
std::string AbaqusNumber(double value);

}  // namespace pba
