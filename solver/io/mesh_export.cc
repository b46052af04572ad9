// ExportMesh: validation, dispatch on the extension, the helpers the
// formats share, and the VTK XML unstructured grid (.vtu).
#include "io/mesh_export.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <string>
#include <vector>

#include "core/atomic_write.h"
#include "core/format.h"
#include "io/mesh_export_formats.h"

namespace pba {
namespace mesh_export {

int ElementRegion(const Mesh& mesh, int e) {
  return mesh.element_region.empty() ? 0 : mesh.element_region[e];
}

std::vector<std::string> RegionNames(const Mesh& mesh) {
  return mesh.region_names.empty() ? std::vector<std::string>{"body"} : mesh.region_names;
}

double Scale(const MeshExportOptions& options) { return options.millimetres ? 1000.0 : 1.0; }

const char* Unit(const MeshExportOptions& options) { return options.millimetres ? "mm" : "m"; }

std::string OneLine(const std::string& text) {
  std::string line = text;
  for (char& c : line) {
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  }
  return line;
}

std::string XmlEscape(const std::string& text) {
  std::string out;
  for (char c : OneLine(text)) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string XmlComment(const std::string& text) {
  std::string out;
  for (char c : OneLine(text)) {
    if (c == '-' && !out.empty() && out.back() == '-') out += ' ';
    out += c;
  }
  if (!out.empty() && out.back() == '-') out += ' ';
  return out;
}

// ASCII VTU: simplest to check by eye and by the tests; an atlas mesh of a
// few hundred thousand elements stays in the tens of megabytes.
std::string VtuText(const Mesh& mesh, const MeshExportOptions& options) {
  const ElementShapeInfo& shape = ShapeInfo(mesh.shape());
  const int npe = shape.nodes, elements = mesh.num_elements();
  const double scale = Scale(options);
  const std::vector<std::string> names = RegionNames(mesh);
  std::string x = "<?xml version=\"1.0\"?>\n";
  if (!options.title.empty()) x += "<!-- " + XmlComment(options.title) + " -->\n";
  x += Format("<!-- PBA mesh export: coordinates in %s; cell data 'region' is the index of ",
              Unit(options)) +
       "the region named below -->\n";
  for (size_t r = 0; r < names.size(); ++r) {
    x += "<!-- region " + std::to_string(r) + ": " + XmlComment(names[r]) + " -->\n";
  }
  x += "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
       "header_type=\"UInt64\">\n  <UnstructuredGrid>\n";
  x += "    <Piece NumberOfPoints=\"" + std::to_string(mesh.num_nodes()) + "\" NumberOfCells=\"" +
       std::to_string(elements) + "\">\n";
  x += "      <Points>\n        <DataArray type=\"Float64\" Name=\"Points\" "
       "NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    x += "          " + RoundTripNumber(scale * mesh.nodes(i, 0)) + " " +
         RoundTripNumber(scale * mesh.nodes(i, 1)) + " " +
         RoundTripNumber(scale * mesh.nodes(i, 2)) + "\n";
  }
  x += "        </DataArray>\n      </Points>\n      <Cells>\n";
  // The mesh's own orders are VTK's (mesh_export.h), so nodes go out as
  // they are.
  x += "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (int e = 0; e < elements; ++e) {
    x += "         ";
    for (int node : mesh.ElementNodes(e)) x += " " + std::to_string(node);
    x += "\n";
  }
  x += "        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" "
       "format=\"ascii\">\n";
  for (int e = 0; e < elements; ++e) {
    x += std::to_string(static_cast<int64_t>(e + 1) * npe) + (e % 16 == 15 ? "\n" : " ");
  }
  x += "\n        </DataArray>\n        <DataArray type=\"UInt8\" Name=\"types\" "
       "format=\"ascii\">\n";
  const std::string type = std::to_string(shape.vtk_cell_type);
  for (int e = 0; e < elements; ++e) x += type + (e % 32 == 31 ? "\n" : " ");
  x += "\n        </DataArray>\n      </Cells>\n      <CellData Scalars=\"region\">\n"
       "        <DataArray type=\"Int32\" Name=\"region\" format=\"ascii\">\n";
  for (int e = 0; e < elements; ++e) {
    x += std::to_string(ElementRegion(mesh, e)) + (e % 32 == 31 ? "\n" : " ");
  }
  x += "\n        </DataArray>\n      </CellData>\n    </Piece>\n  </UnstructuredGrid>\n"
       "</VTKFile>\n";
  return x;
}

namespace {

Status ValidateMesh(const Mesh& mesh) {
  if (mesh.num_nodes() == 0) return Status::InvalidArgument("mesh.nodes", "no nodes");
  const ElementShape shape = mesh.shape();
  const char* elements_field = shape == ElementShape::kHex8 ? "mesh.hexes" : "mesh.tets";
  if (mesh.num_elements() == 0) return Status::InvalidArgument(elements_field, "no elements");
  if (shape == ElementShape::kHex8 && !mesh.tets.empty()) {
    return Status::InvalidArgument("mesh.tets", "both tets and hexes set (one kind per mesh)");
  }
  // Checked on the arrays themselves: a brick mesh with stray mid-edge rows
  // is refused too.
  if (!mesh.midside.empty() && mesh.midside.size() != mesh.tets.size()) {
    return Status::InvalidArgument(
        "mesh.midside", Format("%zu rows for %zu tets", mesh.midside.size(), mesh.tets.size()));
  }
  for (int e = 0; e < mesh.num_elements(); ++e) {
    for (int node : mesh.ElementNodes(e)) {
      if (node < 0 || node >= mesh.num_nodes()) {
        return Status::InvalidArgument(
            shape == ElementShape::kTet10 ? "mesh.tets / mesh.midside" : elements_field,
            Format("element %d has node %d, outside 0..%d", e, node, mesh.num_nodes() - 1));
      }
    }
  }
  if (mesh.element_region.empty()) {
    if (!mesh.region_names.empty()) {
      return Status::InvalidArgument("mesh.region_names",
                                     "region names given but element_region is empty");
    }
    return Status::Ok();
  }
  if (mesh.element_region.size() != static_cast<size_t>(mesh.num_elements())) {
    return Status::InvalidArgument(
        "mesh.element_region",
        Format("%zu entries for %d elements", mesh.element_region.size(), mesh.num_elements()));
  }
  const int regions = static_cast<int>(mesh.region_names.size());
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const int r = mesh.element_region[e];
    if (r < 0 || r >= regions) {
      return Status::InvalidArgument(
          "mesh.element_region",
          Format("element %d has region %d, outside 0..%d (region_names)", e, r, regions - 1));
    }
  }
  return Status::Ok();
}

}  // namespace
}  // namespace mesh_export

Status MeshFormatFromPath(const std::filesystem::path& file, MeshFormat* format) {
  std::string extension = file.extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (extension == ".vtu") {
    *format = MeshFormat::kVtu;
  } else if (extension == ".xdmf") {
    *format = MeshFormat::kXdmf;
  } else if (extension == ".msh") {
    *format = MeshFormat::kGmsh;
  } else if (extension == ".inp") {
    *format = MeshFormat::kAbaqus;
  } else {
    return Status::InvalidArgument(
        "file", "unknown mesh file extension '" + file.extension().string() + "' of " +
                    file.filename().string() + " (expected .vtu, .xdmf, .msh or .inp)");
  }
  return Status::Ok();
}

Status ExportMesh(const Mesh& mesh, const std::filesystem::path& file,
                  const MeshExportOptions& options) {
  MeshFormat format;
  PBA_RETURN_IF_ERROR(MeshFormatFromPath(file, &format));
  PBA_RETURN_IF_ERROR(mesh_export::ValidateMesh(mesh));
  switch (format) {
    case MeshFormat::kVtu:
      return AtomicWriteText(file, mesh_export::VtuText(mesh, options));
    case MeshFormat::kXdmf:
      return mesh_export::WriteXdmf(mesh, file, options);
    case MeshFormat::kGmsh:
      return AtomicWriteText(file, mesh_export::GmshText(mesh, options));
    case MeshFormat::kAbaqus:
      return AtomicWriteText(file, mesh_export::AbaqusText(mesh, options));
  }
  return Status::Internal("unhandled mesh format");
}

}  // namespace pba
