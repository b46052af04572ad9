#include "commands/batch_plot.h"

#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>

#include "exit_codes.h"
#include "files.h"
#include "io/line_plot.h"
#include "output.h"
#include "transfer.h"

namespace pba::cli {
namespace fs = std::filesystem;
namespace {

// A member's name as a file name: characters other than letters, digits and
// "._-=,+" become "_" (so "/" and spaces never reach the path), and a name
// taken already gets "-2", "-3", ...
std::string FileStem(const std::string& name, std::set<std::string>* taken) {
  std::string stem;
  for (char c : name) {
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                       std::string("._-=,+").find(c) != std::string::npos;
    stem += plain ? c : '_';
  }
  if (stem.empty() || stem == "." || stem == "..") stem = "member";
  std::string unique = stem;
  for (int k = 2; !taken->insert(unique).second; ++k) unique = stem + "-" + std::to_string(k);
  return unique;
}

// Writes a message line to stdout, or to stderr when stdout carries JSON.
void Say(bool quiet, const std::string& line) {
  std::fprintf(quiet ? stderr : stdout, "%s\n", line.c_str());
}

// The member's result file (history.csv or sensors.csv) in `target`: kept
// when it is there with the job's checksum, else downloaded. *fetched says
// which.
int FetchHistory(Connection& connection, const RunMember& m, const v1::ResultFile& file,
                 const fs::path& target, bool* fetched) {
  *fetched = false;
  if (!file.sha256().empty() && fs::exists(target) && Sha256File(target) == file.sha256()) {
    return kExitOk;
  }
  *fetched = true;
  const std::string id = m.job_id;
  return DownloadTo(connection, target, file.size_bytes(), file.sha256(),
                    file.name() + " of member '" + m.name + "' (job " + id + ")",
                    [&](grpc::ClientContext* context, int64_t offset) {
                      v1::DownloadResultRequest request;
                      request.set_job_id(id);
                      request.set_file(file.name());
                      request.set_offset(offset);
                      return connection.jobs().DownloadResult(context, request);
                    });
}

std::string ReadText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

bool MembersWritePlotFile(const std::vector<RunMember>& members, const std::string& file,
                          std::string* error) {
  const bool sensors = file == "sensors.csv";
  for (const RunMember& m : members) {
    const v1::Analysis::Type type = m.scene.analysis().type();
    if (sensors) {
      if (type != v1::Analysis::EXPLICIT_DYNAMIC) {
        *error = "member '" + m.name +
                 "': plot: only an EXPLICIT_DYNAMIC analysis writes the sensors.csv a plot "
                 "draws; this member's analysis.type is " +
                 v1::Analysis::Type_Name(type);
        return false;
      }
      if (m.scene.outputs().sensors().empty()) {
        *error = "member '" + m.name +
                 "': plot: its scene has no outputs.sensors, so it writes no sensors.csv";
        return false;
      }
      continue;
    }
    if (type == v1::Analysis::QUASI_STATIC || type == v1::Analysis::EXPLICIT_DYNAMIC ||
        type == v1::Analysis::DYNAMIC_RELAXATION) {
      continue;
    }
    *error = "member '" + m.name +
             "': plot: only a QUASI_STATIC, EXPLICIT_DYNAMIC or DYNAMIC_RELAXATION analysis "
             "writes the history.csv a plot draws; this member's analysis.type is " +
             v1::Analysis::Type_Name(type);
    return false;
  }
  return true;
}

int DrawBatchPlot(Connection& connection, const PlotSpec& spec,
                  const std::vector<RunMember>& members, const BatchPlotOptions& options) {
  LinePlot plot;
  plot.title = spec.title.empty() ? options.default_title : spec.title;
  plot.x_label = spec.x;
  plot.y_label = PlotYLabel(spec);

  std::error_code ec;
  fs::create_directories(options.histories, ec);
  if (ec) {
    std::fprintf(stderr, "pba: cannot create %s: %s\n", options.histories.c_str(),
                 ec.message().c_str());
    return kExitError;
  }
  std::set<std::string> taken;
  int fetched = 0, reused = 0, left_out = 0;
  for (const RunMember& m : members) {
    const std::string stem = FileStem(m.name, &taken);
    if (m.job.state() != v1::Job::SUCCEEDED) {
      std::fprintf(stderr, "pba: warning: member '%s' (job %s) is %s; left out of the plot\n",
                   m.name.c_str(), m.job_id.c_str(), StateName(m.job.state()).c_str());
      ++left_out;
      continue;
    }
    const v1::ResultFile* file = nullptr;
    for (const v1::ResultFile& f : m.job.result_files()) {
      if (f.name() == spec.file) file = &f;
    }
    if (file == nullptr) {
      std::string has;
      for (const v1::ResultFile& f : m.job.result_files())
        has += (has.empty() ? "" : ", ") + f.name();
      std::fprintf(stderr,
                   "pba: plot: member '%s' (job %s) has no %s (its result files: %s). No plot "
                   "written.\n",
                   m.name.c_str(), m.job_id.c_str(), spec.file.c_str(),
                   has.empty() ? "none" : has.c_str());
      return kExitInvalid;
    }
    const fs::path target = options.histories / (stem + ".csv");
    bool downloaded = false;
    if (const int code = FetchHistory(connection, m, *file, target, &downloaded); code != kExitOk) {
      return code;
    }
    (downloaded ? fetched : reused) += 1;

    HistoryTable table;
    std::string error;
    if (!ParseHistoryCsv(ReadText(target), &table, &error)) {
      std::fprintf(stderr, "pba: plot: %s (member '%s', job %s): %s. No plot written.\n",
                   target.c_str(), m.name.c_str(), m.job_id.c_str(), error.c_str());
      return kExitInvalid;
    }
    if (!AddHistorySeries(spec, m.name, table, &plot, &error)) {
      std::fprintf(stderr, "pba: plot: %s (job %s). No plot written.\n", error.c_str(),
                   m.job_id.c_str());
      return kExitInvalid;
    }
  }
  Say(options.quiet, "Histories in " + options.histories.string() + " (" + std::to_string(fetched) +
                         " fetched, " + std::to_string(reused) +
                         " unchanged since an earlier run)");
  if (plot.series.empty()) {
    Say(options.quiet, "No member succeeded: no plot.");
    return kExitOk;
  }
  if (const Status status = WriteLinePlot(plot, options.png); !status.ok()) {
    std::fprintf(stderr, "pba: plot %s: %s\n", options.png.c_str(), status.ToString().c_str());
    return status.code() == Status::Code::kIo ? kExitError : kExitInvalid;
  }
  Say(options.quiet,
      "Plot written to " + options.png.string() + " (" + std::to_string(plot.series.size()) +
          " series" +
          (left_out > 0 ? ", " + std::to_string(left_out) + " member(s) left out" : std::string()) +
          ")");
  return kExitOk;
}

}  // namespace pba::cli
