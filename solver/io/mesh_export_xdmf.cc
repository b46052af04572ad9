// XDMF 3 + HDF5 mesh export: heavy data in <stem>.h5, the light XML in the
// .xdmf that ParaView opens (the syntax of result_writer.cc's result.xdmf).
#include <string>
#include <system_error>
#include <vector>

#include "core/atomic_write.h"
#include "io/h5_writer.h"
#include "io/mesh_export_formats.h"

namespace pba::mesh_export {
namespace {

// The description of /mesh/topology's columns.
const char* TopologyDescription(ElementShape shape) {
  switch (shape) {
    case ElementShape::kTet4:
      return "node indices, 0-based";
    case ElementShape::kTet10:
      return "node indices, 0-based: corners 0-3, then the mid-edge nodes of edges "
             "(0,1) (1,2) (2,0) (0,3) (1,3) (2,3)";
    case ElementShape::kHex8:
      return "node indices, 0-based: one face 0-3, then the opposite face, node "
             "4 + i across from node i (VTK_HEXAHEDRON, Abaqus C3D8)";
  }
  return "";
}

std::string Item(const std::string& dims, const std::string& h5_name, const std::string& path,
                 const char* number_type) {
  return "<DataItem Dimensions=\"" + dims + "\" NumberType=\"" + number_type +
         "\" Precision=\"8\" Format=\"HDF\">" + XmlEscape(h5_name) + ":" + path + "</DataItem>";
}

Status WriteH5(const Mesh& mesh, const std::string& path, const MeshExportOptions& options) {
  const int npe = ShapeInfo(mesh.shape()).nodes, elements = mesh.num_elements();
  const double scale = Scale(options);
  std::vector<double> nodes(static_cast<size_t>(mesh.num_nodes()) * 3);
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    for (int k = 0; k < 3; ++k) nodes[3 * i + k] = scale * mesh.nodes(i, k);
  }
  std::vector<int64_t> topology, region(elements);
  topology.reserve(static_cast<size_t>(elements) * npe);
  for (int e = 0; e < elements; ++e) {
    for (int node : mesh.ElementNodes(e)) topology.push_back(node);
    region[e] = ElementRegion(mesh, e);
  }
  H5Writer w(path);
  if (!w.ok()) return Status::Io("cannot create " + path);
  const std::vector<std::string> names = RegionNames(mesh);
  std::string joined;
  for (size_t r = 0; r < names.size(); ++r) joined += (r ? "\n" : "") + OneLine(names[r]);
  bool ok = WriteStringAttribute(w.file(), "title", OneLine(options.title)) &&
            WriteStringAttribute(w.file(), "region_names", joined);
  w.Group("/mesh");
  w.Dataset("/mesh/nodes", nodes, 3, Unit(options), "x y z");
  w.Dataset("/mesh/topology", topology, npe, "1", TopologyDescription(mesh.shape()));
  w.Dataset("/mesh/region", region, 0, "1",
            "region index per element; names in the file attribute region_names, one a line");
  ok = ok && w.ok();
  return ok ? Status::Ok() : Status::Io("cannot write " + path);
}

std::string XdmfText(const Mesh& mesh, const std::string& h5_name,
                     const MeshExportOptions& options) {
  const ElementShapeInfo& shape = ShapeInfo(mesh.shape());
  const int npe = shape.nodes;
  const std::string ne = std::to_string(mesh.num_elements());
  const std::string nn = std::to_string(mesh.num_nodes());
  std::string x = "<?xml version=\"1.0\" ?>\n";
  if (!options.title.empty()) x += "<!-- " + XmlComment(options.title) + " -->\n";
  x += std::string("<!-- PBA mesh export: coordinates in ") + Unit(options) +
       "; cell attribute 'region' indexes the names of the regions Information element. Open in "
       "ParaView. "
       "-->\n<Xdmf Version=\"3.0\">\n  <Domain>\n    <Grid Name=\"mesh\" GridType=\"Uniform\">\n";
  // The region names in one Information element whose text is meshio's
  // field-data map (name -> index, dimension 3): meshio reads no other
  // form, and ParaView's readers take it as well; title and unit are in the
  // comments above.
  const std::vector<std::string> names = RegionNames(mesh);
  x += "      <Information Name=\"regions\" Value=\"" + std::to_string(names.size()) +
       "\"><![CDATA[<main>";
  for (size_t r = 0; r < names.size(); ++r) {
    x += "<map key=\"" + XmlEscape(names[r]) + "\" dim=\"3\">" + std::to_string(r) + "</map>";
  }
  x += "</main>]]></Information>\n";
  // NodesPerElement only for the quadratic cell, as in result.xdmf.
  // Tetrahedron_10 lists its nodes in VTK_QUADRATIC_TETRA order, which
  // ParaView's XDMF readers pass to VTK unpermuted, and that is the mesh's
  // (C3D10) order.
  x += std::string("      <Topology TopologyType=\"") + shape.xdmf_topology +
       "\" NumberOfElements=\"" + ne +
       (shape.shape == ElementShape::kTet10 ? "\" NodesPerElement=\"10" : "") + "\">\n        " +
       Item(ne + " " + std::to_string(npe), h5_name, "/mesh/topology", "Int") +
       "\n      </Topology>\n      <Geometry GeometryType=\"XYZ\">\n        " +
       Item(nn + " 3", h5_name, "/mesh/nodes", "Float") +
       "\n      </Geometry>\n      <Attribute Name=\"region\" AttributeType=\"Scalar\" "
       "Center=\"Cell\">\n        " +
       Item(ne, h5_name, "/mesh/region", "Int") +
       "\n      </Attribute>\n    </Grid>\n  </Domain>\n</Xdmf>\n";
  return x;
}

}  // namespace

Status WriteXdmf(const Mesh& mesh, const std::filesystem::path& xdmf,
                 const MeshExportOptions& options) {
  std::filesystem::path h5 = xdmf;
  h5.replace_extension(".h5");
  // HDF5 opens the temporary file by name; the descriptor stays unused
  // until AtomicWrite syncs it.
  PBA_RETURN_IF_ERROR(AtomicWrite(h5, ".h5", [&](int, const std::string& temporary) {
    return WriteH5(mesh, temporary, options);
  }));
  const Status status = AtomicWriteText(xdmf, XdmfText(mesh, h5.filename().string(), options));
  if (!status.ok()) {
    std::error_code ec;
    std::filesystem::remove(h5, ec);  // no .h5 without the .xdmf that describes it
  }
  return status;
}

}  // namespace pba::mesh_export
