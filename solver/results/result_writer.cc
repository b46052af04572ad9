// result.h5 (HDF5 C API) and result.xdmf (XDMF 3, the ParaView view of it).
#include "results/result_writer.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "core/atomic_write.h"
#include "core/format.h"
#include "io/h5_writer.h"
#include "io/line_plot.h"
#include "mesh/element_shape.h"
#include "pba/solve.h"
#include "results/surface_gltf.h"

namespace pba {
namespace {

std::string Item(const std::string& dims, const std::string& path,
                 const char* number_type = "Float", int precision = 8) {
  return "<DataItem Dimensions=\"" + dims + "\" NumberType=\"" + number_type + "\" Precision=\"" +
         std::to_string(precision) + "\" Format=\"HDF\">result.h5:" + path + "</DataItem>";
}

// The shape of a connectivity with `nodes_per_element` columns (4, 10 or
// 8, checked by WriteResultFiles); all share VTK's and Abaqus' node order.
const ElementShapeInfo& ShapeOf(int nodes_per_element) {
  return *ShapeWithNodes(nodes_per_element);
}

// The per-component views of an elements x 6 dataset (ComponentView) and
// of one step's displacement rows (StepView), so that every XDMF DataItem
// names a whole dataset: ParaView's default XDMF 3 reader skips a HyperSlab
// ("unrecognized array type") and meshio cannot read one.
const char* const kComponents[6] = {"xx", "yy", "zz", "yz", "xz", "xy"};

std::string ComponentView(const std::string& field, int column) {
  return "/xdmf/" + field + "_" + kComponents[column];
}

std::string StepView(size_t step) { return "/xdmf/displacement_" + std::to_string(step + 1); }

// One column of an elements x 6 dataset as a scalar cell attribute.
std::string ComponentAttribute(const std::string& field, int column, size_t rows) {
  return "      <Attribute Name=\"" + field + "_" + kComponents[column] +
         "\" AttributeType=\"Scalar\" Center=\"Cell\">\n        " +
         Item(std::to_string(rows), ComponentView(field, column)) + "\n      </Attribute>\n";
}

// The elements x 6 fields of /fields written for `outputs` (the finite-strain
// ones from nonlinear analyses only), each with its six component views.
std::vector<const char*> TensorFields(const OutputOptions& outputs, const Solution& s) {
  const size_t values = 6 * (s.tets.size() / s.nodes_per_element);
  const bool finite_strain = !s.jacobian.empty();
  std::vector<const char*> fields;
  if (outputs.stress && s.stress_pa.size() == values) fields.push_back("stress");
  if (outputs.strain && s.strain.size() == values) fields.push_back("strain");
  if (finite_strain && outputs.pk2_stress && s.pk2_stress_pa.size() == values) {
    fields.push_back("pk2_stress");
  }
  if (finite_strain && outputs.almansi_strain && s.almansi_strain.size() == values) {
    fields.push_back("almansi_strain");
  }
  return fields;
}

// The final fields as XDMF attributes of one grid.
std::string FieldAttributes(const OutputOptions& outputs, const Solution& s) {
  const size_t nodes = s.nodes_mm.size() / 3, elements = s.tets.size() / s.nodes_per_element;
  const std::string nn = std::to_string(nodes), ne = std::to_string(elements);
  std::string x;
  if (outputs.displacement) {
    x += "      <Attribute Name=\"displacement\" AttributeType=\"Vector\" Center=\"Node\">\n       "
         " " +
         Item(nn + " 3", "/fields/displacement") + "\n      </Attribute>\n";
  }
  if (outputs.von_mises) {
    x += "      <Attribute Name=\"von_mises\" AttributeType=\"Scalar\" Center=\"Cell\">\n        " +
         Item(ne, "/fields/von_mises") + "\n      </Attribute>\n";
  }
  if (!s.error_indicator.empty()) {
    x += "      <Attribute Name=\"error_indicator\" AttributeType=\"Scalar\" Center=\"Cell\">\n    "
         "    " +
         Item(ne, "/fields/error_indicator") + "\n      </Attribute>\n";
  }
  for (const char* field : TensorFields(outputs, s)) {
    for (int c = 0; c < 6; ++c) x += ComponentAttribute(field, c, elements);
  }
  if (outputs.jacobian && !s.jacobian.empty()) {
    x += "      <Attribute Name=\"jacobian\" AttributeType=\"Scalar\" Center=\"Cell\">\n        " +
         Item(ne, "/fields/jacobian") + "\n      </Attribute>\n";
  }
  return x;
}

// Whether the solution names its elements' regions (one index each).
bool HasRegions(const Solution& s) {
  return !s.region_names.empty() &&
         s.element_region.size() == s.tets.size() / std::max(1, s.nodes_per_element);
}

std::string XdmfText(const std::string& scene_name, const OutputOptions& outputs,
                     const Solution& s) {
  const size_t nodes = s.nodes_mm.size() / 3, elements = s.tets.size() / s.nodes_per_element;
  const std::string nn = std::to_string(nodes), ne = std::to_string(elements);
  const std::string npe = std::to_string(s.nodes_per_element);
  const std::string name = scene_name.empty() ? "result" : scene_name;
  // NodesPerElement only for the quadratic cell, where it restates the type;
  // 4-node files stay as they were.
  const std::string per_element =
      s.nodes_per_element == 10 ? "\" NodesPerElement=\"" + npe : std::string();
  const std::string mesh =
      std::string("      <Topology TopologyType=\"") + ShapeOf(s.nodes_per_element).xdmf_topology +
      "\" NumberOfElements=\"" + ne + per_element + "\">\n        " +
      Item(ne + " " + npe, "/mesh/tets", "Int", 8) +
      "\n      </Topology>\n"
      "      <Geometry GeometryType=\"XYZ\">\n        " +
      Item(nn + " 3", "/mesh/nodes") + "\n      </Geometry>\n" +
      (HasRegions(s) ? "      <Attribute Name=\"region\" AttributeType=\"Scalar\" "
                       "Center=\"Cell\">\n        " +
                           Item(ne, "/mesh/region", "Int", 8) + "\n      </Attribute>\n"
                     : std::string());
  std::string x =
      "<?xml version=\"1.0\" ?>\n<!-- PBA result: lengths in mm, stresses in Pa. Open in ParaView. "
      "-->\n<Xdmf Version=\"3.0\">\n  <Domain>\n";
  const size_t steps = s.step_load_factor.size();
  if (steps == 0) {
    x += "    <Grid Name=\"" + name + "\" GridType=\"Uniform\">\n" + mesh +
         FieldAttributes(outputs, s) + "    </Grid>\n";
  } else {
    // A temporal collection over the load increments (time = load factor):
    // the displacement of every increment, all fields at the last.
    x += "    <Grid Name=\"" + name + "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    for (size_t k = 0; k < steps; ++k) {
      char time[32];
      std::snprintf(time, sizeof time, "%.17g",
                    s.step_time_s.empty() ? s.step_load_factor[k] : s.step_time_s[k]);
      x += "    <Grid Name=\"increment " + std::to_string(k + 1) +
           "\" GridType=\"Uniform\">\n      <Time Value=\"" + time + "\" />\n" + mesh;
      if (k + 1 == steps) {
        x += FieldAttributes(outputs, s);
      } else if (outputs.displacement && s.step_displacement_mm.size() == 3 * steps * nodes) {
        x += "      <Attribute Name=\"displacement\" AttributeType=\"Vector\" Center=\"Node\">\n"
             "        " +
             Item(nn + " 3", StepView(k)) + "\n      </Attribute>\n";
      }
      x += "    </Grid>\n";
    }
    x += "    </Grid>\n";
  }
  return x + "  </Domain>\n</Xdmf>\n";
}

// history.csv (one row per step) and history.png: every force column
// ("[N]") whose values are not all zero, as its magnitude per reaction set
// or contact, against time.
Status WriteHistory(const Solution& solution, const std::filesystem::path& dir) {
  const auto& columns = solution.history_columns;
  std::string csv;
  for (std::size_t c = 0; c < columns.size(); ++c) csv += (c ? "," : "") + CsvQuoted(columns[c]);
  csv += "\n";
  char number[32];
  for (const auto& row : solution.history) {
    for (std::size_t c = 0; c < row.size(); ++c) {
      std::snprintf(number, sizeof number, "%.10g", row[c]);
      csv += (c ? "," : "") + std::string(number);
    }
    csv += "\n";
  }
  PBA_RETURN_IF_ERROR(AtomicWriteText(dir / "history.csv", csv));

  // Force components come in x, y, z triples named "... x [N]".
  LinePlot plot;
  plot.title = solution.summary.scene_name + ": forces through time";
  plot.x_label = "time [s]";
  plot.y_label = "force [N]";
  for (std::size_t c = 0; c + 2 < columns.size(); ++c) {
    const std::string& name = columns[c];
    const std::string suffix = " x [N]";
    if (name.size() <= suffix.size() ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0) {
      continue;
    }
    LineSeries series;
    series.name = name.substr(0, name.size() - suffix.size());
    bool any = false;
    for (const auto& row : solution.history) {
      const double f =
          std::sqrt(row[c] * row[c] + row[c + 1] * row[c + 1] + row[c + 2] * row[c + 2]);
      series.x.push_back(row[0]);
      series.y.push_back(f);
      any = any || f > 0;
    }
    if (!any) continue;
    series.colour = SeriesColour(static_cast<int>(plot.series.size()));
    plot.series.push_back(std::move(series));
  }
  if (plot.series.empty()) return Status::Ok();
  return WriteLinePlot(plot, dir / "history.png");
}

// profile_<name>.csv of each line profile: the header its columns, then one
// row per point; a value that is not finite (a point outside the body) is
// an empty cell.
Status WriteProfiles(const Solution& solution, const std::filesystem::path& dir) {
  char number[32];
  for (const ProfileTable& table : solution.profiles) {
    // The name becomes part of a file name: ValidateScene allows only these.
    const bool plain =
        !table.name.empty() && std::all_of(table.name.begin(), table.name.end(), [](char c) {
          return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
        });
    if (!plain) return Status::Internal("profile name '" + table.name + "' cannot name a file");
    std::string csv;
    for (std::size_t c = 0; c < table.columns.size(); ++c) {
      csv += (c ? "," : "") + CsvQuoted(table.columns[c]);
    }
    csv += "\n";
    for (const auto& row : table.rows) {
      for (std::size_t c = 0; c < row.size(); ++c) {
        if (c) csv += ",";
        if (!std::isfinite(row[c])) continue;
        std::snprintf(number, sizeof number, "%.10g", row[c]);
        csv += number;
      }
      csv += "\n";
    }
    PBA_RETURN_IF_ERROR(AtomicWriteText(dir / ("profile_" + table.name + ".csv"), csv));
  }
  return Status::Ok();
}

// sensors.csv of an EXPLICIT_DYNAMIC run with sensors: the header its
// columns (time_s, then per sensor its raw and filtered quantities), one row
// per sample; 9 significant digits, enough for samples microseconds apart
// over seconds; a value that is not finite is an empty cell.
Status WriteSensors(const Solution& solution, const std::filesystem::path& dir) {
  const auto& columns = solution.sensor_columns;
  std::string csv;
  for (std::size_t c = 0; c < columns.size(); ++c) csv += (c ? "," : "") + CsvQuoted(columns[c]);
  csv += "\n";
  char number[32];
  for (const auto& row : solution.sensor_rows) {
    if (row.size() != columns.size()) {
      return Status::Internal("sensors.csv: a row of " + std::to_string(row.size()) +
                              " values under " + std::to_string(columns.size()) + " columns");
    }
    for (std::size_t c = 0; c < row.size(); ++c) {
      if (c) csv += ",";
      if (!std::isfinite(row[c])) continue;
      std::snprintf(number, sizeof number, "%.9g", row[c]);
      csv += number;
    }
    csv += "\n";
  }
  return AtomicWriteText(dir / "sensors.csv", csv);
}

// surfaces.glb: the regions' surfaces, deformed by the final displacement,
// for a browser (the web view) or any glTF viewer; and with steps through
// time or load, surface_steps.bin: each step's displacement of them.
Status WriteSurfaces(const Solution& solution, int npe, const std::filesystem::path& dir) {
  const std::vector<RegionSurface> surfaces = ExtractRegionSurfaces(
      solution.tets, npe, HasRegions(solution) ? solution.element_region : std::vector<int64_t>(),
      solution.region_names);
  const std::size_t nodes = solution.nodes_mm.size() / 3, steps = solution.step_load_factor.size();
  SurfaceSteps stepped;
  if (steps > 1 && solution.step_displacement_mm.size() == 3 * steps * nodes) {
    stepped.times =
        solution.step_time_s.size() == steps ? solution.step_time_s : solution.step_load_factor;
    PBA_RETURN_IF_ERROR(AtomicWriteText(
        dir / kSurfaceStepsFile,
        SurfaceStepsBin(surfaces, solution.nodes_mm, solution.step_displacement_mm)));
  }
  // The final state's pressure (-trace(sigma) / 3) and largest principal
  // strain, element by element, drawn on the surfaces.
  const std::size_t elements = solution.tets.size() / npe;
  std::vector<double> pressure, principal;
  if (solution.stress_pa.size() == 6 * elements) {
    pressure.resize(elements);
    for (std::size_t e = 0; e < elements; ++e) {
      const double* s = &solution.stress_pa[6 * e];
      pressure[e] = -(s[0] + s[1] + s[2]) / 3;
    }
  }
  if (solution.strain.size() == 6 * elements) {
    principal.resize(elements);
    for (std::size_t e = 0; e < elements; ++e) {
      const double* v = &solution.strain[6 * e];  // xx yy zz yz xz xy, engineering shear
      Eigen::Matrix3d strain;
      strain << v[0], v[5] / 2, v[4] / 2, v[5] / 2, v[1], v[3] / 2, v[4] / 2, v[3] / 2, v[2];
      principal[e] = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(strain, Eigen::EigenvaluesOnly)
                         .eigenvalues()(2);
    }
  }
  const std::vector<int64_t> region =
      HasRegions(solution) ? solution.element_region : std::vector<int64_t>();
  std::vector<VertexScalar> scalars;
  if (!pressure.empty()) {
    scalars.push_back({"_PRESSURE", "pressure", "Pa",
                       VertexMeans(surfaces, solution.tets, npe, region, pressure)});
  }
  if (!principal.empty()) {
    scalars.push_back({"_STRAIN", "largest principal strain", "",
                       VertexMeans(surfaces, solution.tets, npe, region, principal)});
  }
  return AtomicWriteText(
      dir / "surfaces.glb",
      SurfacesGlb(surfaces, solution.nodes_mm, solution.displacement_mm, stepped, scalars));
}

}  // namespace

Status WriteResults(const std::string& scene_name, const OutputOptions& outputs, Solution* solution,
                    const std::filesystem::path& dir) {
  const auto start = std::chrono::steady_clock::now();
  const int npe = solution->nodes_per_element;
  if (ShapeWithNodes(npe) == nullptr || solution->tets.size() % npe != 0) {
    return Status::Internal("solution connectivity: " + std::to_string(solution->tets.size()) +
                            " indices, " + std::to_string(npe) +
                            " nodes per element (4, 10 or 8, dividing the count)");
  }
  const std::filesystem::path h5 = dir / "result.h5";
  {
    H5Writer w(h5);
    if (!w.ok()) return Status::Io("cannot create " + h5.string());
    WriteStringAttribute(w.file(), "pba_version", SolverVersion());
    WriteStringAttribute(w.file(), "scene_name", scene_name);
    w.Group("/mesh");
    w.Group("/fields");
    w.Dataset("/mesh/nodes", solution->nodes_mm, 3, "mm", "x y z");
    w.Dataset("/mesh/tets", solution->tets, npe, "1",
              npe == 10  ? "node indices, 0-based: corners 0-3, then the mid-edge nodes of edges "
                           "(0,1) (1,2) (2,0) (0,3) (1,3) (2,3)"
              : npe == 8 ? "node indices, 0-based: one face 0-3, then the opposite face, node "
                           "4 + i across from node i (VTK_HEXAHEDRON, Abaqus C3D8)"
                         : "node indices, 0-based");
    w.Attribute("/mesh/tets", "element_type", ShapeOf(npe).name);
    if (HasRegions(*solution)) {
      w.Dataset("/mesh/region", solution->element_region, 0, "1",
                "each element's region: an index into the names attribute");
      std::string names;
      for (const std::string& name : solution->region_names) names += name + "\n";
      w.Attribute("/mesh/region", "names", names);
    }
    const std::string voigt = "xx yy zz yz xz xy";
    if (outputs.displacement)
      w.Dataset("/fields/displacement", solution->displacement_mm, 3, "mm", "x y z");
    if (outputs.stress) w.Dataset("/fields/stress", solution->stress_pa, 6, "Pa", voigt);
    if (outputs.strain) {
      w.Dataset("/fields/strain", solution->strain, 6, "1", voigt + " (engineering shear)");
    }
    if (outputs.von_mises) w.Dataset("/fields/von_mises", solution->von_mises_pa, 0, "Pa");
    const bool finite_strain = !solution->jacobian.empty();
    if (finite_strain && outputs.pk2_stress) {
      w.Dataset("/fields/pk2_stress", solution->pk2_stress_pa, 6, "Pa",
                voigt + ", second Piola-Kirchhoff, reference configuration");
    }
    if (finite_strain && outputs.almansi_strain) {
      w.Dataset("/fields/almansi_strain", solution->almansi_strain, 6, "1",
                voigt + " (engineering shear), Euler-Almansi, current configuration");
    }
    if (finite_strain && outputs.jacobian) {
      w.Dataset("/fields/jacobian", solution->jacobian, 0, "1", "J = det F, volume ratio");
    }
    if (!solution->error_indicator.empty()) {
      w.Dataset("/fields/error_indicator", solution->error_indicator, 0, "1");
    }
    if (!solution->step_load_factor.empty() && outputs.displacement) {
      // One record per converged load increment: the path to the answer.
      w.Group("/steps");
      w.Dataset("/steps/load_factor", solution->step_load_factor, 0, "1",
                "fraction of the prescribed loads applied");
      w.Dataset("/steps/displacement", solution->step_displacement_mm, 3, "mm",
                "x y z; rows step-major: step k holds rows k*nodes .. (k+1)*nodes-1");
      if (!solution->step_time_s.empty()) {
        w.Dataset("/steps/time", solution->step_time_s, 0, "s", "time of each step");
      }
    }
    // Views for result.xdmf (ComponentView, StepView).
    const std::vector<const char*> tensors = TensorFields(outputs, *solution);
    const size_t elements = solution->tets.size() / npe, nodes = solution->nodes_mm.size() / 3;
    const size_t steps = solution->step_load_factor.size();
    const bool step_views = steps > 1 && outputs.displacement &&
                            solution->step_displacement_mm.size() == 3 * steps * nodes;
    if (!tensors.empty() || step_views) w.Group("/xdmf");
    for (const std::string field : tensors) {
      const bool stress = field.find("stress") != std::string::npos;
      for (int c = 0; c < 6; ++c) {
        w.View(ComponentView(field, c), "/fields/" + field, elements, 6, 0, elements, c, 1,
               stress ? "Pa" : "1",
               std::string("column ") + kComponents[c] + " of /fields/" + field);
      }
    }
    for (size_t k = 0; step_views && k + 1 < steps; ++k) {
      w.View(StepView(k), "/steps/displacement", steps * nodes, 3, k * nodes, nodes, 0, 3, "mm",
             "x y z; rows of increment " + std::to_string(k + 1) + " of /steps/displacement");
    }
    if (!w.ok()) return Status::Io("cannot write " + h5.string());
  }
  const std::filesystem::path xdmf = dir / "result.xdmf";
  std::ofstream out(xdmf, std::ios::trunc);
  out << XdmfText(scene_name, outputs, *solution);
  out.close();
  if (!out) return Status::Io("cannot write " + xdmf.string());

  if (!solution->history.empty()) PBA_RETURN_IF_ERROR(WriteHistory(*solution, dir));
  PBA_RETURN_IF_ERROR(WriteProfiles(*solution, dir));
  PBA_RETURN_IF_ERROR(WriteSurfaces(*solution, npe, dir));
  if (!solution->sensor_columns.empty()) PBA_RETURN_IF_ERROR(WriteSensors(*solution, dir));

  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  solution->summary.phases.push_back({"write", seconds});
  solution->summary.wall_time_s += seconds;
  return Status::Ok();
}

}  // namespace pba
