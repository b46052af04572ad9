#include "commands/batch_commands.h"

#include <google/protobuf/struct.pb.h>
#include <yaml-cpp/yaml.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>

#include "codec/yaml_codec.h"
#include "commands/batch_plot.h"
#include "commands/batch_shared.h"
#include "commands/command_context.h"
#include "commands/job_commands.h"
#include "core/sha256.h"
#include "core/yaml_guard.h"
#include "exit_codes.h"
#include "files.h"
#include "output.h"

namespace pba::cli {
namespace fs = std::filesystem;
namespace {

struct Batch {
  std::string name;
  fs::path scene_file;
  v1::SnapshotRef snapshot;  // every member's atlas from it, when set
  // Unfinished jobs at most; kParallelAll: every member at once;
  // kParallelAuto: as the server suits (ParallelFor).
  int parallel = kParallelAuto;
  std::vector<std::string> parameters;  // the paths the members set, in order
  std::vector<RunMember> members;       // keyed by name in the state file
  // What each member sets: path, value as written.
  std::vector<std::vector<std::pair<std::string, std::string>>> values;
  std::vector<std::string> outputs;
  PlotSpec plot;  // the picture of the members' histories, when enabled
};

// YAML::LoadFile with aliases and oversized texts refused first: the
// members' copies of a tree of nested aliases expand it (core/yaml_guard.h).
bool LoadBoundedYaml(const std::string& file, YAML::Node* node, std::string* error) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    *error = file + ": cannot read (no such file or not readable)";
    return false;
  }
  std::ostringstream text;
  text << in.rdbuf();
  const YamlProblem problem = FindYamlProblem(text.str());
  if (!problem.message.empty()) {
    *error = file + (problem.line > 0 ? ":" + std::to_string(problem.line) : "") + ": " +
             problem.message;
    return false;
  }
  try {
    *node = YAML::Load(text.str());
  } catch (const YAML::Exception& e) {
    *error = file + ": " + e.what();
    return false;
  }
  return true;
}

std::string LastName(const std::string& path) {
  const size_t dot = path.rfind('.');
  return dot == std::string::npos ? path : path.substr(dot + 1);
}

// A member before its scene is built: its name and the values it sets
// (path, value), in the order given.
struct MemberValues {
  std::string name;
  std::vector<std::pair<std::string, YAML::Node>> values;
};

// The batch file's settings: every key known; name, scene, snapshot,
// parallel, outputs and plot into *batch. False with a message naming the
// file and the key.
bool ReadSettings(const std::string& file, const YAML::Node& root, Batch* batch,
                  std::string* error) {
  if (!root.IsMap()) {
    *error = file + ": a batch is a map with scene, sweep or members, and outputs";
    return false;
  }
  static const char* kKeys[] = {"name",  "scene",   "snapshot", "parallel",
                                "sweep", "members", "outputs",  "plot"};
  for (const auto& entry : root) {
    const std::string key = entry.first.Scalar();
    if (std::find(std::begin(kKeys), std::end(kKeys), key) == std::end(kKeys)) {
      *error = file + ": unknown key '" + key +
               "' (a batch has name, scene, snapshot, parallel, sweep or members, outputs, "
               "plot)";
      return false;
    }
  }
  batch->name = root["name"] ? root["name"].Scalar() : fs::path(file).stem().string();
  if (!root["scene"] || !root["scene"].IsScalar()) {
    *error = file + ": scene: the base scene file is required";
    return false;
  }
  batch->scene_file = fs::path(file).parent_path() / root["scene"].Scalar();
  if (root["snapshot"]) {
    if (!root["snapshot"].IsScalar() ||
        !ParseSnapshotRef(root["snapshot"].Scalar(), &batch->snapshot)) {
      *error = file + ": snapshot: expected PROJECT/SNAPSHOT (an id or a tag)";
      return false;
    }
  }
  if (root["parallel"]) {
    if (root["parallel"].IsScalar() && root["parallel"].Scalar() == "all") {
      batch->parallel = kParallelAll;
    } else {
      try {
        batch->parallel = root["parallel"].as<int>();
      } catch (const YAML::Exception&) {
        batch->parallel = 0;
      }
      if (batch->parallel < 1 || batch->parallel > 64) {
        *error = file + ": parallel: expected a whole number from 1 to 64, or all";
        return false;
      }
    }
  }
  if (root["outputs"]) {
    if (!root["outputs"].IsSequence()) {
      *error = file + ": outputs: expected a list of summary paths";
      return false;
    }
    for (const auto& o : root["outputs"]) batch->outputs.push_back(o.Scalar());
  }
  if (root["plot"]) {
    std::string why;
    if (!ParsePlotSpec(root["plot"], &batch->plot, &why)) {
      *error = file + ": plot: " + why;
      return false;
    }
  }
  return true;
}

// sweep: every combination of the axes' values, each member named by its
// values ("c10_pa=100,element_size_mm=4"); the axes' paths into
// batch->parameters.
bool SweepMembers(const std::string& file, const YAML::Node& sweep, Batch* batch,
                  std::vector<MemberValues>* members, std::string* error) {
  if (!sweep.IsMap() || sweep.size() == 0) {
    *error = file + ": sweep: expected a map of path: [values]";
    return false;
  }
  members->push_back({"", {}});
  for (const auto& axis : sweep) {
    const std::string path = axis.first.Scalar();
    if (!axis.second.IsSequence() || axis.second.size() == 0) {
      *error = file + ": sweep." + path + ": expected a non-empty list of values";
      return false;
    }
    batch->parameters.push_back(path);
    std::vector<MemberValues> next;
    for (const MemberValues& member : *members) {
      for (const auto& value : axis.second) {
        MemberValues extended = member;
        extended.name += (extended.name.empty() ? "" : ",") + LastName(path) + "=" + Scalar(value);
        extended.values.push_back({path, value});
        next.push_back(std::move(extended));
      }
    }
    *members = std::move(next);
  }
  return true;
}

// members: the list as given (a member without a name is "member N"); every
// path any member sets into batch->parameters, in order of appearance.
bool ListedMembers(const std::string& file, const YAML::Node& list, Batch* batch,
                   std::vector<MemberValues>* members, std::string* error) {
  if (!list.IsSequence() || list.size() == 0) {
    *error = file + ": members: expected a non-empty list of {name, set}";
    return false;
  }
  int index = 0;
  for (const auto& m : list) {
    const std::string where = file + ": members[" + std::to_string(index) + "]";
    if (!m.IsMap() || !m["set"] || !m["set"].IsMap()) {
      *error = where + ": expected {name: ..., set: {path: value, ...}}";
      return false;
    }
    MemberValues member;
    member.name = m["name"] ? m["name"].Scalar() : "member " + std::to_string(index + 1);
    for (const auto& v : m["set"]) {
      const std::string path = v.first.Scalar();
      member.values.push_back({path, v.second});
      if (std::find(batch->parameters.begin(), batch->parameters.end(), path) ==
          batch->parameters.end())
        batch->parameters.push_back(path);
    }
    members->push_back(std::move(member));
    ++index;
  }
  return true;
}

// The members' values: a cartesian product (sweep) or a list (members),
// their names unique.
bool ReadMembers(const std::string& file, const YAML::Node& root, Batch* batch,
                 std::vector<MemberValues>* members, std::string* error) {
  if (root["sweep"] && root["members"]) {
    *error = file + ": give sweep or members, not both";
    return false;
  }
  if (root["sweep"]) {
    if (!SweepMembers(file, root["sweep"], batch, members, error)) return false;
  } else if (root["members"]) {
    if (!ListedMembers(file, root["members"], batch, members, error)) return false;
  } else {
    *error = file + ": a batch needs sweep or members";
    return false;
  }
  std::set<std::string> names;
  for (const MemberValues& member : *members) {
    if (!names.insert(member.name).second) {
      *error = file + ": two members are named '" + member.name + "'";
      return false;
    }
  }
  return true;
}

// Each member's scene: the base scene with the member's values set, checked
// by the codec, with a request id from its text.
bool BuildMemberScenes(const std::string& file, const std::vector<MemberValues>& members,
                       Batch* batch, std::string* error) {
  YAML::Node base;
  if (!LoadBoundedYaml(batch->scene_file.string(), &base, error)) return false;
  const std::string base_name = base["name"] ? base["name"].Scalar() : batch->name;
  for (const auto& [name, values] : members) {
    RunMember member;
    member.name = name;
    member.key = name;
    std::vector<std::pair<std::string, std::string>> written;
    YAML::Node scene = YAML::Clone(base);
    for (const auto& [path, value] : values) {
      std::string why;
      if (!SetPath(scene, path, value, &why)) {
        *error = file + ": member '" + name + "': " + why;
        return false;
      }
      written.push_back({path, Scalar(value)});
    }
    scene["name"] = base_name + " [" + name + "]";
    YAML::Emitter out;
    out << scene;
    codec::ParseError parse;
    if (!codec::ParseYaml(out.c_str(), &member.scene, &parse)) {
      parse.line = 0;  // a line of the generated text would mislead
      *error = file + ": member '" + name + "': " + parse.ToString();
      return false;
    }
    // The same member of the same batch gets the same request id, so a
    // submit repeated after an interruption returns the job already made.
    // The key changes with the scene and with the snapshot it is built from.
    const std::string on =
        batch->snapshot.project().empty()
            ? ""
            : "\nsnapshot " + batch->snapshot.project() + "/" + batch->snapshot.snapshot();
    member.request_id = Sha256Hex(batch->name + "\n" + out.c_str() + on).substr(0, 32);
    batch->members.push_back(std::move(member));
    batch->values.push_back(std::move(written));
  }
  return true;
}

// Reads the batch file and builds every member's scene; false with a message
// naming the file, the member and the field.
bool LoadBatch(const std::string& file, Batch* batch, std::string* error) {
  YAML::Node root;
  if (!LoadBoundedYaml(file, &root, error)) return false;
  if (!ReadSettings(file, root, batch, error)) return false;
  std::vector<MemberValues> members;
  if (!ReadMembers(file, root, batch, &members, error)) return false;
  return BuildMemberScenes(file, members, batch, error);
}

fs::path StatePath(const std::string& file) { return file + ".pba-batch"; }

}  // namespace

int RunBatch(Connection& connection, const BatchArgs& args) {
  Batch batch;
  std::string error;
  if (!LoadBatch(args.file, &batch, &error)) {
    std::fprintf(stderr, "pba: %s\n", error.c_str());
    return kExitInvalid;
  }
  // Only some analyses write the file a plot draws (history.csv: the
  // time-stepping ones; sensors.csv: EXPLICIT_DYNAMIC with sensors): refused
  // before anything runs rather than after the whole batch.
  if (batch.plot.enabled && !args.no_plot &&
      !MembersWritePlotFile(batch.members, batch.plot.file, &error)) {
    std::fprintf(stderr, "pba: %s: %s\n", args.file.c_str(), error.c_str());
    return kExitInvalid;
  }
  const bool json = connection.options().json;
  if (args.dry_run) {
    for (const RunMember& m : batch.members) std::printf("%s\n", m.scene.name().c_str());
    std::printf("%zu members; nothing submitted (--dry-run)\n", batch.members.size());
    return kExitOk;
  }

  // Jobs of an earlier run: kept when they succeeded (or are still going),
  // resubmitted when they failed and --retry-failed says so.
  RunOptions options;
  options.state = StatePath(args.file);
  options.snapshot = batch.snapshot;
  options.parallel = ParallelFor(connection, batch.parallel);
  options.retry_failed = args.retry_failed;
  options.ranks = args.ranks;
  options.poll_s = args.poll_s;
  options.quiet = json;
  const std::vector<size_t> to_submit = ResumeMembers(connection, options, &batch.members);
  const size_t kept = batch.members.size() - to_submit.size();
  if (!json) {
    std::printf("Batch %s: %zu members, %zu from an earlier run, %zu to submit, %s\n",
                batch.name.c_str(), batch.members.size(), kept, to_submit.size(),
                options.parallel == kParallelAll
                    ? "all at once (the server's queue bounds how many run)"
                    : (std::to_string(options.parallel) + " at a time").c_str());
    std::fflush(stdout);
  }
  if (const int code = SubmitAndPoll(connection, options, to_submit, &batch.members);
      code != kExitOk)
    return code;

  // The table: member, its values, job, state, outputs.
  std::vector<std::string> header = {"member"};
  for (const std::string& p : batch.parameters) header.push_back(p);
  header.insert(header.end(), {"job", "state"});
  for (const std::string& o : batch.outputs) header.push_back(o);
  std::vector<std::vector<std::string>> rows = {header};
  int failed = 0;
  for (size_t i = 0; i < batch.members.size(); ++i) {
    const RunMember& m = batch.members[i];
    std::vector<std::string> row = {m.name};
    for (const std::string& p : batch.parameters) {
      std::string value;
      for (const auto& [path, v] : batch.values[i]) {
        if (path == p) value = v;
      }
      row.push_back(value);
    }
    row.insert(row.end(), {m.job_id, StateName(m.job.state())});
    failed += m.job.state() != v1::Job::SUCCEEDED;
    const YAML::Node summary = SummaryTree(m.job.summary(), false);
    for (const std::string& o : batch.outputs) row.push_back(GetPath(summary, o));
    rows.push_back(row);
  }
  const fs::path out = args.out.empty() ? fs::path(args.file).parent_path() /
                                              (fs::path(args.file).stem().string() + ".csv")
                                        : fs::path(args.out);
  std::string csv;
  for (const auto& row : rows) {
    for (size_t i = 0; i < row.size(); ++i) csv += (i ? "," : "") + CsvCell(row[i]);
    csv += "\n";
  }
  if (!WriteFileAtomically(out, csv)) {
    std::fprintf(stderr, "pba: cannot write %s\n", out.c_str());
    return kExitError;
  }
  if (json) {
    // One object per member; numbers as numbers.
    google::protobuf::ListValue list;
    for (size_t r = 1; r < rows.size(); ++r) {
      auto& fields = *list.add_values()->mutable_struct_value()->mutable_fields();
      for (size_t i = 0; i < header.size(); ++i) {
        const std::string& cell = rows[r][i];
        char* end = nullptr;
        const double number = std::strtod(cell.c_str(), &end);
        const bool numeric = i > 0 && !cell.empty() && end == cell.c_str() + cell.size();
        if (numeric) {
          fields[header[i]].set_number_value(number);
        } else {
          fields[header[i]].set_string_value(cell);
        }
      }
    }
    PrintJson(list);
  } else {
    PrintTable(rows);
    std::printf("Table written to %s\n", out.c_str());
  }
  if (batch.plot.enabled && !args.no_plot) {
    // Beside the batch file: its histories (or sensor samples); beside the
    // table: the picture.
    const std::string stem = fs::path(args.file).stem().string();
    BatchPlotOptions plot;
    plot.histories = fs::path(args.file).parent_path() /
                     (stem + (batch.plot.file == "sensors.csv" ? "_sensors" : "_histories"));
    plot.png = out.parent_path() / (stem + ".png");
    plot.default_title = batch.name;
    plot.quiet = json;
    std::fflush(stdout);
    if (const int code = DrawBatchPlot(connection, batch.plot, batch.members, plot);
        code != kExitOk)
      return code;
  }
  return failed > 0 ? kExitJobFailed : kExitOk;
}

void RegisterBatchCommands(CLI::App& app, CommandContext& context) {
  CLI::App* batch = AddCommandGroup(app, "batch", "Scripted batches of jobs");
  auto args = std::make_shared<BatchArgs>();
  CLI::App* run = batch->add_subcommand(
      "run", "Run a base scene over parameter sweeps; one table of outputs per member");
  run->add_option("file", args->file, "Batch file (YAML)")->required()->check(CLI::ExistingFile);
  run->add_option("-o,--out", args->out, "CSV table (default FILE's name .csv)");
  run->add_flag("--retry-failed", args->retry_failed,
                "Resubmit members whose earlier job failed or was cancelled");
  run->add_flag("--dry-run", args->dry_run, "Check the members, submit nothing");
  run->add_option("--ranks", args->ranks,
                  "MPI processes each member's job runs on (pba job submit --ranks)")
      ->check(CLI::NonNegativeNumber);
  run->add_flag("--no-plot", args->no_plot,
                "Draw no picture of the members' histories (the plot section)");
  context.Add(run, [args](Connection& c) { return RunBatch(c, *args); });
}

}  // namespace pba::cli
