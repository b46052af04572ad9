#include "commands/study_commands.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/struct.pb.h>
#include <yaml-cpp/yaml.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>

#include "codec/yaml_codec.h"
#include "commands/batch_shared.h"
#include "commands/command_context.h"
#include "commands/job_commands.h"
#include "core/sha256.h"
#include "exit_codes.h"
#include "files.h"
#include "output.h"
#include "pba/v1/summary.pb.h"
#include "study_math.h"

namespace pba::cli {
namespace fs = std::filesystem;
namespace {

// The element size the solver uses when mesh.element_size_mm is 0 or left
// out (EffectiveElementSize in solver/mesh/primitive_mesher.cc): 8 mm for an
// atlas, else a twentieth of the body's largest dimension [mm].
double DefaultElementSize(const v1::Geometry& g) {
  if (g.has_atlas()) return 8;
  double largest = 0;
  if (g.has_box()) {
    for (double s : g.box().size_mm()) largest = std::max(largest, s);
  } else if (g.has_cylinder()) {
    largest = std::max(2 * g.cylinder().radius_mm(), g.cylinder().height_mm());
  } else if (g.has_spherical_shell()) {
    largest = g.spherical_shell().outer_radius_mm();
  } else if (g.has_ellipsoid()) {
    for (double a : g.ellipsoid().semi_axes_mm()) largest = std::max(largest, 2 * a);
  }
  return largest / 20;
}

std::string Format(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

// An element size as written into the member's scene and shown: four
// significant digits, so that the scene, its request id and the table agree.
double Rounded(double size_mm) { return std::stod(Format("%.4g", size_mm)); }

// Checks that `path` names a number in a Summary (field names from
// summary.proto, [i] after a repeated field), so that a typo is reported
// before anything is submitted.
bool CheckSummaryPath(const std::string& path, std::string* error) {
  std::vector<std::string> parts;
  if (!SplitPath(path, &parts)) {
    *error =
        "--quantity '" + path + "' is not a path (names joined by dots, [i] for list elements)";
    return false;
  }
  using google::protobuf::FieldDescriptor;
  const google::protobuf::Descriptor* message = v1::Summary::descriptor();
  const FieldDescriptor* field = nullptr;
  bool indexed = false;
  std::string walked;
  for (const std::string& part : parts) {
    if (part[0] == '[') {
      if (field == nullptr || !field->is_repeated() || indexed) {
        *error = "--quantity '" + path + "': " + walked + " is not a list";
        return false;
      }
      indexed = true;
      walked += part;
      continue;
    }
    if (field != nullptr) {
      if (field->is_repeated() && !indexed) {
        *error = "--quantity '" + path + "': " + walked + " is a list: give an element, " + walked +
                 "[0]";
        return false;
      }
      if (field->type() != FieldDescriptor::TYPE_MESSAGE) {
        *error = "--quantity '" + path + "': " + walked + " is a number, it has no '" + part + "'";
        return false;
      }
      message = field->message_type();
    }
    field = message->FindFieldByName(part);
    walked += (walked.empty() ? "" : ".") + part;
    indexed = false;
    if (field == nullptr) {
      std::string names;
      for (int i = 0; i < message->field_count(); ++i)
        names += (i ? ", " : "") + message->field(i)->name();
      *error =
          "--quantity '" + path + "': the summary has no " + walked + " (there: " + names + ")";
      return false;
    }
  }
  const bool number = field->cpp_type() == FieldDescriptor::CPPTYPE_DOUBLE ||
                      field->cpp_type() == FieldDescriptor::CPPTYPE_FLOAT ||
                      field->cpp_type() == FieldDescriptor::CPPTYPE_INT32 ||
                      field->cpp_type() == FieldDescriptor::CPPTYPE_INT64;
  if (!number || (field->is_repeated() && !indexed)) {
    *error =
        "--quantity '" + path + "' is not a number of the summary" +
        (field->is_repeated() && !indexed ? " (a list: give an element, " + path + "[0])" : "");
    return false;
  }
  return true;
}

struct Study {
  std::string name;           // the base scene's
  std::vector<double> sizes;  // element sizes [mm], coarsest first
  std::vector<RunMember> members;
  // What each member's scene sets: path, value [mm].
  std::vector<std::vector<std::pair<std::string, double>>> set;
  v1::SnapshotRef snapshot;
};

// Builds one member scene per element size from the base scene; false with
// a message naming the scene file, the member and the field.
bool BuildStudy(const StudyArgs& args, Study* study, std::string* error) {
  for (const std::string& q : args.quantities) {
    if (!CheckSummaryPath(q, error)) return false;
  }
  if (!args.snapshot.empty() && !ParseSnapshotRef(args.snapshot, &study->snapshot)) {
    *error = "--snapshot: expected PROJECT/SNAPSHOT (an id or a tag)";
    return false;
  }
  // The codec's read first: it refuses aliases (core/yaml_guard.h), which
  // the members' clones of `base` below would expand.
  v1::Scene scene;
  codec::ParseError parse;
  if (!codec::ReadYamlFile(args.scene, &scene, &parse)) {
    *error = parse.ToString();
    return false;
  }
  YAML::Node base;
  try {
    base = YAML::LoadFile(args.scene);
  } catch (const YAML::Exception& e) {
    *error = args.scene + ": " + e.what();
    return false;
  }
  if (scene.mesh().adapt().target_error_percent() != 0) {
    *error = args.scene +
             ": mesh.adapt: a convergence study compares uniform element sizes, and each member "
             "would refine its mesh on its own; remove mesh.adapt from the scene for the study "
             "(an adaptive solve's summary lists its cycles)";
    return false;
  }
  study->name = scene.name().empty() ? fs::path(args.scene).stem().string() : scene.name();
  // The scene's own size: what its mesh is scaled from.
  const double own = scene.mesh().element_size_mm() > 0 ? scene.mesh().element_size_mm()
                                                        : DefaultElementSize(scene.geometry());
  if (!(own > 0)) {
    *error = args.scene + ": mesh.element_size_mm: no size to start from (give --sizes)";
    return false;
  }
  if (!args.sizes.empty()) {
    study->sizes = args.sizes;
    for (double h : study->sizes) {
      if (!(h > 0) || !std::isfinite(h)) {
        *error = "--sizes: element sizes are positive numbers of mm, got " + Format("%g", h);
        return false;
      }
    }
  } else {
    if (!(args.ratio > 1.0)) {
      *error = "--ratio: successive element sizes must shrink, so a ratio above 1, got " +
               Format("%g", args.ratio);
      return false;
    }
    for (int i = 0; i < args.meshes; ++i) study->sizes.push_back(own / std::pow(args.ratio, i));
  }
  for (double& h : study->sizes) h = Rounded(h);
  std::sort(study->sizes.rbegin(), study->sizes.rend());
  if (std::adjacent_find(study->sizes.begin(), study->sizes.end()) != study->sizes.end()) {
    *error = "two meshes have the same element size (to four digits): choose sizes further apart";
    return false;
  }
  if (study->sizes.size() < 2) {
    *error = "a convergence study needs at least two meshes (three for the extrapolation)";
    return false;
  }

  const v1::Atlas& atlas = scene.geometry().atlas();
  const std::string on =
      study->snapshot.project().empty()
          ? ""
          : "\nsnapshot " + study->snapshot.project() + "/" + study->snapshot.snapshot();
  for (size_t i = 0; i < study->sizes.size(); ++i) {
    const double h = study->sizes[i];
    RunMember member;
    member.name = "h=" + Format("%g", h) + " mm";
    YAML::Node yaml = YAML::Clone(base);
    std::vector<std::pair<std::string, double>> set = {{"mesh.element_size_mm", h}};
    // An atlas's finer sizes scale with the mesh: the region of interest's
    // elements (at most the size outside, as the solver takes them) and the
    // facets of surfaces and interfaces when the scene sets them.
    if (scene.geometry().has_atlas()) {
      if (atlas.roi_radius_mm() > 0 && atlas.roi_element_size_mm() > 0)
        set.push_back({"geometry.atlas.roi_element_size_mm",
                       Rounded(std::min(atlas.roi_element_size_mm(), own) * h / own)});
      if (atlas.facet_size_mm() > 0)
        set.push_back({"geometry.atlas.facet_size_mm", Rounded(atlas.facet_size_mm() * h / own)});
    }
    for (const auto& [path, value] : set) {
      // Written as the short number shown (a plain scalar the codec reads as a number).
      std::string why;
      if (!SetPath(yaml, path, YAML::Node(Format("%g", value)), &why)) {
        *error = args.scene + ": member '" + member.name + "': " + why;
        return false;
      }
    }
    yaml["name"] = study->name + " [" + member.name + "]";
    YAML::Emitter out;
    out << yaml;
    if (!codec::ParseYaml(out.c_str(), &member.scene, &parse)) {
      parse.line = 0;  // a line of the generated text would mislead
      *error = args.scene + ": member '" + member.name + "': " + parse.ToString();
      return false;
    }
    // The same mesh of the same scene gets the same request id, so a rerun
    // (or a submit repeated after an interruption) finds the job made.
    member.request_id = Sha256Hex("convergence\n" + std::string(out.c_str()) + on).substr(0, 32);
    member.key = member.request_id;
    study->members.push_back(std::move(member));
    study->set.push_back(std::move(set));
  }
  return true;
}

// A number of the summary at `path`; false (with *error naming the path
// and the mesh) when it is absent or not a number.
bool Number(const YAML::Node& summary, const std::string& path, const RunMember& m, double* value,
            std::string* error) {
  const std::string text = GetPath(summary, path);
  char* end = nullptr;
  *value = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(*value)) {
    *error = text.empty()
                 ? path + " is not in the summary of mesh " + m.name + " (job " + m.job_id + ")"
                 : path + " of mesh " + m.name + " (job " + m.job_id + ") is not a number: '" +
                       text + "'";
    return false;
  }
  return true;
}

std::string Optional(const char* format, const std::optional<double>& value, double scale = 1) {
  return value ? Format(format, *value * scale) : "-";
}

void SetNumber(google::protobuf::Struct* s, const std::string& key,
               const std::optional<double>& value, double scale = 1) {
  if (value) (*s->mutable_fields())[key].set_number_value(*value * scale);
}

void PrintDryRun(const Study& study) {
  for (size_t i = 0; i < study.members.size(); ++i) {
    std::string sizes;
    for (const auto& [path, value] : study.set[i])
      sizes += (sizes.empty() ? "" : ", ") + path + " = " + Format("%g", value);
    std::printf("mesh %zu: %s\n", i + 1, sizes.c_str());
  }
  std::printf("%zu meshes; nothing submitted (--dry-run)\n", study.members.size());
}

// --out, or SCENE's stem + ".convergence.csv" beside it.
fs::path TablePath(const StudyArgs& args) {
  return args.out.empty() ? fs::path(args.scene).parent_path() /
                                (fs::path(args.scene).stem().string() + ".convergence.csv")
                          : fs::path(args.out);
}

// Submits the meshes an earlier run (the state file beside `out`) has not
// done and follows every mesh's job until it ends. kExitOk, or the exit code
// of a request that failed.
int RunMeshes(Connection& connection, const StudyArgs& args, const fs::path& out, Study* study) {
  const bool json = connection.options().json;
  RunOptions options;
  options.state = out.string() + ".pba-study";
  options.name_in_state = true;
  options.snapshot = study->snapshot;
  options.parallel = args.parallel;
  options.retry_failed = args.retry_failed;
  options.ranks = args.ranks;
  options.poll_s = args.poll_s;
  options.quiet = json;
  const std::vector<size_t> to_submit = ResumeMembers(connection, options, &study->members);
  if (!json) {
    std::string sizes;
    for (double h : study->sizes) sizes += (sizes.empty() ? "" : ", ") + Format("%g", h);
    std::printf(
        "Convergence study of %s: %zu meshes (element size %s mm), %zu from an earlier run, %zu "
        "to submit, %d at a time\n",
        study->name.c_str(), study->members.size(), sizes.c_str(),
        study->members.size() - to_submit.size(), to_submit.size(), args.parallel);
    std::fflush(stdout);
  }
  return SubmitAndPoll(connection, options, to_submit, &study->members);
}

// Every mesh is needed: names each that did not succeed; true when all did.
bool EveryMeshSucceeded(const Study& study) {
  int failed = 0;
  for (const RunMember& m : study.members) {
    if (m.job.state() == v1::Job::SUCCEEDED) continue;
    ++failed;
    std::fprintf(stderr, "pba: mesh %s (job %s) ended %s%s\n", m.name.c_str(), m.job_id.c_str(),
                 StateName(m.job.state()).c_str(),
                 m.job.error().empty() ? "" : (": " + m.job.error()).c_str());
  }
  if (failed > 0) {
    std::fprintf(stderr, "pba: no table without every mesh; rerun with --retry-failed\n");
    return false;
  }
  return true;
}

// What each mesh's job gave, coarsest mesh first.
struct MeshResults {
  std::vector<double> elements, nodes, wall;
  std::vector<std::vector<double>> values;  // [quantity][mesh]
};

// Reads every mesh's elements, nodes, wall time and quantities from its
// summary. kExitOk, or kExitInvalid (printed) when a number is missing or a
// finer mesh has no more elements than the coarser one.
int ReadMeshResults(const Study& study, const StudyArgs& args, MeshResults* results) {
  const size_t n = study.members.size(), nq = args.quantities.size();
  results->elements.assign(n, 0);
  results->nodes.assign(n, 0);
  results->wall.assign(n, 0);
  results->values.assign(nq, std::vector<double>(n));
  std::vector<double>& elements = results->elements;
  std::string error;
  for (size_t i = 0; i < n; ++i) {
    const RunMember& m = study.members[i];
    const YAML::Node summary = SummaryTree(m.job.summary(), true);
    bool ok = Number(summary, "modelled.elements", m, &elements[i], &error) &&
              Number(summary, "modelled.nodes", m, &results->nodes[i], &error) &&
              Number(summary, "performance.wall_time_s", m, &results->wall[i], &error);
    for (size_t q = 0; ok && q < nq; ++q)
      ok = Number(summary, args.quantities[q], m, &results->values[q][i], &error);
    if (!ok) {
      std::fprintf(stderr, "pba: %s\n", error.c_str());
      return kExitInvalid;
    }
    if (i > 0 && !(elements[i] > elements[i - 1])) {
      std::fprintf(stderr,
                   "pba: meshes %s and %s have %.0f and %.0f elements: a smaller size must give "
                   "more elements; choose sizes further apart\n",
                   study.members[i - 1].name.c_str(), m.name.c_str(), elements[i - 1], elements[i]);
      return kExitInvalid;
    }
  }
  return kExitOk;
}

// What the study prints, writes and (with --json) prints instead.
struct StudyReport {
  std::vector<std::vector<std::string>> rows, csv_rows;  // per mesh
  std::vector<std::vector<std::string>> analysis;        // per quantity
  std::vector<std::string> notes;
  google::protobuf::Struct document;
};

// One row per mesh: its size, elements, nodes, wall time and each quantity
// with its change from the previous mesh; for the terminal, the CSV and the
// document's "meshes".
void TabulateMeshes(const Study& study, const StudyArgs& args, const MeshResults& results,
                    StudyReport* report) {
  const size_t n = study.members.size(), nq = args.quantities.size();
  const std::string below = "< " + Format("%g", args.tolerance_pct) + " %";
  std::vector<std::string> header = {"mesh", "element size [mm]", "elements", "nodes",
                                     "wall time [s]"};
  std::vector<std::string> csv_header = {"mesh",  "element_size_mm", "elements",
                                         "nodes", "wall_time_s",     "job"};
  for (const std::string& q : args.quantities) {
    header.insert(header.end(), {q, "change [%]", below});
    csv_header.insert(csv_header.end(), {q, q + ":change_pct", q + ":below_tolerance"});
  }
  report->rows = {header};
  report->csv_rows = {csv_header};
  auto& fields = *report->document.mutable_fields();
  fields["scene"].set_string_value(study.name);
  fields["tolerance_pct"].set_number_value(args.tolerance_pct);
  auto* meshes = fields["meshes"].mutable_list_value();
  for (size_t i = 0; i < n; ++i) {
    const RunMember& m = study.members[i];
    const double elements = results.elements[i], nodes = results.nodes[i], wall = results.wall[i];
    std::vector<std::string> row = {std::to_string(i + 1), Format("%g", study.sizes[i]),
                                    Format("%.0f", elements), Format("%.0f", nodes),
                                    Format("%.2f", wall)};
    std::vector<std::string> csv = {std::to_string(i + 1),    Format("%g", study.sizes[i]),
                                    Format("%.0f", elements), Format("%.0f", nodes),
                                    Format("%.6g", wall),     m.job_id};
    auto& mesh = *meshes->add_values()->mutable_struct_value();
    auto& mf = *mesh.mutable_fields();
    mf["mesh"].set_number_value(static_cast<double>(i + 1));
    mf["element_size_mm"].set_number_value(study.sizes[i]);
    mf["elements"].set_number_value(elements);
    mf["nodes"].set_number_value(nodes);
    mf["wall_time_s"].set_number_value(wall);
    mf["job"].set_string_value(m.job_id);
    auto& qf = *mf["quantities"].mutable_struct_value();
    for (size_t q = 0; q < nq; ++q) {
      const std::vector<double>& values = results.values[q];
      std::optional<double> change;
      if (i > 0) change = study::RelativeChange(values[i - 1], values[i]);
      const std::string ok =
          !change ? "-" : (std::abs(*change) * 100 < args.tolerance_pct ? "yes" : "no");
      row.insert(row.end(), {Format("%.6g", values[i]), Optional("%+.2f", change, 100), ok});
      csv.insert(csv.end(), {Format("%.10g", values[i]),
                             change ? Format("%.6g", *change * 100) : "", ok == "-" ? "" : ok});
      auto& entry = *(*qf.mutable_fields())[args.quantities[q]].mutable_struct_value();
      (*entry.mutable_fields())["value"].set_number_value(values[i]);
      SetNumber(&entry, "change_pct", change, 100);
      if (change) (*entry.mutable_fields())["below_tolerance"].set_bool_value(ok == "yes");
    }
    report->rows.push_back(row);
    report->csv_rows.push_back(csv);
  }
}

// A mesh's representative size from its element count: elements^(-1/3)
// (Celik et al. 2008, eq. 1 in 3-D), which holds the refinement the meshes
// really have, not only the one asked for.
double RepresentativeSize(double elements) { return std::cbrt(1.0 / elements); }

// What a quantity's behaviour on the three finest meshes means, when it is
// worth a note.
void NoteBehaviour(const std::string& name, const study::ThreeGrid& g,
                   std::vector<std::string>* notes) {
  switch (g.behaviour) {
    case study::Behaviour::kOscillatory:
      notes->push_back(name +
                       ": oscillates about its limit; no order, no extrapolate. Half "
                       "its swing over the three meshes: " +
                       Optional("%.3g", g.oscillation_half_range, 100) +
                       " % of the finest result.");
      break;
    case study::Behaviour::kDiverging:
      notes->push_back(name +
                       ": the change grows on refinement (as at a stress singularity: a "
                       "corner, or the edge of a support or a load); no order, no extrapolate.");
      break;
    case study::Behaviour::kIndeterminate:
      notes->push_back(name + ": two successive meshes give the same value; no order.");
      break;
    case study::Behaviour::kUnchanged:
      notes->push_back(name + ": the same on the three finest meshes (a prescribed value?).");
      break;
    case study::Behaviour::kMonotone:
      if (g.asymptotic_ratio && std::abs(*g.asymptotic_ratio - 1) > 0.1)
        notes->push_back(name + ": GCI ratio " + Format("%.3f", *g.asymptotic_ratio) +
                         " is not near 1: the meshes may not be in the asymptotic range.");
      break;
  }
}

// With more than three meshes: the order of every three successive ones,
// coarsest first, to show whether it settles; into the quantity's analysis
// entry `a` and, when any has an order, a note.
void NoteSuccessiveOrders(const std::string& name, const MeshResults& results,
                          const std::vector<double>& values, google::protobuf::Struct* a,
                          std::vector<std::string>* notes) {
  const size_t n = values.size();
  const auto size = [&](size_t i) { return RepresentativeSize(results.elements[i]); };
  std::string orders, error;
  bool any_order = false;
  auto* list = (*a->mutable_fields())["orders_of_successive_triples"].mutable_list_value();
  for (size_t j = 0; j + 2 < n; ++j) {
    study::ThreeGrid t;
    if (!study::AnalyseThreeGrids(size(j + 2), values[j + 2], size(j + 1), values[j + 1], size(j),
                                  values[j], &t, &error))
      continue;
    const std::string text = t.order ? Format("%.2f", *t.order) : study::BehaviourName(t.behaviour);
    orders += (orders.empty() ? "" : ", ") + text;
    any_order = any_order || t.order;
    if (t.order) {
      list->add_values()->set_number_value(*t.order);
    } else {
      list->add_values()->set_string_value(text);
    }
  }
  if (any_order)
    notes->push_back(name + ": order p of each three successive meshes, coarsest first: " + orders +
                     ".");
}

// Per quantity, the three finest meshes (Celik's 1, the finest, to 3):
// observed order, extrapolate and grid convergence index, into the report's
// analysis table, notes and the document's "analysis". kExitOk, or
// kExitInvalid (printed) when a quantity cannot be analysed.
int AnalyseFinestMeshes(const StudyArgs& args, const MeshResults& results, StudyReport* report) {
  const size_t n = results.elements.size(), nq = args.quantities.size();
  report->analysis = {{"quantity", "convergence", "r21", "r32", "order p", "extrapolate",
                       "e_ext [%]", "GCI fine [%]", "GCI coarse [%]", "GCI ratio"}};
  auto* list = (*report->document.mutable_fields())["analysis"].mutable_list_value();
  if (n < 3) {
    report->notes.push_back("Two meshes: no order and no extrapolate (they need three).");
    return kExitOk;
  }
  const size_t i1 = n - 1, i2 = n - 2, i3 = n - 3;
  const auto size = [&](size_t i) { return RepresentativeSize(results.elements[i]); };
  for (size_t q = 0; q < nq; ++q) {
    const std::vector<double>& values = results.values[q];
    const std::string& name = args.quantities[q];
    study::ThreeGrid g;
    std::string error;
    if (!study::AnalyseThreeGrids(size(i1), values[i1], size(i2), values[i2], size(i3), values[i3],
                                  &g, &error)) {
      std::fprintf(stderr, "pba: %s: %s\n", name.c_str(), error.c_str());
      return kExitInvalid;
    }
    const std::string behaviour = study::BehaviourName(g.behaviour);
    report->analysis.push_back(
        {name, behaviour, Format("%.3f", g.r21), Format("%.3f", g.r32), Optional("%.2f", g.order),
         Optional("%.6g", g.extrapolated), Optional("%.3f", g.extrapolated_error, 100),
         Optional("%.3f", g.gci_fine, 100), Optional("%.3f", g.gci_coarse, 100),
         Optional("%.3f", g.asymptotic_ratio)});
    auto& a = *list->add_values()->mutable_struct_value();
    (*a.mutable_fields())["quantity"].set_string_value(name);
    (*a.mutable_fields())["convergence"].set_string_value(behaviour);
    (*a.mutable_fields())["r21"].set_number_value(g.r21);
    (*a.mutable_fields())["r32"].set_number_value(g.r32);
    SetNumber(&a, "order", g.order);
    SetNumber(&a, "extrapolated", g.extrapolated);
    SetNumber(&a, "extrapolated_error_pct", g.extrapolated_error, 100);
    SetNumber(&a, "gci_fine_pct", g.gci_fine, 100);
    SetNumber(&a, "gci_coarse_pct", g.gci_coarse, 100);
    SetNumber(&a, "asymptotic_ratio", g.asymptotic_ratio);
    SetNumber(&a, "oscillation_half_range_pct", g.oscillation_half_range, 100);
    NoteBehaviour(name, g, &report->notes);
    if (n > 3) NoteSuccessiveOrders(name, results, values, &a, &report->notes);
  }
  return kExitOk;
}

// Writes the CSV table to `out`, then prints the tables and notes, or with
// --json the document. kExitOk, or kExitError when the table cannot be
// written.
int WriteAndPrint(const fs::path& out, bool json, size_t meshes, StudyReport* report) {
  std::string text;
  for (const auto& row : report->csv_rows) {
    for (size_t i = 0; i < row.size(); ++i) text += (i ? "," : "") + CsvCell(row[i]);
    text += "\n";
  }
  if (!WriteFileAtomically(out, text)) {
    std::fprintf(stderr, "pba: cannot write %s\n", out.c_str());
    return kExitError;
  }
  if (json) {
    (*report->document.mutable_fields())["table"].set_string_value(out.string());
    PrintJson(report->document);
    return kExitOk;
  }
  PrintTable(report->rows);
  if (meshes >= 3) {
    std::printf(
        "\nThe three finest meshes (Celik et al. 2008; 1 the finest, r the ratio of sizes from "
        "element counts):\n");
    PrintTable(report->analysis);
  }
  for (const std::string& note : report->notes) std::printf("%s\n", note.c_str());
  std::printf("Table written to %s\n", out.c_str());
  return kExitOk;
}

}  // namespace

int RunConvergenceStudy(Connection& connection, const StudyArgs& args) {
  Study study;
  std::string error;
  if (!BuildStudy(args, &study, &error)) {
    std::fprintf(stderr, "pba: %s\n", error.c_str());
    return kExitInvalid;
  }
  if (args.dry_run) {
    PrintDryRun(study);
    return kExitOk;
  }
  const fs::path out = TablePath(args);
  if (const int code = RunMeshes(connection, args, out, &study); code != kExitOk) return code;
  if (!EveryMeshSucceeded(study)) return kExitJobFailed;
  MeshResults results;
  if (const int code = ReadMeshResults(study, args, &results); code != kExitOk) return code;
  StudyReport report;
  TabulateMeshes(study, args, results, &report);
  if (const int code = AnalyseFinestMeshes(args, results, &report); code != kExitOk) return code;
  return WriteAndPrint(out, connection.options().json, study.members.size(), &report);
}

void RegisterStudyCommands(CLI::App& app, CommandContext& context) {
  CLI::App* study = AddCommandGroup(app, "study", "Studies over many jobs of one scene");
  auto args = std::make_shared<StudyArgs>();
  CLI::App* convergence = study->add_subcommand(
      "convergence",
      "Mesh convergence: the scene on successively finer meshes; change per mesh, observed "
      "order, Richardson extrapolate and grid convergence index");
  convergence->add_option("scene", args->scene, "Scene file (YAML)")
      ->required()
      ->check(CLI::ExistingFile);
  convergence
      ->add_option("-q,--quantity", args->quantities,
                   "A number of the summary, e.g. results.reactions[0].force_n[2] (repeatable)")
      ->required();
  CLI::Option* sizes =
      convergence
          ->add_option("--sizes", args->sizes,
                       "Element sizes [mm], e.g. 8,5.6,4 (default: the scene's own, then divided "
                       "by --ratio)")
          ->delimiter(',');
  convergence->add_option("--meshes", args->meshes, "Number of meshes without --sizes")
      ->check(CLI::Range(2, 12))
      ->capture_default_str()
      ->excludes(sizes);
  convergence->add_option("--ratio", args->ratio, "Ratio of successive element sizes, > 1")
      ->check(CLI::Range(1.05, 4.0))
      ->capture_default_str()
      ->excludes(sizes);
  convergence->add_option("--parallel", args->parallel, "Jobs in flight at most")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  convergence->add_option(
      "-o,--out", args->out,
      "CSV table (default SCENE's name .convergence.csv beside it; the state file beside it)");
  convergence->add_option("--snapshot", args->snapshot,
                          "PROJECT/SNAPSHOT: build an atlas scene from this snapshot");
  convergence
      ->add_option("--tolerance", args->tolerance_pct,
                   "A change from the previous mesh below it [%] counts as converged")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  convergence->add_flag("--retry-failed", args->retry_failed,
                        "Resubmit meshes whose earlier job failed or was cancelled");
  convergence
      ->add_option("--ranks", args->ranks,
                   "MPI processes each mesh's job runs on (pba job submit --ranks)")
      ->check(CLI::NonNegativeNumber);
  convergence->add_flag("--dry-run", args->dry_run,
                        "Print the sizes each mesh's scene gets, submit nothing");
  context.Add(convergence, [args](Connection& c) { return RunConvergenceStudy(c, *args); });
}

}  // namespace pba::cli
