// pba-server: the PBA gRPC server.
//
//   pba-server --data DIR [--listen HOST:PORT] [--solver PATH] [--max-running N]
//              [--log-level LEVEL] [--tls-cert PEM --tls-key PEM] [--insecure]
//   pba-server admin create-user NAME [--server-admin] --data DIR
//   pba-server admin disable-user NAME --data DIR
//   pba-server admin enable-user NAME --data DIR
//
// The admin forms work offline on the data directory (the server may be
// running: it reads users from the database on every call, so a disabled
// user's token is refused from their next call on). create-user prints the
// new token once on stdout; only its hash is kept. On the first start the
// server creates the user "admin" itself, a server admin, with the token in
// DIR/admin.token.
//
// Everything runs under umask 077 and the data directory is made 0700:
// the database, blobs, uploads and job files are the server user's alone.
// Plaintext on an address that is not loopback is refused unless
// --insecure (pba_server.h).
//
// Prints "pba-server listening on HOST:PORT" once it accepts calls and writes
// DIR/server.json ({"address": ..., "pid": ...}) for scripts; SIGTERM or
// SIGINT shut it down cleanly (running jobs are re-queued) with exit code 0.
#include <signal.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <system_error>
#include <thread>

#include "app/pba_server.h"
#include "core/atomic_write.h"
#include "jobs/solver_process.h"
#include "store/atlas_store.h"

namespace {

namespace fs = std::filesystem;

// The data directory's store, opened by an admin command (and the
// directory made private, as the server makes it).
pba::Status OpenStore(const std::string& data_dir, std::unique_ptr<pba::AtlasStore>* store) {
  PBA_RETURN_IF_ERROR(pba::AtlasStore::Open(data_dir, store));
  return pba::RestrictDataDir(data_dir);
}

int CreateUser(const std::string& data_dir, const std::string& name, bool server_admin) {
  std::unique_ptr<pba::AtlasStore> store;
  pba::Status status = OpenStore(data_dir, &store);
  std::string token;
  if (status.ok()) status = store->CreateUser(name, &token, server_admin);
  if (!status.ok()) {
    std::cerr << "pba-server admin create-user: " << status.ToString() << std::endl;
    return 1;
  }
  std::cerr << "created " << (server_admin ? "server admin" : "atlas user") << " '" << name
            << "'; its token follows (shown only now; send it as "
               "'authorization: Bearer <token>')"
            << std::endl;
  std::cout << token << std::endl;
  return 0;
}

int SetDisabled(const std::string& data_dir, const std::string& name, bool disabled) {
  const char* command = disabled ? "disable-user" : "enable-user";
  std::unique_ptr<pba::AtlasStore> store;
  pba::Status status = OpenStore(data_dir, &store);
  bool changed = false;
  if (status.ok()) status = store->SetUserDisabled(name, disabled, &changed);
  if (!status.ok()) {
    std::cerr << "pba-server admin " << command << ": " << status.ToString() << std::endl;
    return 1;
  }
  const char* state = disabled ? "disabled" : "enabled";
  if (!changed) {
    std::cerr << "user '" << name << "' was already " << state << std::endl;
  } else if (disabled) {
    std::cerr << "disabled user '" << name
              << "': their token is refused from their next call on, also by a running server; "
                 "their locks stay until their leases lapse or a project admin breaks them"
              << std::endl;
  } else {
    std::cerr << "enabled user '" << name << "' again: their token works again" << std::endl;
  }
  return 0;
}

// The folder this executable is in (the current one if unknown).
fs::path ExecutableDir() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::current_path() : self.parent_path();
}

fs::path DefaultSolver() { return ExecutableDir() / "pba-solve"; }

// The first `name` in a directory of PATH that is an executable file; empty
// when there is none.
fs::path FindInPath(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string dirs = path != nullptr ? path : "/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t end = std::min(dirs.find(':', start), dirs.size());
    const fs::path candidate = fs::path(dirs.substr(start, end - start)) / name;
    if (end > start && ::access(candidate.c_str(), X_OK) == 0) return candidate;
    start = end + 1;
  }
  return {};
}

// The serving options as given on the command line (defaults as shown by
// --help).
struct ServeFlags {
  std::string data_dir;
  std::string listen = "127.0.0.1:50051";
  std::string solver;
  int max_running = 1;
  double atlas_cache_gib = 2.0;
  double surface_cache_mib = 512;
  std::string log_level = "info";
  std::string tls_cert, tls_key;
  bool insecure = false;
  int64_t max_job_time_s = pba::kDefaultMaxJobTime.count();
  int max_attempts = 3;
  double solver_memory_gib = -1;  // < 0: DefaultSolverMemoryBytes
  double upload_quota_gib = 4;
  double keep_results_days = 30;
  int max_ranks = 0;        // 0: the machine's cores
  std::string mpirun = "";  // empty: mpirun from PATH; "none": no MPI
  std::string executor = "local";
  std::string job_dir;
  std::string slurm_partition, slurm_account;
  int slurm_cpus = 1;
  int slurm_max_jobs = 1000;
  int slurm_array_min = 10;
  double slurm_poll_s = 2;
  double slurm_gather_s = 1;
  double slurm_settle_s = 60;
  int max_open_jobs = pba::kDefaultMaxOpenJobs;
  std::string http;
  std::string web_root;
};

void AddServeOptions(CLI::App& app, ServeFlags* flags) {
  app.add_option("--data", flags->data_dir, "Data directory (pba.db, jobs/); created if absent");
  app.add_option("--listen", flags->listen, "HOST:PORT to listen on; port 0 picks a free port")
      ->capture_default_str();
  app.add_option("--solver", flags->solver, "pba-solve executable (default: next to pba-server)");
  app.add_option("--max-running", flags->max_running, "Jobs run at the same time")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--atlas-cache-size", flags->atlas_cache_gib,
                 "Bound of <data>/cache/atlas, the built atlas meshes solves share [GiB]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--surface-cache-size", flags->surface_cache_mib,
                 "Bound of <data>/cache/surfaces, the structures' surfaces the web view draws "
                 "[MiB]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--log-level", flags->log_level,
                 "trace, debug, info, warn, error, critical or off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}))
      ->capture_default_str();
  app.add_option("--tls-cert", flags->tls_cert,
                 "PEM certificate (chain) to serve TLS with; needs --tls-key");
  app.add_option("--tls-key", flags->tls_key, "PEM private key of --tls-cert");
  app.add_flag("--insecure", flags->insecure,
               "Allow plaintext on an address that is not loopback (tokens then cross the "
               "network in the clear)");
  app.add_option("--max-job-time", flags->max_job_time_s,
                 "Wall-clock limit of a job [s]; a job may ask for less; 0: none")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--max-attempts", flags->max_attempts,
                 "Starts of a job (restarts re-queue running jobs) before it is given up")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  app.add_option("--solver-memory", flags->solver_memory_gib,
                 "Address-space limit of each pba-solve [GiB]; 0: none (default: 3/4 of the "
                 "physical memory divided by --max-running)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--upload-quota", flags->upload_quota_gib,
                 "Bytes one user's unfinished uploads may announce together [GiB]; 0: no quota")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--keep-results", flags->keep_results_days,
                 "Days a finished job's files are kept; 0: forever")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--max-ranks", flags->max_ranks,
                 "MPI ranks a job may ask for (pba job submit --ranks), run through mpirun on "
                 "this machine; 0: its cores")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--mpirun", flags->mpirun,
                 "The mpirun that runs jobs on several ranks (default: mpirun from PATH); "
                 "\"none\": every job runs as one process");
  app.add_option("--executor", flags->executor,
                 "Where jobs run: local (children of this server) or slurm (Slurm jobs, "
                 "submitted with sbatch; the server can run on a login node)")
      ->check(CLI::IsMember({"local", "slurm"}))
      ->capture_default_str();
  app.add_option("--job-dir", flags->job_dir,
                 "Job folders (default: <data>/jobs); with --executor slurm a directory every "
                 "compute node sees at the same path");
  app.add_option("--slurm-partition", flags->slurm_partition,
                 "Slurm partition of the jobs (default: Slurm's default)");
  app.add_option("--slurm-account", flags->slurm_account,
                 "Slurm account the jobs are charged to (default: the user's)");
  app.add_option("--slurm-cpus", flags->slurm_cpus,
                 "CPUs of each job's rank (--cpus-per-task; pba-solve --threads)")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  app.add_option("--slurm-max-jobs", flags->slurm_max_jobs,
                 "Jobs in Slurm's hands at once; the rest wait in PBA's queue")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  app.add_option("--slurm-array-min", flags->slurm_array_min,
                 "Jobs with the same limits handed to Slurm together go as one job array when "
                 "there are at least this many (0: each its own Slurm job)")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  app.add_option("--slurm-poll", flags->slurm_poll_s, "Seconds between two looks at squeue")
      ->check(CLI::Range(0.1, 600.0))
      ->capture_default_str();
  app.add_option("--slurm-gather", flags->slurm_gather_s,
                 "Seconds the queue must be quiet after a submit before its jobs go to Slurm, "
                 "so that a sweep submitted job by job goes as one array (at most 10 times "
                 "this after the first); 0: at once")
      ->check(CLI::Range(0.0, 60.0))
      ->capture_default_str();
  app.add_option("--slurm-settle", flags->slurm_settle_s,
                 "Seconds a job Slurm completed may take to show its exit code and every file "
                 "of its result here (a shared filesystem may show a node's writes late) "
                 "before it is judged on what is there")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  app.add_option("--http", flags->http,
                 "HOST:PORT of the web view (the atlas, its locks and history, the jobs and "
                 "their results in a browser); port 0 picks a free one; TLS as --tls-cert");
  app.add_option("--web-root", flags->web_root,
                 "The web view's files (default: share/pba/web beside the binaries)");
  app.add_option("--max-open-jobs", flags->max_open_jobs,
                 "Jobs one user may have queued or running at once; a submit beyond is refused "
                 "(RESOURCE_EXHAUSTED); 0: no bound")
      ->check(CLI::Range(0, 100000000))
      ->capture_default_str();
}

// `pba-server admin ...`: the subcommands and what they were given.
struct AdminCommands {
  CLI::App* create_user = nullptr;
  CLI::App* disable_user = nullptr;
  CLI::App* enable_user = nullptr;
  std::string user;
  std::string data_dir;
  bool server_admin = false;
};

void AddAdminCommands(CLI::App& app, AdminCommands* commands) {
  CLI::App* admin = app.add_subcommand("admin", "Offline administration of the data directory");
  admin->require_subcommand(1);
  CLI::App* create_user =
      admin->add_subcommand("create-user", "Create a user and print its token once");
  create_user->add_option("name", commands->user, "The user's name")->required();
  create_user->add_option("--data", commands->data_dir, "Data directory")->required();
  create_user->add_flag("--server-admin", commands->server_admin,
                        "A server admin: sees and cancels every job, of every project");
  CLI::App* disable_user = admin->add_subcommand(
      "disable-user", "Refuse a user's token from their next call on (also a running server's)");
  disable_user->add_option("name", commands->user, "The user's name")->required();
  disable_user->add_option("--data", commands->data_dir, "Data directory")->required();
  CLI::App* enable_user =
      admin->add_subcommand("enable-user", "Accept a disabled user's token again");
  enable_user->add_option("name", commands->user, "The user's name")->required();
  enable_user->add_option("--data", commands->data_dir, "Data directory")->required();
  commands->create_user = create_user;
  commands->disable_user = disable_user;
  commands->enable_user = enable_user;
}

// Block the shutdown signals before any thread starts, so every thread
// inherits the mask and only sigwait() in Serve sees them: no work happens in
// a signal handler. (Children unblock them again before exec.) Returns them.
sigset_t BlockShutdownSignals() {
  sigset_t shutdown_signals;
  sigemptyset(&shutdown_signals);
  sigaddset(&shutdown_signals, SIGTERM);
  sigaddset(&shutdown_signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &shutdown_signals, nullptr);
  // A client vanishing mid-write must not kill the server.
  signal(SIGPIPE, SIG_IGN);
  // Past a file-size limit (ulimit -f) a write must fail with EFBIG and
  // become an error naming the file, not end the server.
  signal(SIGXFSZ, SIG_IGN);
  return shutdown_signals;
}

pba::ServerOptions ServerOptionsFromFlags(const ServeFlags& flags) {
  pba::ServerOptions options;
  options.data_dir = flags.data_dir;
  options.listen = flags.listen;
  options.solver = flags.solver.empty() ? DefaultSolver() : fs::path(flags.solver);
  options.max_running = flags.max_running;
  options.atlas_cache_gib = flags.atlas_cache_gib;
  options.surface_cache_mib = flags.surface_cache_mib;
  options.tls_cert = flags.tls_cert;
  options.tls_key = flags.tls_key;
  options.insecure = flags.insecure;
  options.max_job_time = std::chrono::seconds(flags.max_job_time_s);
  options.max_attempts = flags.max_attempts;
  const bool slurm = flags.executor == "slurm";
  // This machine's memory says nothing of a compute node's: under Slurm
  // the default is none (the partition's own), and a limit given is also
  // the job's --mem.
  options.max_solver_memory_bytes =
      flags.solver_memory_gib < 0 ? (slurm ? 0 : pba::DefaultSolverMemoryBytes(flags.max_running))
                                  : static_cast<int64_t>(flags.solver_memory_gib * (1LL << 30));
  if (slurm) options.executor = pba::ServerOptions::ExecutorKind::kSlurm;
  options.jobs_dir = flags.job_dir;
  options.slurm.partition = flags.slurm_partition;
  options.slurm.account = flags.slurm_account;
  options.slurm.cpus_per_task = flags.slurm_cpus;
  options.slurm.max_submitted = flags.slurm_max_jobs;
  options.slurm.array_min = flags.slurm_array_min;
  options.slurm.poll = std::chrono::milliseconds(static_cast<int64_t>(flags.slurm_poll_s * 1000));
  options.slurm.gather =
      std::chrono::milliseconds(static_cast<int64_t>(flags.slurm_gather_s * 1000));
  options.slurm.settle =
      std::chrono::milliseconds(static_cast<int64_t>(flags.slurm_settle_s * 1000));
  options.max_open_jobs = flags.max_open_jobs;
  options.http_listen = flags.http;
  options.web_app_dir = flags.web_root.empty() ? ExecutableDir() / ".." / "share" / "pba" / "web"
                                               : fs::path(flags.web_root);
  options.upload_quota_bytes = static_cast<int64_t>(flags.upload_quota_gib * (1LL << 30));
  options.keep_results =
      std::chrono::seconds(static_cast<int64_t>(flags.keep_results_days * 86400));
  const int cores = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  options.max_ranks = flags.max_ranks > 0 ? flags.max_ranks : cores;
  if (flags.mpirun != "none") {
    options.mpirun = flags.mpirun.empty() ? FindInPath("mpirun") : fs::path(flags.mpirun);
  }
  // Parallel solves share the cores rather than each taking all of them.
  if (flags.max_running > 1) {
    options.solver_threads =
        std::max(1, static_cast<int>(std::thread::hardware_concurrency()) / flags.max_running);
  }
  return options;
}

// Starts the server, announces it (stdout, DIR/server.json, the log) and
// serves until one of `shutdown_signals` arrives. The exit code.
int Serve(const ServeFlags& flags, const sigset_t& shutdown_signals) {
  const pba::ServerOptions options = ServerOptionsFromFlags(flags);
  std::unique_ptr<pba::PbaServer> server;
  const pba::Status started = pba::PbaServer::Start(options, &server);
  if (!started.ok()) {
    spdlog::error("cannot start: {}", started.ToString());
    return 1;
  }

  const fs::path server_json = fs::absolute(flags.data_dir) / "server.json";
  const std::string info = "{\"address\":\"" + server->address() + "\",\"http\":\"" +
                           server->http_address() + "\",\"pid\":" + std::to_string(::getpid()) +
                           "}\n";
  const pba::Status written = pba::AtomicWriteText(server_json, info);
  if (!written.ok()) spdlog::warn("cannot write server.json: {}", written.ToString());
  if (!server->http_address().empty()) {
    std::cout << "web view on " << (flags.tls_cert.empty() ? "http://" : "https://")
              << server->http_address() << "/" << std::endl;
  }
  std::cout << "pba-server listening on " << server->address() << std::endl;
  if (!flags.tls_cert.empty()) spdlog::info("TLS with the certificate {}", flags.tls_cert);
  if (flags.tls_cert.empty() && !pba::IsLoopbackListen(flags.listen)) {
    spdlog::warn("--insecure: serving plaintext on {}; tokens cross the network in the clear",
                 flags.listen);
  }
  spdlog::info("serving jobs from {} with solver {}", fs::absolute(flags.data_dir).string(),
               options.solver.string());
  // The effective limits, defaults included (0: none).
  spdlog::info("limits: --max-job-time {} s, --solver-memory {:.2f} GiB, --upload-quota {:.2f} GiB",
               flags.max_job_time_s,
               static_cast<double>(options.max_solver_memory_bytes) / (1LL << 30),
               flags.upload_quota_gib);

  int signal_number = 0;
  while (sigwait(&shutdown_signals, &signal_number) != 0) {
  }
  spdlog::info("{} received: shutting down", pba::SignalName(signal_number));
  server->Shutdown();
  std::error_code ec;
  fs::remove(server_json, ec);
  spdlog::info("stopped");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Before anything is created: every file of the data directory (and of
  // the solves this starts, which inherit it) is the server user's alone.
  ::umask(077);
  CLI::App app{"pba-server: runs PBA simulation jobs behind a gRPC API"};
  ServeFlags flags;
  AddServeOptions(app, &flags);
  AdminCommands admin;
  AddAdminCommands(app, &admin);
  CLI11_PARSE(app, argc, argv);
  if (admin.create_user->parsed())
    return CreateUser(admin.data_dir, admin.user, admin.server_admin);
  if (admin.disable_user->parsed()) return SetDisabled(admin.data_dir, admin.user, true);
  if (admin.enable_user->parsed()) return SetDisabled(admin.data_dir, admin.user, false);
  if (flags.data_dir.empty()) {
    std::cerr << "--data is required\n" << app.help() << std::flush;
    return 2;
  }

  spdlog::set_default_logger(spdlog::stderr_color_mt("pba-server"));
  spdlog::set_level(spdlog::level::from_str(flags.log_level));
  const sigset_t shutdown_signals = BlockShutdownSignals();
  return Serve(flags, shutdown_signals);
}
