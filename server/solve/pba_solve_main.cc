// pba-solve: runs one scene from a file and writes its result directory.
// The server runs every job through it in a child process; scripted users
// call it directly.
//
// The result directory appears whole or not at all (StagingDir), with
// SHA256SUMS, its files' digests, written last (core/checksum_file.h): the
// server checks a result against it before taking it. What is at
// --out is checked before the solve (CheckOutputDir): nothing, an empty
// directory, or with --force an earlier result of pba-solve; never a file,
// a link or a directory holding anything pba-solve does not write. The
// server runs each job into a fresh folder.
//
// Exit codes: the table pba, pba-solve and pba-atlas share (core/exit_codes.h,
// docs/cli.md "Exit codes"): 0 success; 2 bad command line; 5 invalid scene;
// 11 the solve broke down or the scene cannot be solved as posed; 13 I/O
// error; 7 cancelled (SIGTERM/SIGINT); 1 internal error.
//
// Cancel: SIGTERM or SIGINT sets the flag the solver looks at (assembly,
// every conjugate-gradient and Newton iteration, explicit steps, dynamic
// relaxation), so a cancelled solve normally ends with its own "cancelled
// during ..." error. Some phases cannot look: a CHOLMOD or Eigen
// factorisation, CGAL's mesh refinement of an atlas, a library writing a
// file. A watchdog therefore ends the process with exit code 7 (cancelled)
// kCancelGrace after the signal if it is still running, so a cancel never
// waits for the server's SIGKILL. Nothing is lost that was kept: results reach --out
// only by the staging directory's final rename.
//
// The two signals are blocked in every thread and taken by the watchdog
// (sigtimedwait), not by a handler: METIS, which CHOLMOD's ordering calls,
// installs its own SIGTERM handler while it runs and longjmps out of itself
// on the signal, so a cancel during the ordering was swallowed and the
// solve ran on to its end. OpenBLAS starts its threads from a library
// constructor, before main, with the mask they inherit then; so main
// blocks the signals and executes the program again once
// (BlockCancelSignals), and every thread of the new image has them blocked.
//
// SIGXFSZ is ignored: past a file-size limit (ulimit -f) a write fails with
// EFBIG and the solve ends with an I/O error naming the file, instead of the
// process dying without a word.

#include <signal.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "atlas/structure_split.h"
#include "codec/summary_text.h"
#include "codec/yaml_codec.h"
#include "convert/convert.h"
#include "core/checksum_file.h"
#include "core/exit_codes.h"
#include "core/format.h"
#include "pba/solve.h"
#include "pba/v1/scene.pb.h"
#include "pba/v1/solve_event.pb.h"
#include "solve/staging_dir.h"

namespace pba {
namespace {

std::atomic<bool> g_cancel{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void OnSignal(int) { g_cancel.store(true); }

// The signals that cancel a solve.
sigset_t CancelSignals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  return set;
}

// Blocks the cancel signals, and unless they were blocked already (the
// image this exec made) executes the program again with them blocked (see
// the top of the file). One that arrives in between stays pending across
// the exec. Should the exec fail, the program runs on as it is: OnSignal
// then takes the signals in the threads that do not block them.
void BlockCancelSignals(char** argv) {
  sigset_t current;
  ::sigprocmask(SIG_SETMASK, nullptr, &current);
  if (sigismember(&current, SIGTERM) == 1 && sigismember(&current, SIGINT) == 1) return;
  const sigset_t cancel = CancelSignals();
  ::sigprocmask(SIG_BLOCK, &cancel, nullptr);
  // By its own path, not /proc/self/exe, so that the process keeps its
  // name ("pba-solve" in ps, and to the server's tests).
  char self[4096];
  const ssize_t n = ::readlink("/proc/self/exe", self, sizeof self - 1);
  if (n > 0) {
    self[n] = '\0';
    ::execv(self, argv);
  }
  ::execv("/proc/self/exe", argv);
}

// How long a cancelled solve may take to stop by itself before the
// watchdog ends it: well under the second a cancel is promised in, well
// over an assembly chunk or a CG iteration on a large mesh.
constexpr std::chrono::milliseconds kCancelGrace{600};

// Takes the cancel signals, sets the flag, and ends the process
// kCancelGrace later (see the top of the file). A detached thread that
// only waits and reads the flag: no lock is taken, so it cannot deadlock
// with the solve it ends.
void StartCancelWatchdog() {
  std::thread([] {
    const sigset_t cancel = CancelSignals();
    const timespec poll = {0, 25'000'000};
    while (!g_cancel.load()) {
      if (::sigtimedwait(&cancel, nullptr, &poll) > 0) g_cancel.store(true);
    }
    std::this_thread::sleep_for(kCancelGrace);
    static constexpr char kMessage[] =
        "pba-solve: cancelled; the current phase cannot stop by itself (a direct "
        "factorisation, mesh refinement or a file being written), so the process ends here\n";
    [[maybe_unused]] const ssize_t ignored = ::write(STDERR_FILENO, kMessage, sizeof kMessage - 1);
    std::_Exit(kExitCancelled);
  }).detach();
}

enum class ProgressMode { kJson, kText, kNone };

class Reporter {
 public:
  // `who` names the process in error messages ("pba-solve", or with its
  // rank in an MPI job).
  explicit Reporter(ProgressMode mode, std::string who = "pba-solve")
      : mode_(mode), who_(std::move(who)) {}

  void Progress(const ProgressEvent& event) {
    if (mode_ == ProgressMode::kJson) {
      v1::SolveEvent out;
      out.set_kind(v1::SolveEvent::PROGRESS);
      out.set_phase(event.phase);
      out.set_progress(event.fraction);
      out.set_message(event.message);
      Emit(out);
    } else if (mode_ == ProgressMode::kText) {
      std::printf("[%3d%%] %-9s %s\n", static_cast<int>(event.fraction * 100 + 0.5),
                  event.phase.c_str(), event.message.c_str());
      std::fflush(stdout);
    }
  }

  void Done(const std::string& out_dir, const v1::Summary& summary) {
    if (mode_ == ProgressMode::kJson) {
      v1::SolveEvent out;
      out.set_kind(v1::SolveEvent::DONE);
      out.set_progress(1.0);
      out.set_message(out_dir);
      Emit(out);
    } else if (mode_ == ProgressMode::kText) {
      std::printf("\n%s\nResult in %s (open result.xdmf in ParaView)\n",
                  codec::FormatSummary(summary).c_str(), out_dir.c_str());
    }
  }

  // Errors always reach stderr for people; in JSON mode also stdout for the server.
  int Error(const Status& status) {
    std::fprintf(stderr, "%s: error: %s\n", who_.c_str(), status.ToString().c_str());
    if (mode_ == ProgressMode::kJson) {
      v1::SolveEvent out;
      out.set_kind(v1::SolveEvent::ERROR);
      out.set_code(CodeName(status.code()));
      out.set_field(status.field());
      out.set_message(status.ToString());
      Emit(out);
    }
    return ExitCodeForStatus(status.code(), kExitNumerical);
  }

 private:
  static const char* CodeName(Status::Code code) {
    switch (code) {
      case Status::Code::kInvalidArgument:
        return "INVALID_ARGUMENT";
      case Status::Code::kFailedPrecondition:
        return "FAILED_PRECONDITION";
      case Status::Code::kNumerical:
        return "NUMERICAL";
      case Status::Code::kIo:
        return "IO";
      case Status::Code::kCancelled:
        return "CANCELLED";
      default:
        return "INTERNAL";
    }
  }

  static void Emit(const v1::SolveEvent& event) {
    std::printf("%s\n", codec::ToJsonLine(event).c_str());
    std::fflush(stdout);
  }

  ProgressMode mode_;
  std::string who_;
};

// Whether `entry` of an output directory is something pba-solve writes
// there (an earlier result): summary.json, result.h5 and .xdmf,
// history.csv and .png, sensors.csv, profile_<name>.csv, and an import's
// structures/ folder holding nothing but structure files (.json, .nii.gz).
bool WrittenByPbaSolve(const std::filesystem::directory_entry& entry) {
  namespace fs = std::filesystem;
  const auto ends_with = [](const std::string& text, const std::string& end) {
    return text.size() >= end.size() &&
           text.compare(text.size() - end.size(), end.size(), end) == 0;
  };
  std::error_code ec;
  const std::string name = entry.path().filename().string();
  if (entry.is_symlink(ec)) return false;
  if (entry.is_regular_file(ec)) {
    for (const char* known :
         {"summary.json", "result.h5", "result.xdmf", "surfaces.glb", "surface_steps.bin",
          "history.csv", "history.png", "sensors.csv", kChecksumFileName}) {
      if (name == known) return true;
    }
    return name.rfind("profile_", 0) == 0 && ends_with(name, ".csv");
  }
  if (!entry.is_directory(ec) || name != "structures") return false;
  for (const fs::directory_entry& inner : fs::directory_iterator(entry.path(), ec)) {
    const std::string file = inner.path().filename().string();
    if (inner.is_symlink(ec) || !inner.is_regular_file(ec)) return false;
    if (!ends_with(file, ".json") && !ends_with(file, ".nii.gz")) return false;
  }
  return !ec;
}

Status WriteText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  out.close();
  if (!out) return Status::Io("cannot write " + path.string());
  return Status::Ok();
}

// --atlas-cache: where built atlas meshes are shared between solves.
struct AtlasCacheFlags {
  std::string dir;   // empty: no cache
  double gib = 2.0;  // the directory's bound
};

// --checkpoint, --checkpoint-every, --restart (QUASI_STATIC).
struct CheckpointFlags {
  std::string dir;      // empty: no checkpoints
  double every_s = 30;  // at most this often [s of wall time]
  std::string restart;  // a checkpoint.h5 to continue from; empty: from t = 0
};

// In an MPI job (mpirun -np N pba-solve) every rank runs this with the same
// arguments and solves the same scene, sharing its linear solves; rank 0
// alone reports progress, checks and writes --out, --export-inp and the
// checkpoints, and the other ranks end once the solve has. Their errors go
// to stderr under their rank.
int Run(const std::string& scene_path, const std::string& out_dir, bool force,
        const std::string& inp_path, ProgressMode mode, int threads, const AtlasCacheFlags& cache,
        CheckpointFlags checkpoint, const SolveRanks& ranks) {
  const bool writer = ranks.rank == 0;
  Reporter reporter(writer ? mode : ProgressMode::kNone,
                    ranks.size > 1 ? Format("pba-solve (rank %d of %d)", ranks.rank, ranks.size)
                                   : std::string("pba-solve"));
  // Before anything is solved: a solve of hours must not end in a refusal.
  if (writer && !out_dir.empty()) {
    if (Status s = CheckOutputDir(out_dir, force, "pba-solve", WrittenByPbaSolve); !s.ok()) {
      return reporter.Error(s);
    }
  }

  v1::Scene scene;
  codec::ParseError parse_error;
  if (!codec::ReadYamlFile(scene_path, &scene, &parse_error)) {
    return reporter.Error(Status::InvalidArgument(parse_error.field, parse_error.ToString()));
  }
  SceneSpec spec;
  Status status = SceneFromProto(scene, &spec);
  // Structure names checked against the atlas the scene is built from.
  if (status.ok() && spec.geometry.kind == GeometrySpec::Kind::kAtlas) {
    spec.geometry.atlas.known_structures = KnownAtlasStructures(spec.geometry.atlas);
  }
  if (status.ok()) status = ValidateScene(spec);
  if (!status.ok()) return reporter.Error(status);
  if (writer && !inp_path.empty()) {
    status = ExportAbaqusInput(spec, inp_path);
    if (!status.ok()) return reporter.Error(status);
    std::fprintf(stderr, "pba-solve: wrote %s (run it in CalculiX with: ccx -i %s)\n",
                 inp_path.c_str(), std::filesystem::path(inp_path).replace_extension().c_str());
    if (spec.mesh.adapt.enabled()) {
      std::fprintf(stderr,
                   "pba-solve: note: the deck holds the scene's first mesh; mesh.adapt refines "
                   "it only while solving\n");
    }
  }
  if (out_dir.empty()) return kExitOk;
  if (!writer) checkpoint.dir.clear();

  SolveOptions options;
  options.threads = threads;
  options.cancel = &g_cancel;
  options.progress = [&reporter](const ProgressEvent& event) { reporter.Progress(event); };
  options.checkpoint_dir = checkpoint.dir;
  options.checkpoint_every_s = checkpoint.every_s;
  options.restart_from = checkpoint.restart;
  if (!cache.dir.empty()) {
    // A cache that cannot be made costs this solve its speed-up, not its
    // result.
    std::error_code ec;
    std::filesystem::create_directories(cache.dir, ec);
    if (ec) {
      std::fprintf(stderr, "pba-solve: not using the atlas cache %s: %s\n", cache.dir.c_str(),
                   ec.message().c_str());
    } else {
      options.atlas_cache_dir = cache.dir;
      options.atlas_cache_max_bytes = static_cast<std::uint64_t>(cache.gib * 1024 * 1024 * 1024);
    }
  }

  Solution solution;
  status = SolveScene(spec, options, &solution);
  if (!status.ok()) return reporter.Error(status);
  if (!writer) return kExitOk;

  StagingDir staging;
  status = StagingDir::Create(out_dir, &staging);
  if (!status.ok()) return reporter.Error(status);
  status = WriteResultFiles(spec, &solution, staging.path());
  if (!status.ok()) return reporter.Error(status);
  const v1::Summary summary = SummaryToProto(solution.summary);
  status = WriteText(staging.path() / "summary.json", codec::ToJson(summary));
  if (!status.ok()) return reporter.Error(status);
  status = WriteChecksumFile(staging.path());
  if (!status.ok()) return reporter.Error(status);
  if (g_cancel.load())
    return reporter.Error(Status::Cancelled("cancelled before the result was saved"));
  status = staging.Commit();
  if (!status.ok()) return reporter.Error(status);

  reporter.Done(std::filesystem::absolute(out_dir).lexically_normal().string(), summary);
  return kExitOk;
}

// The atlas import's half that runs in a child process: the source split
// into a structure set, <out>/structures/ (structure_split.h), with a
// summary.json saying what was found.
struct ImportArgs {
  std::string kind;  // synthetic, plates, labels
  std::string source;
  std::string colour_table;
  std::vector<std::string> structures;
};

int RunImport(const ImportArgs& args, const std::string& out_dir, bool force, ProgressMode mode) {
  Reporter reporter(mode);
  if (Status s = CheckOutputDir(out_dir, force, "pba-solve", WrittenByPbaSolve); !s.ok()) {
    return reporter.Error(s);
  }
  const auto start = std::chrono::steady_clock::now();
  SplitOptions options;
  if (args.kind == "synthetic") {
    options.source.source = AtlasBuildOptions::Source::kSynthetic;
  } else if (args.kind == "plates") {
    options.source.source = AtlasBuildOptions::Source::kPlates;
  } else {
    options.source.source = AtlasBuildOptions::Source::kLabelVolume;
    options.source.colour_table = args.colour_table;
  }
  options.source.input = args.source;
  options.structures = args.structures;
  if (args.kind != "synthetic" && args.source.empty()) {
    return reporter.Error(Status::InvalidArgument("import-source", "required for " + args.kind));
  }
  reporter.Progress({"split", 0.0, "splitting the atlas into structures"});
  StagingDir staging;
  Status status = StagingDir::Create(out_dir, &staging);
  if (!status.ok()) return reporter.Error(status);
  SplitResult result;
  status = SplitAtlas(options, staging.path() / "structures", &result);
  if (!status.ok()) return reporter.Error(status);
  if (g_cancel.load()) return reporter.Error(Status::Cancelled("cancelled"));

  v1::Summary summary;
  summary.set_scene_name("atlas import");
  summary.set_solver_version(SolverVersion());
  const int n = static_cast<int>(result.set.structures.size());
  summary.mutable_modelled()->set_geometry(
      std::to_string(n) + " structure" + (n == 1 ? "" : "s") + " from " +
      (args.kind == "synthetic" ? std::string("the synthetic atlas")
       : args.kind == "plates"  ? "plates, as plate contours"
                                : "a label volume, as label masks"));
  for (const std::string& name : result.absent) {
    summary.mutable_modelled()->add_notes("absent from the source (not imported): " + name);
  }
  summary.mutable_performance()->set_wall_time_s(
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  status = WriteText(staging.path() / "summary.json", codec::ToJson(summary));
  if (status.ok()) status = WriteChecksumFile(staging.path());
  if (!status.ok()) return reporter.Error(status);
  status = staging.Commit();
  if (!status.ok()) return reporter.Error(status);
  reporter.Done(std::filesystem::absolute(out_dir).lexically_normal().string(), summary);
  return kExitOk;
}

// The structures' surfaces a view draws (pba-server's DownloadSurfaces):
// the structure set in `set_dir` meshed as a job's atlas is, at
// `facet_mm`, without sliver removal, improvement or validation (no one
// solves on these tetrahedra; their surface triangles are the same), and
// each structure's outer and interface triangles written to
// <out>/surfaces.glb (surface_gltf.h), with a summary.json.
int RunAtlasSurfaces(const std::string& set_dir, double facet_mm, const std::string& out_dir,
                     bool force, ProgressMode mode) {
  Reporter reporter(mode);
  if (Status s = CheckOutputDir(out_dir, force, "pba-solve", WrittenByPbaSolve); !s.ok()) {
    return reporter.Error(s);
  }
  const auto start = std::chrono::steady_clock::now();
  reporter.Progress({"mesh", 0.0, "meshing the structures' surfaces"});
  AtlasSurfaces surfaces;
  if (Status s = MeshAtlasSurfaces(set_dir, facet_mm, &surfaces); !s.ok()) {
    return reporter.Error(s);
  }
  if (g_cancel.load()) return reporter.Error(Status::Cancelled("cancelled"));
  StagingDir staging;
  Status status = StagingDir::Create(out_dir, &staging);
  if (status.ok()) status = WriteText(staging.path() / "surfaces.glb", surfaces.glb);

  v1::Summary summary;
  summary.set_scene_name("atlas surfaces");
  summary.set_solver_version(SolverVersion());
  summary.mutable_modelled()->set_geometry(
      Format("%d structures' surfaces, %lld triangles, facets of at most %g mm",
             surfaces.structures, static_cast<long long>(surfaces.triangles), facet_mm));
  // (The build's notes are about its tetrahedra's quality, which a view
  // does not ask for.)
  summary.mutable_performance()->set_wall_time_s(
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (status.ok()) status = WriteText(staging.path() / "summary.json", codec::ToJson(summary));
  if (status.ok()) status = WriteChecksumFile(staging.path());
  if (status.ok() && g_cancel.load()) status = Status::Cancelled("cancelled before writing");
  if (status.ok()) status = staging.Commit();
  if (!status.ok()) return reporter.Error(status);
  const std::string written = std::filesystem::absolute(out_dir).lexically_normal().string();
  if (mode == ProgressMode::kText) {
    std::printf("wrote %s/surfaces.glb: %s, in %.2f s\n", written.c_str(),
                summary.modelled().geometry().c_str(), summary.performance().wall_time_s());
  } else {
    reporter.Done(written, summary);
  }
  return kExitOk;
}

}  // namespace
}  // namespace pba

int main(int argc, char** argv) {
  // First, before anything is printed or started.
  pba::BlockCancelSignals(argv);
  CLI::App app{"pba-solve: run one PBA scene and write result.h5, result.xdmf and summary.json"};
  app.set_version_flag("--version", std::string("pba-solve ") + pba::SolverVersion());
  std::string scene_path;
  std::string out_dir;
  std::string progress = "auto";
  int threads = 0;
  app.add_option("scene", scene_path, "Scene file (YAML or JSON, see docs/scene-reference.md)");
  pba::ImportArgs import;
  app.add_option("--import-atlas", import.kind,
                 "Instead of a scene: split an atlas into a structure set in OUT/structures "
                 "(the server's atlas import)")
      ->check(CLI::IsMember({"synthetic", "plates", "labels"}));
  app.add_option("--import-source", import.source,
                 "--import-atlas plates: the plate directory; labels: the label volume");
  app.add_option("--colour-table", import.colour_table,
                 "--import-atlas labels: the label table (CSV); default the built-in one");
  app.add_option("--structure", import.structures,
                 "--import-atlas: keep only this structure (repeatable; group prefixes allowed)");
  std::string surfaces_of;
  app.add_option("--atlas-surfaces", surfaces_of,
                 "Instead of a scene: mesh this structure set's surfaces into OUT/surfaces.glb "
                 "(what the web view draws of a project's structures)");
  double surfaces_facet_mm = 3;
  app.add_option("--facet-mm", surfaces_facet_mm,
                 "--atlas-surfaces: triangle size on surfaces and interfaces [mm]")
      ->check(CLI::Range(0.5, 50.0))
      ->capture_default_str();
  std::string inp_path;
  app.add_option("-o,--out", out_dir,
                 "Result directory (created; must not exist or be empty, or with --force hold "
                 "an earlier result)");
  bool force = false;
  app.add_flag("--force", force,
               "Replace an earlier result at --out (never a directory with other files)");
  app.add_option("--export-inp", inp_path,
                 "Write the model as an Abaqus input deck that CalculiX runs (SI units); "
                 "without --out, export only");
  app.add_option("--progress", progress,
                 "Progress on stdout: json (one pba.v1.SolveEvent per line), text, none, or auto "
                 "(text on a terminal, json otherwise)")
      ->check(CLI::IsMember({"auto", "json", "text", "none"}));
  app.add_option("--threads", threads,
                 "Threads the solve may use, its libraries' (CHOLMOD, OpenBLAS) included; 0 "
                 "uses every core")
      ->check(CLI::NonNegativeNumber);
  pba::AtlasCacheFlags cache;
  app.add_option("--atlas-cache", cache.dir,
                 "Directory of built atlas meshes shared between solves (created if absent): a "
                 "4-node atlas scene whose atlas and mesh options match an entry takes its mesh");
  app.add_option("--atlas-cache-size", cache.gib,
                 "Bound of the --atlas-cache directory [GiB]; least recently used meshes go")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  pba::CheckpointFlags checkpoint;
  app.add_option("--checkpoint", checkpoint.dir,
                 "QUASI_STATIC: write DIR/checkpoint.h5 (created if absent) after converged time "
                 "steps and after the last, so that an interrupted run can be resumed (--restart)");
  app.add_option("--checkpoint-every", checkpoint.every_s,
                 "Wall time between two checkpoints at least [s]; 0 writes after every step")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--restart", checkpoint.restart,
                 "QUASI_STATIC: continue from this checkpoint.h5 (same mesh, materials, "
                 "constraints and contacts; the time curve may run further)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? pba::kExitOk : pba::kExitUsage;
  }

  // In an MPI job every rank starts MPI here, before any thread of its own.
  pba::SolveRanks ranks;
  if (const pba::Status joined = pba::JoinRanks(&ranks); !joined.ok()) {
    std::fprintf(stderr, "pba-solve: error: %s\n", joined.ToString().c_str());
    return pba::kExitError;
  }
  if (ranks.size > 1 && threads == 0) {
    // "Every core" is the machine's cores shared by its ranks.
    threads = std::max(1, static_cast<int>(std::thread::hardware_concurrency()) / ranks.on_node);
  }

  std::signal(SIGTERM, pba::OnSignal);
  std::signal(SIGINT, pba::OnSignal);
  std::signal(SIGXFSZ, SIG_IGN);
  pba::StartCancelWatchdog();

  pba::ProgressMode mode = pba::ProgressMode::kJson;
  if (progress == "text" || (progress == "auto" && ::isatty(STDOUT_FILENO))) {
    mode = pba::ProgressMode::kText;
  } else if (progress == "none") {
    mode = pba::ProgressMode::kNone;
  }
  try {
    if (!surfaces_of.empty()) {
      if (!scene_path.empty() || !import.kind.empty() || out_dir.empty() || ranks.size > 1) {
        std::fprintf(stderr,
                     "pba-solve: --atlas-surfaces takes --out DIR, no scene and no import, as "
                     "one process\n");
        pba::EndRanksWith(pba::kExitUsage);
        return pba::kExitUsage;
      }
      return pba::RunAtlasSurfaces(surfaces_of, surfaces_facet_mm, out_dir, force, mode);
    }
    if (!import.kind.empty()) {
      if (!scene_path.empty() || out_dir.empty()) {
        std::fprintf(stderr, "pba-solve: --import-atlas takes --out DIR and no scene\n");
        return pba::kExitUsage;
      }
      if (ranks.size > 1) {
        std::fprintf(stderr, "pba-solve: --import-atlas runs as one process, not under mpirun\n");
        pba::EndRanksWith(pba::kExitUsage);
        return pba::kExitUsage;
      }
      return pba::RunImport(import, out_dir, force, mode);
    }
    if (scene_path.empty()) {
      std::fprintf(stderr, "pba-solve: a scene file is required\n");
      return pba::kExitUsage;
    }
    if (out_dir.empty() && inp_path.empty()) {
      std::fprintf(stderr,
                   "pba-solve: --out DIR is required (or --export-inp FILE to export only)\n");
      return pba::kExitUsage;
    }
    const int code =
        pba::Run(scene_path, out_dir, force, inp_path, mode, threads, cache, checkpoint, ranks);
    // A rank that failed ends the job: the others may wait for it.
    if (code != pba::kExitOk) pba::EndRanksWith(code);
    return code;
  } catch (const std::bad_alloc&) {
    // Past its address-space limit (pba-server --solver-memory, ulimit -v)
    // or the machine's memory: said so, for the server as an ERROR event.
    struct rlimit limit {};
    std::string what = "out of memory: the model needs more memory than this process may use";
    if (::getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY) {
      what += " (its address-space limit is " + std::to_string(limit.rlim_cur >> 20) + " MiB)";
    }
    const int code = pba::Reporter(mode).Error(pba::Status::Internal(what));
    pba::EndRanksWith(code);
    return code;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pba-solve: internal error: %s\n", e.what());
    pba::EndRanksWith(pba::kExitError);
    return pba::kExitError;
  }
}
