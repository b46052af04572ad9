#include "commands/batch_commands.h"

#include <google/protobuf/struct.pb.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>

#include "codec/yaml_codec.h"
#include "commands/job_commands.h"
#include "exit_codes.h"
#include "files.h"
#include "output.h"

namespace pba::cli {
namespace fs = std::filesystem;
namespace {

struct Member {
  std::string name;
  std::vector<std::pair<std::string, std::string>> values;  // path, value as written
  v1::Scene scene;
  std::string request_id;
  std::string job_id;  // from the state file or the submit
  v1::Job job;
};

struct Batch {
  std::string name;
  fs::path scene_file;
  v1::SnapshotRef snapshot;  // every member's atlas from it, when set
  int parallel = 2;
  std::vector<std::string> parameters;  // the paths the members set, in order
  std::vector<Member> members;
  std::vector<std::string> outputs;
};

// "a.b[2].c" -> {"a", "b", "[2]", "c"}; false on a malformed path.
bool SplitPath(const std::string& path, std::vector<std::string>* parts) {
  parts->clear();
  std::string current;
  for (size_t i = 0; i < path.size(); ++i) {
    const char c = path[i];
    if (c == '.') {
      if (current.empty() && (parts->empty() || parts->back()[0] != '[')) return false;
      if (!current.empty()) parts->push_back(current);
      current.clear();
    } else if (c == '[') {
      if (!current.empty()) parts->push_back(current);
      current.clear();
      const size_t close = path.find(']', i);
      if (close == std::string::npos || close == i + 1) return false;
      const std::string index = path.substr(i + 1, close - i - 1);
      if (index.find_first_not_of("0123456789") != std::string::npos) return false;
      parts->push_back("[" + index + "]");
      i = close;
    } else {
      current += c;
    }
  }
  if (!current.empty()) parts->push_back(current);
  return !parts->empty() && (*parts)[0][0] != '[';
}

// Sets `path` in `node` to `value`, creating maps on the way; a list index
// must exist. False with *error naming the part that does not fit.
bool SetPath(YAML::Node node, const std::string& path, const YAML::Node& value,
             std::string* error) {
  std::vector<std::string> parts;
  if (!SplitPath(path, &parts)) {
    *error = "'" + path + "' is not a path (names joined by dots, [i] for list elements)";
    return false;
  }
  for (size_t i = 0; i < parts.size(); ++i) {
    const bool last = i + 1 == parts.size();
    const std::string& part = parts[i];
    if (part[0] == '[') {
      const size_t index = std::stoul(part.substr(1, part.size() - 2));
      if (!node.IsSequence() || index >= node.size()) {
        *error = path + ": the base scene has " +
                 std::to_string(node.IsSequence() ? node.size() : 0) + " entries there, no " + part;
        return false;
      }
      if (last) {
        node[index] = value;
        return true;
      }
      node.reset(node[index]);
      continue;
    }
    if (node.IsDefined() && !node.IsNull() && !node.IsMap()) {
      *error = path + ": '" + part + "' is inside a value that is not a map";
      return false;
    }
    if (last) {
      node[part] = value;
      return true;
    }
    YAML::Node child = node[part];
    if (!child.IsDefined() || child.IsNull()) {
      node[part] = YAML::Node(YAML::NodeType::Map);
      child = node[part];
    }
    node.reset(child);
  }
  return true;
}

// The value at `path` in a JSON document read as YAML; "" when absent.
std::string GetPath(const YAML::Node& root, const std::string& path) {
  std::vector<std::string> parts;
  if (!SplitPath(path, &parts)) return "";
  YAML::Node node = YAML::Clone(root);
  for (const std::string& part : parts) {
    if (part[0] == '[') {
      const size_t index = std::stoul(part.substr(1, part.size() - 2));
      if (!node.IsSequence() || index >= node.size()) return "";
      node.reset(node[index]);
    } else {
      if (!node.IsMap() || !node[part]) return "";
      node.reset(node[part]);
    }
  }
  if (node.IsScalar()) return node.Scalar();
  YAML::Emitter out;
  out << YAML::Flow << node;
  return out.c_str();
}

std::string Scalar(const YAML::Node& value) {
  if (value.IsScalar()) return value.Scalar();
  YAML::Emitter out;
  out << YAML::Flow << value;
  return out.c_str();
}

std::string LastName(const std::string& path) {
  const size_t dot = path.rfind('.');
  return dot == std::string::npos ? path : path.substr(dot + 1);
}

// Reads the batch file and builds every member's scene; false with a message
// naming the file, the member and the field.
bool LoadBatch(const std::string& file, Batch* batch, std::string* error) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(file);
  } catch (const YAML::Exception& e) {
    *error = file + ": " + e.what();
    return false;
  }
  if (!root.IsMap()) {
    *error = file + ": a batch is a map with scene, sweep or members, and outputs";
    return false;
  }
  static const char* kKeys[] = {"name",  "scene",   "snapshot", "parallel",
                                "sweep", "members", "outputs"};
  for (const auto& entry : root) {
    const std::string key = entry.first.Scalar();
    if (std::find(std::begin(kKeys), std::end(kKeys), key) == std::end(kKeys)) {
      *error = file + ": unknown key '" + key +
               "' (a batch has name, scene, snapshot, parallel, sweep or members, outputs)";
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
    try {
      batch->parallel = root["parallel"].as<int>();
    } catch (const YAML::Exception&) {
      batch->parallel = 0;
    }
    if (batch->parallel < 1 || batch->parallel > 64) {
      *error = file + ": parallel: expected a whole number from 1 to 64";
      return false;
    }
  }
  if (root["outputs"]) {
    if (!root["outputs"].IsSequence()) {
      *error = file + ": outputs: expected a list of summary paths";
      return false;
    }
    for (const auto& o : root["outputs"]) batch->outputs.push_back(o.Scalar());
  }
  // The members' values: a cartesian product, or a list.
  std::vector<std::pair<std::string, std::vector<std::pair<std::string, YAML::Node>>>> members;
  if (root["sweep"] && root["members"]) {
    *error = file + ": give sweep or members, not both";
    return false;
  }
  if (root["sweep"]) {
    if (!root["sweep"].IsMap() || root["sweep"].size() == 0) {
      *error = file + ": sweep: expected a map of path: [values]";
      return false;
    }
    members.push_back({"", {}});
    for (const auto& axis : root["sweep"]) {
      const std::string path = axis.first.Scalar();
      if (!axis.second.IsSequence() || axis.second.size() == 0) {
        *error = file + ": sweep." + path + ": expected a non-empty list of values";
        return false;
      }
      batch->parameters.push_back(path);
      std::vector<std::pair<std::string, std::vector<std::pair<std::string, YAML::Node>>>> next;
      for (const auto& member : members) {
        for (const auto& value : axis.second) {
          auto extended = member;
          extended.first +=
              (extended.first.empty() ? "" : ",") + LastName(path) + "=" + Scalar(value);
          extended.second.push_back({path, value});
          next.push_back(std::move(extended));
        }
      }
      members = std::move(next);
    }
  } else if (root["members"]) {
    if (!root["members"].IsSequence() || root["members"].size() == 0) {
      *error = file + ": members: expected a non-empty list of {name, set}";
      return false;
    }
    int index = 0;
    for (const auto& m : root["members"]) {
      const std::string where = file + ": members[" + std::to_string(index) + "]";
      if (!m.IsMap() || !m["set"] || !m["set"].IsMap()) {
        *error = where + ": expected {name: ..., set: {path: value, ...}}";
        return false;
      }
      std::string name = m["name"] ? m["name"].Scalar() : "member " + std::to_string(index + 1);
      std::vector<std::pair<std::string, YAML::Node>> values;
      for (const auto& v : m["set"]) {
        const std::string path = v.first.Scalar();
        values.push_back({path, v.second});
        if (std::find(batch->parameters.begin(), batch->parameters.end(), path) ==
            batch->parameters.end())
          batch->parameters.push_back(path);
      }
      members.push_back({name, values});
      ++index;
    }
  } else {
    *error = file + ": a batch needs sweep or members";
    return false;
  }
  std::set<std::string> names;
  for (const auto& [name, values] : members) {
    if (!names.insert(name).second) {
      *error = file + ": two members are named '" + name + "'";
      return false;
    }
  }

  YAML::Node base;
  try {
    base = YAML::LoadFile(batch->scene_file.string());
  } catch (const YAML::Exception& e) {
    *error = batch->scene_file.string() + ": " + e.what();
    return false;
  }
  const std::string base_name = base["name"] ? base["name"].Scalar() : batch->name;
  for (const auto& [name, values] : members) {
    Member member;
    member.name = name;
    YAML::Node scene = YAML::Clone(base);
    for (const auto& [path, value] : values) {
      std::string why;
      if (!SetPath(scene, path, value, &why)) {
        *error = file + ": member '" + name + "': " + why;
        return false;
      }
      member.values.push_back({path, Scalar(value)});
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
    member.request_id = Sha256Text(batch->name + "\n" + out.c_str() + on).substr(0, 32);
    batch->members.push_back(std::move(member));
  }
  return true;
}

fs::path StatePath(const std::string& file) { return file + ".pba-batch"; }

// member name -> job id, one "job-id<TAB>member" line each.
std::map<std::string, std::string> ReadState(const std::string& file) {
  std::map<std::string, std::string> jobs;
  std::ifstream in(StatePath(file));
  std::string line;
  while (std::getline(in, line)) {
    const size_t tab = line.find('\t');
    if (tab != std::string::npos) jobs[line.substr(tab + 1)] = line.substr(0, tab);
  }
  return jobs;
}

void WriteState(const std::string& file, const Batch& batch) {
  std::string content;
  for (const Member& m : batch.members) {
    if (!m.job_id.empty()) content += m.job_id + "\t" + m.name + "\n";
  }
  WriteFileAtomically(StatePath(file), content);
}

std::string CsvCell(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

bool IsDone(v1::Job::State state) {
  return state == v1::Job::SUCCEEDED || state == v1::Job::FAILED || state == v1::Job::CANCELLED;
}

}  // namespace

int RunBatch(Connection& connection, const BatchArgs& args) {
  Batch batch;
  std::string error;
  if (!LoadBatch(args.file, &batch, &error)) {
    std::fprintf(stderr, "pba: %s\n", error.c_str());
    return kExitInvalid;
  }
  const bool json = connection.options().json;
  if (args.dry_run) {
    for (const Member& m : batch.members) std::printf("%s\n", m.scene.name().c_str());
    std::printf("%zu members; nothing submitted (--dry-run)\n", batch.members.size());
    return kExitOk;
  }

  // Jobs of an earlier run: kept when they succeeded (or are still going),
  // resubmitted when they failed and --retry-failed says so.
  const auto earlier = ReadState(args.file);
  std::vector<size_t> to_submit;
  for (size_t i = 0; i < batch.members.size(); ++i) {
    Member& m = batch.members[i];
    const auto it = earlier.find(m.name);
    if (it != earlier.end()) {
      v1::GetJobRequest request;
      request.set_id(it->second);
      auto context = connection.UnaryContext();
      grpc::Status status = connection.jobs().GetJob(context.get(), request, &m.job);
      const bool failed =
          status.ok() && (m.job.state() == v1::Job::FAILED || m.job.state() == v1::Job::CANCELLED);
      if (status.ok() && !(failed && args.retry_failed)) {
        m.job_id = it->second;
        continue;
      }
      if (failed) m.request_id = Sha256Text(m.request_id + it->second).substr(0, 32);
    }
    to_submit.push_back(i);
  }
  const size_t kept = batch.members.size() - to_submit.size();
  if (!json) {
    std::printf("Batch %s: %zu members, %zu from an earlier run, %zu to submit, %d at a time\n",
                batch.name.c_str(), batch.members.size(), kept, to_submit.size(), batch.parallel);
    std::fflush(stdout);
  }

  // Submit with at most `parallel` unfinished jobs; poll them.
  size_t next = 0, finished = 0;
  const auto in_flight = [&] {
    int n = 0;
    for (const Member& m : batch.members) n += !m.job_id.empty() && !IsDone(m.job.state());
    return n;
  };
  while (true) {
    while (next < to_submit.size() && in_flight() < batch.parallel) {
      Member& m = batch.members[to_submit[next++]];
      v1::SubmitJobRequest request;
      *request.mutable_scene() = m.scene;
      if (!batch.snapshot.project().empty()) *request.mutable_snapshot() = batch.snapshot;
      request.set_request_id(m.request_id);
      auto context = connection.UnaryContext();
      grpc::Status status = connection.jobs().SubmitJob(context.get(), request, &m.job);
      if (!status.ok()) {
        WriteState(args.file, batch);
        return connection.Fail("submitting member '" + m.name + "'", status);
      }
      m.job_id = m.job.id();
      WriteState(args.file, batch);
      if (!json) std::printf("submitted %s: %s\n", m.job_id.c_str(), m.name.c_str());
    }
    bool any_open = false;
    for (Member& m : batch.members) {
      if (m.job_id.empty() || IsDone(m.job.state())) continue;
      v1::GetJobRequest request;
      request.set_id(m.job_id);
      auto context = connection.UnaryContext();
      grpc::Status status = connection.jobs().GetJob(context.get(), request, &m.job);
      if (!status.ok()) return connection.Fail("job " + m.job_id, status);
      if (IsDone(m.job.state())) {
        ++finished;
        if (!json) {
          std::printf("[%zu/%zu] %s %s: %s%s\n", finished, to_submit.size(), m.job_id.c_str(),
                      m.name.c_str(), StateName(m.job.state()).c_str(),
                      m.job.error().empty() ? "" : (" (" + m.job.error() + ")").c_str());
        }
      } else {
        any_open = true;
      }
    }
    std::fflush(stdout);
    if (!any_open && next >= to_submit.size()) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(static_cast<int>(args.poll_s * 1000)));
  }

  // The table: member, its values, job, state, outputs.
  std::vector<std::string> header = {"member"};
  for (const std::string& p : batch.parameters) header.push_back(p);
  header.insert(header.end(), {"job", "state"});
  for (const std::string& o : batch.outputs) header.push_back(o);
  std::vector<std::vector<std::string>> rows = {header};
  int failed = 0;
  for (const Member& m : batch.members) {
    std::vector<std::string> row = {m.name};
    for (const std::string& p : batch.parameters) {
      std::string value;
      for (const auto& [path, v] : m.values) {
        if (path == p) value = v;
      }
      row.push_back(value);
    }
    row.insert(row.end(), {m.job_id, StateName(m.job.state())});
    failed += m.job.state() != v1::Job::SUCCEEDED;
    const YAML::Node summary = YAML::Load(codec::ToJson(m.job.summary()));
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
  return failed > 0 ? kExitJobFailed : kExitOk;
}

}  // namespace pba::cli
