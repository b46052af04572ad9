#include "commands/batch_shared.h"

#include <google/protobuf/util/json_util.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <map>
#include <thread>

#include "codec/yaml_codec.h"
#include "core/sha256.h"
#include "exit_codes.h"
#include "files.h"
#include "output.h"

namespace pba::cli {
namespace {

bool IsDone(v1::Job::State state) {
  return state == v1::Job::SUCCEEDED || state == v1::Job::FAILED || state == v1::Job::CANCELLED;
}

// key -> job id, from "job-id<TAB>key[<TAB>name]" lines.
std::map<std::string, std::string> ReadState(const std::filesystem::path& path) {
  std::map<std::string, std::string> jobs;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    const size_t tab = line.find('\t');
    if (tab == std::string::npos) continue;
    const size_t end = line.find('\t', tab + 1);
    jobs[line.substr(tab + 1, end == std::string::npos ? std::string::npos : end - tab - 1)] =
        line.substr(0, tab);
  }
  return jobs;
}

void WriteState(const RunOptions& options, const std::vector<RunMember>& members) {
  std::string content;
  for (const RunMember& m : members) {
    if (m.job_id.empty()) continue;
    content += m.job_id + "\t" + m.key + (options.name_in_state ? "\t" + m.name : "") + "\n";
  }
  WriteFileAtomically(options.state, content);
}

}  // namespace

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
  return Scalar(node);
}

std::string Scalar(const YAML::Node& value) {
  if (value.IsScalar()) return value.Scalar();
  YAML::Emitter out;
  out << YAML::Flow << value;
  return out.c_str();
}

std::string CsvCell(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

YAML::Node SummaryTree(const v1::Summary& summary, bool zeros) {
  if (!zeros) return YAML::Load(codec::ToJson(summary));
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  options.always_print_primitive_fields = true;
  std::string json;
  // Printing a well-formed message cannot fail.
  (void)google::protobuf::util::MessageToJsonString(summary, &json, options);
  return YAML::Load(json);
}

int ParallelFor(Connection& connection, int parallel) {
  if (parallel != kParallelAuto) return parallel;
  v1::ServerInfo info;
  auto context = connection.UnaryContext();
  // A server without GetServerInfo runs its jobs locally.
  const grpc::Status status =
      connection.jobs().GetServerInfo(context.get(), v1::GetServerInfoRequest(), &info);
  return status.ok() && info.executor() == "slurm" ? kParallelAll : kParallelDefault;
}

std::vector<size_t> ResumeMembers(Connection& connection, const RunOptions& options,
                                  std::vector<RunMember>* members) {
  const auto earlier = ReadState(options.state);
  std::vector<size_t> to_submit;
  for (size_t i = 0; i < members->size(); ++i) {
    RunMember& m = (*members)[i];
    const auto it = earlier.find(m.key);
    if (it != earlier.end()) {
      v1::GetJobRequest request;
      request.set_id(it->second);
      auto context = connection.UnaryContext();
      grpc::Status status = connection.jobs().GetJob(context.get(), request, &m.job);
      const bool failed =
          status.ok() && (m.job.state() == v1::Job::FAILED || m.job.state() == v1::Job::CANCELLED);
      if (status.ok() && !(failed && options.retry_failed)) {
        m.job_id = it->second;
        continue;
      }
      // A new key for the retry: the old one would return the failed job.
      if (failed) m.request_id = Sha256Hex(m.request_id + it->second).substr(0, 32);
    }
    to_submit.push_back(i);
  }
  return to_submit;
}

int SubmitAndPoll(Connection& connection, const RunOptions& options,
                  const std::vector<size_t>& to_submit, std::vector<RunMember>* members) {
  size_t next = 0, finished = 0;
  const auto in_flight = [&] {
    int n = 0;
    for (const RunMember& m : *members) n += !m.job_id.empty() && !IsDone(m.job.state());
    return n;
  };
  // The server refused a submit over its bound of open jobs per user,
  // which counts all of the user's queued and running jobs, this batch's
  // or not: no more until the next look, then the same member again.
  bool full = false, said_full = false;
  while (true) {
    while (next < to_submit.size() &&
           (options.parallel == kParallelAll || in_flight() < options.parallel) && !full) {
      RunMember& m = (*members)[to_submit[next++]];
      v1::SubmitJobRequest request;
      *request.mutable_scene() = m.scene;
      if (!options.snapshot.project().empty()) *request.mutable_snapshot() = options.snapshot;
      request.set_request_id(m.request_id);
      request.set_ranks(options.ranks);
      auto context = connection.UnaryContext();
      grpc::Status status = connection.jobs().SubmitJob(context.get(), request, &m.job);
      if (status.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED) {
        --next;
        full = true;
        if (!options.quiet && !said_full) {
          std::printf(
              "the server takes no more open jobs from you now (its bound counts all your queued "
              "and running jobs; %d are this batch's); waiting for room\n",
              in_flight());
        }
        said_full = true;  // once: the member lines say how it goes on
        break;
      }
      if (!status.ok()) {
        WriteState(options, *members);
        return connection.Fail("submitting member '" + m.name + "'", status);
      }
      m.job_id = m.job.id();
      WriteState(options, *members);
      if (!options.quiet) std::printf("submitted %s: %s\n", m.job_id.c_str(), m.name.c_str());
      // A request id seen before returns its job, which may have ended.
      if (IsDone(m.job.state())) {
        ++finished;
        if (!options.quiet) {
          std::printf("[%zu/%zu] %s %s: %s\n", finished, to_submit.size(), m.job_id.c_str(),
                      m.name.c_str(), StateName(m.job.state()).c_str());
        }
      }
    }
    bool any_open = false;
    for (RunMember& m : *members) {
      if (m.job_id.empty() || IsDone(m.job.state())) continue;
      v1::GetJobRequest request;
      request.set_id(m.job_id);
      auto context = connection.UnaryContext();
      grpc::Status status = connection.jobs().GetJob(context.get(), request, &m.job);
      if (!status.ok()) return connection.Fail("job " + m.job_id, status);
      if (IsDone(m.job.state())) {
        ++finished;
        if (!options.quiet) {
          std::printf("[%zu/%zu] %s %s: %s%s\n", finished, to_submit.size(), m.job_id.c_str(),
                      m.name.c_str(), StateName(m.job.state()).c_str(),
                      m.job.error().empty() ? "" : (" (" + m.job.error() + ")").c_str());
        }
      } else {
        any_open = true;
      }
    }
    std::fflush(stdout);
    if (!any_open && next >= to_submit.size()) return kExitOk;
    full = false;
    std::this_thread::sleep_for(std::chrono::milliseconds(static_cast<int>(options.poll_s * 1000)));
  }
}

}  // namespace pba::cli
