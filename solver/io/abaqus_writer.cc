// Abaqus/CalculiX input deck of a scene's model, so the same problem can be
// run in a peer code (CalculiX: `ccx -i model`). SI units: m, N, Pa.
#include <cstdio>
#include <fstream>
#include <string>

#include "pba/solve.h"
#include "scene/model_builder.h"

namespace pba {
namespace {

std::string Upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

// Abaqus reads at most 16 entries per data line.
void WriteIdList(std::ofstream& out, const std::vector<int>& nodes) {
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    out << nodes[i] + 1 << ((i % 16 == 15 || i + 1 == nodes.size()) ? "\n" : ", ");
  }
}

}  // namespace

Status ExportAbaqusInput(const SceneSpec& scene, const std::filesystem::path& file) {
  PBA_RETURN_IF_ERROR(ValidateScene(scene));
  const Model model = BuildModel(scene);
  const Mesh& mesh = model.mesh;
  std::ofstream out(file, std::ios::trunc);
  if (!out) return Status::Io("cannot write " + file.string());
  char line[160];
  out << "** PBA " << SolverVersion() << " model of scene '" << scene.name << "'\n"
      << "** Units: m, N, Pa. Node and element numbers are PBA's indices + 1.\n"
      << "*HEADING\n"
      << (scene.name.empty() ? "pba model" : scene.name) << "\n*NODE, NSET=NALL\n";
  for (int i = 0; i < mesh.num_nodes(); ++i) {
    std::snprintf(line, sizeof line, "%d, %.17g, %.17g, %.17g\n", i + 1, mesh.nodes(i, 0),
                  mesh.nodes(i, 1), mesh.nodes(i, 2));
    out << line;
  }
  out << "*ELEMENT, TYPE=C3D4, ELSET=EALL\n";
  for (int e = 0; e < mesh.num_elements(); ++e) {
    const auto& t = mesh.tets[e];
    out << e + 1 << ", " << t[0] + 1 << ", " << t[1] + 1 << ", " << t[2] + 1 << ", " << t[3] + 1
        << "\n";
  }
  for (const auto& [name, set] : mesh.face_sets) {
    out << "*NSET, NSET=" << Upper(name) << "\n";
    WriteIdList(out, set.nodes);
  }
  const LinearElasticParams& p = scene.material.linear_elastic;
  std::snprintf(line, sizeof line, "%.17g, %.17g\n", p.youngs_modulus_pa, p.poissons_ratio);
  out << "*MATERIAL, NAME=TISSUE\n*ELASTIC\n"
      << line << "*SOLID SECTION, ELSET=EALL, MATERIAL=TISSUE\n*STEP\n*STATIC\n*BOUNDARY\n";
  // The resolved constraints, one per unknown: the deck needs no rule for
  // conditions that overlap on shared edges.
  for (int dof = 0; dof < model.dofs.num_dofs(); ++dof) {
    if (!model.dofs.prescribed(dof)) continue;
    std::snprintf(line, sizeof line, "%d, %d, %d, %.17g\n", dof / 3 + 1, dof % 3 + 1, dof % 3 + 1,
                  model.dofs.prescribed_value(dof));
    out << line;
  }
  for (const auto& name : ReactionSetNames(scene)) {
    out << "*NODE PRINT, NSET=" << Upper(name) << ", TOTALS=ONLY\nRF\n";
  }
  out << "*NODE PRINT, NSET=NALL\nU\n*NODE FILE\nU\n*EL FILE\nS\n*END STEP\n";
  out.close();
  if (!out) return Status::Io("cannot write " + file.string());
  return Status::Ok();
}

}  // namespace pba
