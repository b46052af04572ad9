// Abaqus/CalculiX input deck of a resolved problem (ExportAbaqusInput in
// pba/solve.h is the public entry, from a scene).
#pragma once

#include <filesystem>
#include <string>

#include "io/abaqus_format.h"
#include "pba/status.h"
#include "scene/problem.h"

namespace pba {

// Writes the problem's model (mesh, node sets named as the face sets, one
// element set, material and section per material, resolved constraints,
// pressures, tractions and gravity, one static step printing reactions and
// displacements) as an input deck that CalculiX runs (`ccx -i NAME`). SI
// units. kIo when it cannot write.
Status WriteAbaqusDeck(const Problem& problem, const std::filesystem::path& file);

}  // namespace pba
