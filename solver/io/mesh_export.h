// Export of a region-labelled mesh (the atlas's) to the files people open it
// with: VTK XML (.vtu, ParaView), XDMF 3 + HDF5 (.xdmf, ParaView / VisIt),
// Gmsh 4.1 ASCII (.msh) and an Abaqus / CalculiX deck (.inp). Geometry and
// labels only: no fields, materials or loads (for an analysis deck see
// ExportAbaqusInput in pba/solve.h).
//
// Elements: 4-node tetrahedra, 10-node tetrahedra (Mesh::midside non-empty)
// or 8-node hexahedra, one kind per mesh. Each format gets its own node
// order (Mesh holds the C3D10 / VTK_HEXAHEDRON orders, mesh.h):
//   TET4   VTK_TETRA (10), XDMF Tetrahedron, Gmsh 4, C3D4: the mesh's order.
//   TET10  VTK_QUADRATIC_TETRA (24), XDMF Tetrahedron_10, C3D10: corners,
//          then edges (0,1) (1,2) (2,0) (0,3) (1,3) (2,3), the mesh's order;
//          Gmsh 11: corners, then edges (0,1) (1,2) (2,0) (3,0) (3,2) (3,1),
//          i.e. the last two mid-edge nodes swapped.
//   HEX8   VTK_HEXAHEDRON (12), XDMF Hexahedron, Gmsh 5, C3D8: the mesh's
//          order.
//
// Regions. Element e's region is element_region[e], or 0 for a one-region
// mesh (region_names and element_region empty), which is named "body".
//   .vtu   cell data `region` (Int32); names as XML comments, one per region.
//   .xdmf  cell attribute `region`; names as Information elements
//          (Name "region <index>", Value the name).
//   .msh   a 3-D physical group and a volume entity per region, both tagged
//          region index + 1, the group named after the region
//          ($PhysicalNames); each region's elements form one block.
//   .inp   an *ELSET per region, its name sanitised to Abaqus rules
//          (letters, digits, underscore, starting with a letter, at most 80
//          characters, unique ignoring case), with a comment mapping each set
//          to the region's index and full name; face sets as *NSET (sanitised
//          the same way).
// Numbering: files with 1-based ids (.msh, .inp) use the mesh's node and
// element index + 1; .vtu and .xdmf use the 0-based indices.
//
// Files are ASCII except the .h5 (little-endian float64 / int64). Writes are
// atomic: each file goes to a temporary file in its directory and is
// renamed over the target; for .xdmf the .h5 is written first, then the
// .xdmf (if the .xdmf fails, the new .h5 is removed again). On failure no
// new file and no temporary file is left.
#pragma once

#include <filesystem>
#include <string>

#include "mesh/mesh.h"
#include "pba/status.h"

namespace pba {

enum class MeshFormat { kVtu, kXdmf, kGmsh, kAbaqus };

struct MeshExportOptions {
  // Coordinates written in millimetres (the atlas's unit; Mesh::nodes times
  // 1000) when true, else in metres as stored. Every format states the unit
  // in its comment / metadata.
  bool millimetres = true;
  // Free text written where the format has a comment or metadata slot: the
  // VTU and XDMF leading XML comment (and an XDMF Information element), a
  // Gmsh $Comments section (which Gmsh skips), the Abaqus *HEADING. E.g.
  // "synthetic atlas - not for clinical use". One line; newlines become
  // spaces.
  std::string title;
};

// The format named by `file`'s extension (case-insensitive): .vtu, .xdmf,
// .msh, .inp. kInvalidArgument (field "file") naming any other extension.
Status MeshFormatFromPath(const std::filesystem::path& file, MeshFormat* format);

// Writes `mesh` to `file` in the format its extension names; .xdmf also
// writes <stem>.h5 beside it (datasets /mesh/nodes: nodes x 3 float64 in the
// chosen unit, /mesh/topology: elements x nodes-per-element int64 0-based,
// /mesh/region: elements int64).
// kInvalidArgument for an unknown extension (field "file") or a bad mesh,
// naming the field: no nodes or elements ("mesh.nodes", "mesh.tets" /
// "mesh.hexes"), a node index out of range, midside not one row per tet
// ("mesh.midside"), element_region not one entry per element or an entry
// outside region_names ("mesh.element_region"), region_names set without
// element_region ("mesh.region_names"). kIo when a file cannot be written.
Status ExportMesh(const Mesh& mesh, const std::filesystem::path& file,
                  const MeshExportOptions& options = {});

}  // namespace pba
