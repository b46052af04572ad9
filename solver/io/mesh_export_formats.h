// Internals of mesh_export: the per-format writers and what they share.
// ExportMesh validates the mesh before any of these run.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include "core/number_format.h"
#include "io/mesh_export.h"
#include "mesh/mesh.h"
#include "pba/status.h"

namespace pba::mesh_export {

// element_region[e], or 0 for a one-region mesh.
int ElementRegion(const Mesh& mesh, int e);

// region_names, or {"body"} for a one-region mesh.
std::vector<std::string> RegionNames(const Mesh& mesh);

// Coordinate scale from metres: 1000 or 1; and its unit name, "mm" or "m".
double Scale(const MeshExportOptions& options);
const char* Unit(const MeshExportOptions& options);

// `text` on one line (newlines and tabs as spaces).
std::string OneLine(const std::string& text);

// `text` escaped for an XML attribute value or element text.
std::string XmlEscape(const std::string& text);

// `text` safe inside an XML comment (no "--", no trailing '-').
std::string XmlComment(const std::string& text);

// The file contents of each text format.
std::string VtuText(const Mesh& mesh, const MeshExportOptions& options);
std::string GmshText(const Mesh& mesh, const MeshExportOptions& options);
std::string AbaqusText(const Mesh& mesh, const MeshExportOptions& options);

// Writes the .h5 beside `xdmf`, then `xdmf` itself (both atomically).
Status WriteXdmf(const Mesh& mesh, const std::filesystem::path& xdmf,
                 const MeshExportOptions& options);

}  // namespace pba::mesh_export
