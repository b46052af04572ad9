#include "service/surface_views.h"

#include <google/protobuf/util/json_util.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <system_error>
#include <utility>

#include "core/atomic_write.h"
#include "core/cache_dir.h"
#include "core/sha256.h"
#include "jobs/solver_process.h"
#include "pba/solve.h"
#include "pba/v1/solve_event.pb.h"
#include "service/atlas_jobs.h"

namespace pba {
namespace fs = std::filesystem;

namespace {

// Scratch folders of builds: hidden, and removed at start (a server that
// died mid-build leaves one).
constexpr char kScratchPrefix[] = ".build-";

// Whether `bytes` are a whole glTF binary: its header ("glTF", version 2)
// and the length the header gives.
bool IsGlb(const std::string& bytes) {
  if (bytes.size() < 12 || bytes.compare(0, 4, "glTF") != 0) return false;
  uint32_t version = 0, length = 0;
  std::memcpy(&version, bytes.data() + 4, 4);
  std::memcpy(&length, bytes.data() + 8, 4);
  return version == 2 && length == bytes.size();
}

// The whole of `path` into *bytes, at most `limit` of them.
bool ReadWhole(const fs::path& path, std::uintmax_t limit, std::string* bytes) {
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec || size > limit) return false;
  std::ifstream in(path, std::ios::binary);
  bytes->assign(static_cast<size_t>(size), '\0');
  in.read(bytes->data(), static_cast<std::streamsize>(size));
  return in.gcount() == static_cast<std::streamsize>(size);
}

// The message of the solver's ERROR event among its stdout lines, else its
// last line of stderr (without "pba-solve: error: ").
std::string SolverMessage(const std::string& error_line, const fs::path& stderr_log) {
  if (!error_line.empty()) {
    v1::SolveEvent event;
    google::protobuf::util::JsonParseOptions options;
    options.ignore_unknown_fields = true;
    if (google::protobuf::util::JsonStringToMessage(error_line, &event, options).ok() &&
        event.kind() == v1::SolveEvent::ERROR && !event.message().empty()) {
      return event.message();
    }
  }
  std::ifstream in(stderr_log);
  std::string line, last;
  while (std::getline(in, line)) {
    if (!line.empty()) last = line;
  }
  const std::string prefix = "pba-solve: error: ";
  if (last.rfind(prefix, 0) == 0) last = last.substr(prefix.size());
  if (last.size() > 1000) last = last.substr(0, 1000) + "...";
  return last;
}

}  // namespace

SurfaceViews::SurfaceViews(SurfaceViewOptions options) : options_(std::move(options)) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(options_.cache_dir, ec)) {
    if (entry.path().filename().string().rfind(kScratchPrefix, 0) == 0) {
      fs::remove_all(entry.path(), ec);
    }
  }
}

std::string SurfaceViews::KeyOf(const std::vector<SnapshotFile>& files) const {
  char facet[64];
  std::snprintf(facet, sizeof facet, "%.17g", options_.facet_mm);
  std::string text =
      std::string("pba-surfaces 1\nsolver ") + SolverVersion() + "\nfacet_mm " + facet + "\n";
  for (const SnapshotFile& file : files) {
    const Revision& r = file.revision;
    text += std::to_string(r.structure.size()) + ":" + r.structure + " " +
            std::to_string(static_cast<int>(r.format)) + " " + r.content_sha256 + "\n";
  }
  return Sha256Hex(text);
}

Status SurfaceViews::Get(const std::string& project, int64_t snapshot,
                         const std::vector<SnapshotFile>& files,
                         const std::function<bool()>& cancelled, SurfaceView* view) {
  *view = SurfaceView();
  if (files.empty()) {
    return Status::FailedPrecondition("there are no structures to draw");
  }
  std::error_code ec;
  fs::create_directories(options_.cache_dir, ec);
  if (ec) return Status::Io("cannot create " + options_.cache_dir.string() + ": " + ec.message());
  view->key = KeyOf(files);
  view->glb = options_.cache_dir / (view->key + ".glb");
  // Read whole at once: a prune by another call may remove the file next.
  const auto hit = [&] {
    if (!fs::is_regular_file(view->glb, ec)) return false;
    if (!ReadWhole(view->glb, options_.cache_bytes, &view->bytes) || !IsGlb(view->bytes)) {
      view->bytes.clear();
      fs::remove(view->glb, ec);
      return false;
    }
    fs::last_write_time(view->glb, fs::file_time_type::clock::now(), ec);
    return true;
  };
  if (hit()) {
    view->cached = true;
    return Status::Ok();
  }
  PBA_RETURN_IF_ERROR(turns_.Acquire(cancelled, options_.patience));
  // Someone else's build of the same key may have ended while this waited.
  Status status = Status::Ok();
  if (hit()) {
    view->cached = true;
  } else {
    const auto start = std::chrono::steady_clock::now();
    status = Build(project, snapshot, files, cancelled, view->glb, &view->bytes);
    view->build_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  turns_.Release();
  if (status.ok()) Prune(view->glb);
  return status;
}

Status SurfaceViews::Build(const std::string& project, int64_t snapshot,
                           const std::vector<SnapshotFile>& files,
                           const std::function<bool()>& cancelled, const fs::path& entry,
                           std::string* bytes) {
  const fs::path scratch = options_.cache_dir / (kScratchPrefix + std::to_string(::getpid()) + "-" +
                                                 std::to_string(builds_.fetch_add(1)));
  struct Remove {
    fs::path path;
    ~Remove() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  } remove{scratch};
  PBA_RETURN_IF_ERROR(WriteStructureSetOf(files, project, snapshot, scratch / "set"));
  char facet[64];
  std::snprintf(facet, sizeof facet, "%g", options_.facet_mm);
  SolverCommand command;
  command.program = options_.solver;
  command.args = {"--atlas-surfaces",
                  (scratch / "set").string(),
                  "--facet-mm",
                  facet,
                  "--out",
                  (scratch / "out").string(),
                  "--progress",
                  "json",
                  "--threads",
                  "1"};
  command.stderr_log = scratch / "stderr.log";
  command.max_address_space_bytes = options_.memory_bytes;
  SolverProcess process;
  PBA_RETURN_IF_ERROR(process.Start(command));
  const auto deadline = std::chrono::steady_clock::now() + options_.time_limit;
  bool timed_out = false, gave_up = false;
  std::string line, error_line;
  for (;;) {
    const SolverProcess::ReadResult read = process.ReadLine(&line, std::chrono::milliseconds(200));
    if (read == SolverProcess::ReadResult::kEnd) break;
    if (read == SolverProcess::ReadResult::kLine && line.find("\"ERROR\"") != std::string::npos) {
      error_line = line;
    }
    if (!timed_out && !gave_up) {
      timed_out = std::chrono::steady_clock::now() >= deadline;
      gave_up = cancelled && cancelled();
      if (timed_out || gave_up) process.Signal(SIGKILL);
    }
  }
  ProcessExit exit;
  while (!process.TryWait(&exit)) ::usleep(10000);
  if (gave_up) return Status::Cancelled("the surfaces' build was cancelled");
  if (timed_out) {
    return Status::InvalidArgument(
        "structures", "meshing the structures' surfaces took longer than " +
                          std::to_string(options_.time_limit.count()) + " s, the server's bound");
  }
  if (exit.signaled || exit.code != 0) {
    std::string why = SolverMessage(error_line, command.stderr_log);
    if (why.empty()) {
      why = exit.signaled
                ? std::string("the solver ended with signal ") + std::to_string(exit.signal)
                : "the solver ended with exit code " + std::to_string(exit.code);
    }
    return Status::InvalidArgument("structures", "the structures' surfaces cannot be made: " + why);
  }
  const fs::path made = scratch / "out" / "surfaces.glb";
  if (!ReadWhole(made, options_.cache_bytes, bytes) || !IsGlb(*bytes)) {
    bytes->clear();
    return Status::Internal("the solver wrote no glTF binary (of at most the cache's " +
                            std::to_string(options_.cache_bytes >> 20) + " MiB) at " +
                            made.string());
  }
  return MoveIntoPlace(made, entry, /*never_replace=*/false);
}

void SurfaceViews::Prune(const fs::path& keep) {
  EvictLeastRecentlyUsed(options_.cache_dir, ".glb", options_.cache_bytes,
                         keep.filename().string());
}

}  // namespace pba
