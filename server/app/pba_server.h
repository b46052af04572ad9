// PbaServer: everything pba-server runs, wired together: the job store, the
// executor, the atlas store with its uploads, the gRPC services (jobs, atlas,
// health, reflection). main() adds the command line, signals and
// server.json; tests start it in-process.
//
// First start: when the atlas store has no user, Start() creates the user
// "admin", a server admin (job_service.h), and writes its token to
// <data>/admin.token (mode 0600, created exclusively, fsynced) and logs
// where it is. Every service asks for tokens (call_auth.h).
//
// Trust boundaries (docs/design.md): Start() refuses to listen without TLS
// on anything but loopback (127.0.0.0/8, ::1, localhost) or a unix socket
// unless ServerOptions::insecure says so, since tokens travel in every
// call's metadata. The data directory is made 0700; main() sets the umask
// to 077 before anything is created, so every file the server and its
// solves write is 0600 (a library does not set process-wide state, so
// in-process tests keep their own umask). Health: the default service
// ("") and one status per service (pba.v1.JobService, pba.v1.AtlasService)
// are SERVING once Start() returns, NOT_SERVING from Shutdown() on.
#pragma once

#include <grpcpp/server.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>

#include "jobs/job_event_hub.h"
#include "jobs/job_executor.h"
#include "jobs/slurm_executor.h"
#include "pba/status.h"
#include "service/atlas_event_hub.h"
#include "service/atlas_jobs.h"
#include "service/atlas_service.h"
#include "service/job_service.h"
#include "service/surface_views.h"
#include "store/atlas_store.h"
#include "store/job_store.h"
#include "store/upload_store.h"
#include "web/web_server.h"

namespace pba {

// Enough for a sweep of several thousand members; far below what would
// slow the queue's queries.
inline constexpr int kDefaultMaxOpenJobs = 10000;

struct ServerOptions {
  // Holds pba.db and jobs/; created if absent.
  std::filesystem::path data_dir;
  // HOST:PORT; port 0 picks a free port (see PbaServer::address()).
  std::string listen = "127.0.0.1:50051";
  // The pba-solve executable; must exist and be executable.
  std::filesystem::path solver;
  int max_running = 1;
  int solver_threads = 0;
  // Jobs may ask for up to this many MPI ranks, run through `mpirun` (empty:
  // no MPI; every job one process).
  int max_ranks = 1;
  std::filesystem::path mpirun;
  // Bound of data_dir/cache/atlas, the built atlas meshes every pba-solve
  // shares [GiB].
  double atlas_cache_gib = 2.0;
  // Bound of data_dir/cache/surfaces, the structures' surfaces the web
  // view draws (service/surface_views.h) [MiB].
  double surface_cache_mib = 512;
  // SIGTERM-to-SIGKILL grace for solves being cancelled or stopped.
  std::chrono::milliseconds kill_grace{10000};
  // How long in-flight RPCs may take to finish at shutdown.
  std::chrono::milliseconds drain{5000};
  // TLS: PEM certificate chain and private key. Both set: the server speaks
  // only TLS; both empty: plaintext (fine on loopback); one alone is an error.
  std::filesystem::path tls_cert, tls_key;
  // Allows plaintext on an address that is not loopback (IsLoopbackListen);
  // without it Start() refuses that.
  bool insecure = false;
  // A job's wall-clock limit (ExecutorOptions::max_job_time); 0: none.
  std::chrono::seconds max_job_time{kDefaultMaxJobTime};
  // Starts of a job before it is given up (ExecutorOptions::max_attempts).
  int max_attempts = 3;
  // Address-space limit of each pba-solve [bytes]; 0: none.
  int64_t max_solver_memory_bytes = 0;
  // How long a finished job's folder is kept (ExecutorOptions::keep_results);
  // 0: forever.
  std::chrono::seconds keep_results{0};
  // Jobs one user may have queued or running at once; a submit beyond is
  // RESOURCE_EXHAUSTED (JobServiceImpl). 0: no bound.
  int max_open_jobs = kDefaultMaxOpenJobs;
  // Bytes one user's open uploads may announce together
  // (UploadStore::set_quota_bytes); 0: no quota.
  int64_t upload_quota_bytes = 0;
  // Where jobs run: children of this server (kLocal, jobs/job_executor.h)
  // or Slurm jobs (kSlurm, jobs/slurm_executor.h) with `slurm`'s options.
  enum class ExecutorKind { kLocal, kSlurm };
  ExecutorKind executor = ExecutorKind::kLocal;
  SlurmOptions slurm;
  // The job folders (empty: data_dir/jobs); with Slurm a directory every
  // compute node sees at the same path, which then also holds the atlas
  // mesh cache (jobs_dir/.atlas-cache).
  std::filesystem::path jobs_dir;
  // pba-server --http: HOST:PORT of the web view (web/web_server.h; port 0
  // picks a free one), empty for none; served with the same TLS
  // certificate, and refused on an address that is not loopback without
  // TLS unless `insecure`. `web_app_dir`: the application's files.
  std::string http_listen;
  std::filesystem::path web_app_dir;
};

class PbaServer {
 public:
  static constexpr char kRequeueAtStart[] =
      "re-queued: the server stopped while this job was running";
  static constexpr char kAdminUser[] = "admin";
  static constexpr char kAdminTokenFile[] = "admin.token";

  // Opens the store, re-queues jobs a previous server left RUNNING, starts
  // listening and then the executor.
  static Status Start(const ServerOptions& options, std::unique_ptr<PbaServer>* out);

  PbaServer(const PbaServer&) = delete;
  PbaServer& operator=(const PbaServer&) = delete;
  ~PbaServer();  // Shutdown()

  // HOST:PORT actually listened on (the real port when 0 was asked for).
  const std::string& address() const { return address_; }
  // HOST:PORT of the web view ("" without --http).
  std::string http_address() const { return web_ != nullptr ? web_->address() : ""; }

  // <data>/admin.token if this start created the first admin, else empty.
  const std::filesystem::path& admin_token_file() const { return admin_token_file_; }

  // Ends watch streams, drains RPCs (up to options.drain), stops running
  // solves (their jobs are re-queued) and closes the store. Idempotent.
  void Shutdown();

 private:
  PbaServer() = default;
  // The web view (options.http_listen) on the gRPC server's in-process
  // channel; the gRPC server is stopped when it cannot start.
  Status StartWeb(const ServerOptions& options);

  ServerOptions options_;
  std::unique_ptr<JobStore> store_;
  JobEventHub hub_;
  std::unique_ptr<Executor> executor_;
  std::unique_ptr<JobServiceImpl> service_;
  std::unique_ptr<AtlasStore> atlas_store_;
  std::unique_ptr<UploadStore> uploads_;
  AtlasEventHub atlas_hub_;
  std::unique_ptr<SurfaceViews> surface_views_;  // outlives atlas_service_
  std::unique_ptr<AtlasServiceImpl> atlas_service_;
  std::unique_ptr<AtlasJobs> atlas_jobs_;
  std::filesystem::path admin_token_file_;
  std::unique_ptr<grpc::Server> server_;
  std::unique_ptr<WebServer> web_;
  std::string address_;
  bool shut_down_ = false;
};

// Whether `listen` (a gRPC server address) can only be reached from this
// machine: "unix:..." and "unix-abstract:..." sockets, and HOST:PORT whose
// HOST is "localhost" or an address in 127.0.0.0/8 or ::1 (also
// IPv4-mapped, [::ffff:127.x.y.z]). Anything else, a wildcard or a name
// included, is not.
bool IsLoopbackListen(const std::string& listen);

// Makes `data_dir` (which must exist) 0700: it holds the tokens' hashes,
// the admin's token and everyone's geometry and results.
Status RestrictDataDir(const std::filesystem::path& data_dir);

// Checks that `solver` is an executable regular file.
Status CheckSolver(const std::filesystem::path& solver);

// If `store` has no user, creates `user` (a server admin) and writes its
// token (and a newline) to `token_file`, mode 0600, written atomically
// (AtomicWrite, never_replace: never over a file that appears meanwhile);
// *created says whether it did. A token file left from an earlier database
// that has no users is removed first, so it is replaced.
Status CreateFirstAdmin(AtlasStore& store, const std::string& user,
                        const std::filesystem::path& token_file, bool* created);

}  // namespace pba
