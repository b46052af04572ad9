// pba-server: the PBA gRPC server.
//
//   pba-server --data DIR [--listen HOST:PORT] [--solver PATH] [--max-running N]
//              [--log-level LEVEL]
//   pba-server admin create-user NAME --data DIR
//
// The second form creates an atlas user offline (the server may be running)
// and prints its token once on stdout; only its hash is kept. On the first
// start the server creates the user "admin" itself, with the token in
// DIR/admin.token.
//
// Prints "pba-server listening on HOST:PORT" once it accepts calls and writes
// DIR/server.json ({"address": ..., "pid": ...}) for scripts; SIGTERM or
// SIGINT shut it down cleanly (running jobs are re-queued) with exit code 0.
#include <signal.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <system_error>
#include <thread>

#include "app/pba_server.h"
#include "jobs/solver_process.h"
#include "store/atlas_store.h"
#include "store/atomic_file.h"

namespace {

namespace fs = std::filesystem;

int CreateUser(const std::string& data_dir, const std::string& name) {
  std::unique_ptr<pba::AtlasStore> store;
  pba::Status status = pba::AtlasStore::Open(data_dir, &store);
  std::string token;
  if (status.ok()) status = store->CreateUser(name, &token);
  if (!status.ok()) {
    std::cerr << "pba-server admin create-user: " << status.ToString() << std::endl;
    return 1;
  }
  std::cerr << "created atlas user '" << name
            << "'; its token follows (shown only now; send it as "
               "'authorization: Bearer <token>')"
            << std::endl;
  std::cout << token << std::endl;
  return 0;
}

fs::path DefaultSolver() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return (ec ? fs::current_path() : self.parent_path()) / "pba-solve";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"pba-server: runs PBA simulation jobs behind a gRPC API"};
  std::string data_dir;
  std::string listen = "127.0.0.1:50051";
  std::string solver;
  int max_running = 1;
  std::string log_level = "info";
  std::string tls_cert, tls_key;
  app.add_option("--data", data_dir, "Data directory (pba.db, jobs/); created if absent");
  app.add_option("--listen", listen, "HOST:PORT to listen on; port 0 picks a free port")
      ->capture_default_str();
  app.add_option("--solver", solver, "pba-solve executable (default: next to pba-server)");
  app.add_option("--max-running", max_running, "Jobs run at the same time")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  double atlas_cache_gib = 2.0;
  app.add_option("--atlas-cache-size", atlas_cache_gib,
                 "Bound of <data>/cache/atlas, the built atlas meshes solves share [GiB]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error, critical or off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}))
      ->capture_default_str();
  app.add_option("--tls-cert", tls_cert,
                 "PEM certificate (chain) to serve TLS with; needs --tls-key");
  app.add_option("--tls-key", tls_key, "PEM private key of --tls-cert");
  int64_t max_job_time_s = 0;
  app.add_option("--max-job-time", max_job_time_s,
                 "Wall-clock limit of a job [s]; a job may ask for less; 0: none")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  int max_attempts = 3;
  app.add_option("--max-attempts", max_attempts,
                 "Starts of a job (restarts re-queue running jobs) before it is given up")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  double solver_memory_gib = 0;
  app.add_option("--solver-memory", solver_memory_gib,
                 "Address-space limit of each pba-solve [GiB]; 0: none")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  double keep_results_days = 30;
  app.add_option("--keep-results", keep_results_days,
                 "Days a finished job's files are kept; 0: forever")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  CLI::App* admin = app.add_subcommand("admin", "Offline administration of the data directory");
  admin->require_subcommand(1);
  CLI::App* create_user =
      admin->add_subcommand("create-user", "Create a user and print its token once");
  std::string new_user;
  std::string admin_data_dir;
  create_user->add_option("name", new_user, "The user's name")->required();
  create_user->add_option("--data", admin_data_dir, "Data directory")->required();
  CLI11_PARSE(app, argc, argv);
  if (create_user->parsed()) return CreateUser(admin_data_dir, new_user);
  if (data_dir.empty()) {
    std::cerr << "--data is required\n" << app.help() << std::flush;
    return 2;
  }

  spdlog::set_default_logger(spdlog::stderr_color_mt("pba-server"));
  spdlog::set_level(spdlog::level::from_str(log_level));

  // Block the shutdown signals before any thread starts, so every thread
  // inherits the mask and only sigwait() below sees them: no work happens in
  // a signal handler. (Children unblock them again before exec.)
  sigset_t shutdown_signals;
  sigemptyset(&shutdown_signals);
  sigaddset(&shutdown_signals, SIGTERM);
  sigaddset(&shutdown_signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &shutdown_signals, nullptr);
  // A client vanishing mid-write must not kill the server.
  signal(SIGPIPE, SIG_IGN);

  pba::ServerOptions options;
  options.data_dir = data_dir;
  options.listen = listen;
  options.solver = solver.empty() ? DefaultSolver() : fs::path(solver);
  options.max_running = max_running;
  options.atlas_cache_gib = atlas_cache_gib;
  options.tls_cert = tls_cert;
  options.tls_key = tls_key;
  options.max_job_time = std::chrono::seconds(max_job_time_s);
  options.max_attempts = max_attempts;
  options.max_solver_memory_bytes = static_cast<int64_t>(solver_memory_gib * (1LL << 30));
  options.keep_results = std::chrono::seconds(static_cast<int64_t>(keep_results_days * 86400));
  // Parallel solves share the cores rather than each taking all of them.
  if (max_running > 1) {
    options.solver_threads =
        std::max(1, static_cast<int>(std::thread::hardware_concurrency()) / max_running);
  }

  std::unique_ptr<pba::PbaServer> server;
  const pba::Status started = pba::PbaServer::Start(options, &server);
  if (!started.ok()) {
    spdlog::error("cannot start: {}", started.ToString());
    return 1;
  }

  const fs::path server_json = fs::absolute(data_dir) / "server.json";
  const std::string info =
      "{\"address\":\"" + server->address() + "\",\"pid\":" + std::to_string(::getpid()) + "}\n";
  const pba::Status written = pba::WriteFileAtomically(server_json, info);
  if (!written.ok()) spdlog::warn("cannot write server.json: {}", written.ToString());
  std::cout << "pba-server listening on " << server->address() << std::endl;
  if (!tls_cert.empty()) spdlog::info("TLS with the certificate {}", tls_cert);
  spdlog::info("serving jobs from {} with solver {}", fs::absolute(data_dir).string(),
               options.solver.string());

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
