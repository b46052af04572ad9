#include "app/pba_server.h"

#include <arpa/inet.h>
#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/resource_quota.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <system_error>
#include <vector>

#include "core/atomic_write.h"

namespace pba {
namespace fs = std::filesystem;

Status CheckSolver(const fs::path& solver) {
  std::error_code ec;
  if (!fs::is_regular_file(solver, ec)) {
    return Status::FailedPrecondition("the solver " + solver.string() +
                                      " does not exist (use --solver PATH)");
  }
  if (::access(solver.c_str(), X_OK) != 0) {
    return Status::FailedPrecondition("the solver " + solver.string() + " is not executable");
  }
  return Status::Ok();
}

bool IsLoopbackListen(const std::string& listen) {
  if (listen.rfind("unix:", 0) == 0 || listen.rfind("unix-abstract:", 0) == 0) return true;
  std::string host;
  if (!listen.empty() && listen.front() == '[') {
    const size_t close = listen.find(']');
    if (close == std::string::npos) return false;
    host = listen.substr(1, close - 1);
  } else {
    const size_t colon = listen.rfind(':');
    if (colon == std::string::npos) return false;
    host = listen.substr(0, colon);
  }
  std::transform(host.begin(), host.end(), host.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (host == "localhost") return true;
  in_addr v4{};
  if (::inet_pton(AF_INET, host.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
  in6_addr v6{};
  if (::inet_pton(AF_INET6, host.c_str(), &v6) == 1) {
    if (IN6_IS_ADDR_LOOPBACK(&v6)) return true;
    return IN6_IS_ADDR_V4MAPPED(&v6) && v6.s6_addr[12] == 127;
  }
  return false;
}

Status RestrictDataDir(const fs::path& data_dir) {
  if (::chmod(data_dir.c_str(), 0700) != 0) {
    return Status::Io("cannot make " + data_dir.string() +
                      " private (mode 0700): " + std::strerror(errno));
  }
  return Status::Ok();
}

Status CreateFirstAdmin(AtlasStore& store, const std::string& user, const fs::path& token_file,
                        bool* created) {
  *created = false;
  int64_t users = 0;
  PBA_RETURN_IF_ERROR(store.CountUsers(&users));
  if (users > 0) return Status::Ok();
  std::error_code ec;
  if (fs::exists(token_file, ec)) {
    // Its token belonged to a database that is gone: useless, and in the way.
    spdlog::warn("replacing {}: the atlas store has no users", token_file.string());
    fs::remove(token_file, ec);
  }
  // The (temporary) file first, so a token is never issued that cannot be
  // written down; named only once the token is in it and synced. Never
  // replacing: a file that appeared since is not the stale one removed above.
  AtomicWriteOptions options;
  options.never_replace = true;  // mode 0600, the default
  PBA_RETURN_IF_ERROR(AtomicWrite(
      token_file, "",
      [&](int fd, const std::string& temporary) {
        std::string token;
        PBA_RETURN_IF_ERROR(store.CreateUser(user, &token, /*server_admin=*/true));
        const std::string line = token + "\n";
        return WriteAll(fd, line.data(), line.size(), temporary);
      },
      options));
  *created = true;
  return Status::Ok();
}

namespace {

// Threads gRPC may use for calls at once (see the ResourceQuota below).
constexpr int kMaxServerThreads = 512;

// A PEM file's text; kInvalidArgument naming `field` when it cannot be read
// or holds no "-----BEGIN ...<kind>-----" block.
Status ReadPem(const fs::path& path, const char* field, const char* kind, std::string* pem) {
  std::ifstream in(path);
  if (!in) return Status::InvalidArgument(field, "cannot read " + path.string());
  std::stringstream text;
  text << in.rdbuf();
  *pem = text.str();
  if (pem->find("-----BEGIN") == std::string::npos || pem->find(kind) == std::string::npos) {
    return Status::InvalidArgument(field,
                                   path.string() + " holds no PEM " + std::string(kind) + " block");
  }
  return Status::Ok();
}

// The executor's may_run: a job whose owner was disabled while it waited in
// the queue (or before a restart re-queued it) does not run. Jobs stored
// before owners were kept have none, and run.
Status OwnerMayRun(AtlasStore& users, const v1::Job& job) {
  if (job.owner().empty()) return Status::Ok();
  bool disabled = false;
  PBA_RETURN_IF_ERROR(users.IsUserDisabled(job.owner(), &disabled));
  if (disabled) {
    return Status::FailedPrecondition("not started: its owner '" + job.owner() +
                                      "' was disabled (pba-server admin disable-user)");
  }
  return Status::Ok();
}

// Jobs a Slurm-backed server handed to Slurm run on there: a server with
// the local executor would run them a second time, so it does not start.
Status RefuseJobsInSlurm(JobStore& store) {
  std::vector<v1::Job> scheduled;
  PBA_RETURN_IF_ERROR(store.ListScheduled(&scheduled));
  if (scheduled.empty()) return Status::Ok();
  std::string named;
  for (std::size_t i = 0; i < scheduled.size() && i < 5; ++i) {
    named += (i > 0 ? ", " : "") + scheduled[i].id() + " (Slurm job " +
             scheduled[i].scheduler().job_id() + ")";
  }
  return Status::FailedPrecondition(
      std::to_string(scheduled.size()) + " job(s) are in Slurm's hands: " + named +
      (scheduled.size() > 5 ? ", ..." : "") +
      "; start with --executor slurm to follow them (or cancel them there first)");
}

// The executor `options` choose; a Slurm one checked against its cluster.
Status MakeExecutor(const ServerOptions& options, JobStore& store, JobEventHub& hub,
                    ExecutorOptions executor_options, std::unique_ptr<Executor>* executor) {
  if (options.executor == ServerOptions::ExecutorKind::kLocal) {
    *executor = std::make_unique<JobExecutor>(store, hub, std::move(executor_options));
    return Status::Ok();
  }
  auto slurm =
      std::make_unique<SlurmExecutor>(store, hub, std::move(executor_options), options.slurm);
  PBA_RETURN_IF_ERROR(slurm->Check());
  *executor = std::move(slurm);
  return Status::Ok();
}

// What GetServerInfo answers for `options`.
v1::ServerInfo InfoOf(const ServerOptions& options) {
  v1::ServerInfo info;
  const bool slurm = options.executor == ServerOptions::ExecutorKind::kSlurm;
  info.set_executor(slurm ? "slurm" : "local");
  info.set_max_running(slurm ? options.slurm.max_submitted : options.max_running);
  info.set_max_open_jobs(options.max_open_jobs);
  info.set_array_min(slurm ? options.slurm.array_min : 0);
  info.set_max_ranks(options.mpirun.empty() ? 1 : options.max_ranks);
  info.set_max_job_time_s(options.max_job_time.count());
  return info;
}

// The executor's options from the server's (what the store adds is set
// by Start).
ExecutorOptions ExecutorOptionsFor(const ServerOptions& options, const fs::path& data_dir,
                                   const fs::path& jobs_dir) {
  ExecutorOptions executor_options;
  executor_options.data_dir = data_dir;
  executor_options.solver = fs::absolute(options.solver);
  executor_options.max_running = options.max_running;
  executor_options.solver_threads = options.solver_threads;
  executor_options.mpirun = options.mpirun;
  executor_options.max_ranks = options.max_ranks;
  executor_options.jobs_dir = jobs_dir;
  // Slurm's nodes read the cache where they read the job folders.
  executor_options.atlas_cache_dir = options.executor == ServerOptions::ExecutorKind::kSlurm
                                         ? jobs_dir / ".atlas-cache"
                                         : data_dir / "cache" / "atlas";
  executor_options.atlas_cache_gib = options.atlas_cache_gib;
  executor_options.kill_grace = options.kill_grace;
  executor_options.max_job_time = options.max_job_time;
  executor_options.max_attempts = options.max_attempts;
  executor_options.max_solver_memory_bytes = options.max_solver_memory_bytes;
  executor_options.keep_results = options.keep_results;
  return executor_options;
}

// Where and within what the structures' surfaces are built: the solve's
// memory bound (or 4 GiB), five minutes.
SurfaceViewOptions SurfaceViewOptionsFor(const ServerOptions& options, const fs::path& data_dir) {
  SurfaceViewOptions views;
  views.solver = fs::absolute(options.solver);
  views.cache_dir = data_dir / "cache" / "surfaces";
  views.cache_bytes = static_cast<std::uint64_t>(options.surface_cache_mib * (1 << 20));
  if (options.max_solver_memory_bytes > 0) views.memory_bytes = options.max_solver_memory_bytes;
  return views;
}

}  // namespace

Status PbaServer::StartWeb(const ServerOptions& options) {
  WebOptions web;
  web.listen = options.http_listen;
  web.app_dir = options.web_app_dir;
  web.tls_cert = options.tls_cert;
  web.tls_key = options.tls_key;
  const Status started =
      WebServer::Start(web, server_->InProcessChannel(grpc::ChannelArguments()), &web_);
  if (!started.ok()) {
    server_->Shutdown();
    server_.reset();
  }
  return started;
}

Status PbaServer::Start(const ServerOptions& options, std::unique_ptr<PbaServer>* out) {
  std::unique_ptr<PbaServer> server(new PbaServer());
  server->options_ = options;
  // Tokens travel in every call's metadata: in plaintext they are for this
  // machine only, unless the operator says otherwise.
  if (options.tls_cert.empty() && options.tls_key.empty() && !options.insecure &&
      !IsLoopbackListen(options.listen)) {
    return Status::InvalidArgument(
        "listen", options.listen +
                      " is not a loopback address, and without TLS every token would cross the "
                      "network in the clear: give --tls-cert and --tls-key, listen on "
                      "127.0.0.1, [::1], localhost or a unix: socket, or pass --insecure to "
                      "accept that");
  }
  if (!options.http_listen.empty() && options.tls_cert.empty() && !options.insecure &&
      (!IsLoopbackListen(options.http_listen) || options.http_listen.rfind("unix:", 0) == 0)) {
    return Status::InvalidArgument(
        "http", options.http_listen +
                    " is not a loopback address, and without TLS the session cookie would "
                    "cross the network in the clear: give --tls-cert and --tls-key, serve on "
                    "127.0.0.1, [::1] or localhost, or pass --insecure to accept that");
  }
  std::error_code ec;
  server->options_.data_dir = fs::absolute(options.data_dir, ec);
  const fs::path& data_dir = server->options_.data_dir;
  const fs::path jobs_dir =
      options.jobs_dir.empty() ? data_dir / "jobs" : fs::absolute(options.jobs_dir, ec);
  fs::create_directories(jobs_dir, ec);
  if (ec) return Status::Io("cannot create " + jobs_dir.string() + ": " + ec.message());
  PBA_RETURN_IF_ERROR(RestrictDataDir(data_dir));
  PBA_RETURN_IF_ERROR(CheckSolver(options.solver));
  if (!options.mpirun.empty() && ::access(options.mpirun.c_str(), X_OK) != 0) {
    return Status::FailedPrecondition("the mpirun " + options.mpirun.string() +
                                      " is not an executable (use --mpirun PATH, or none)");
  }
  if (options.max_ranks < 1) {
    return Status::InvalidArgument("max_ranks", "must be at least 1");
  }
  if (options.max_open_jobs < 0) {
    return Status::InvalidArgument("max_open_jobs", "must not be negative (0: no bound)");
  }
  // TLS material is read before anything is opened: a bad path is named at
  // once, not after the stores are up.
  std::string cert_pem, key_pem;
  if (options.tls_cert.empty() != options.tls_key.empty()) {
    return Status::InvalidArgument(options.tls_cert.empty() ? "tls_cert" : "tls_key",
                                   "TLS needs both a certificate and its key");
  }
  if (!options.tls_cert.empty()) {
    PBA_RETURN_IF_ERROR(ReadPem(options.tls_cert, "tls_cert", "CERTIFICATE", &cert_pem));
    PBA_RETURN_IF_ERROR(ReadPem(options.tls_key, "tls_key", "PRIVATE KEY", &key_pem));
  }

  PBA_RETURN_IF_ERROR(JobStore::Open(data_dir / "pba.db", &server->store_));
  std::vector<v1::JobEvent> requeued;
  PBA_RETURN_IF_ERROR(server->store_->RequeueInterrupted(kRequeueAtStart, &requeued));
  for (const v1::JobEvent& event : requeued) {
    spdlog::info("job {} QUEUED: {}", event.job_id(), event.message());
  }
  if (options.executor == ServerOptions::ExecutorKind::kLocal) {
    PBA_RETURN_IF_ERROR(RefuseJobsInSlurm(*server->store_));
  }

  PBA_RETURN_IF_ERROR(AtlasStore::Open(data_dir, &server->atlas_store_));
  // A blob is written before its revision's row, so a crash between the two
  // leaves a blob nothing names; nothing else writes blobs before the server
  // listens, so this is the moment to remove them.
  BlobSweepReport swept_blobs;
  PBA_RETURN_IF_ERROR(server->atlas_store_->SweepBlobs(&swept_blobs));
  if (swept_blobs.removed_blobs + swept_blobs.removed_temp_files > 0) {
    spdlog::info("removed {} blob(s) no revision names and {} temporary file(s), {} bytes",
                 swept_blobs.removed_blobs, swept_blobs.removed_temp_files,
                 swept_blobs.removed_bytes);
  }
  PBA_RETURN_IF_ERROR(UploadStore::Open(data_dir / "uploads", &server->uploads_));
  server->uploads_->set_quota_bytes(options.upload_quota_bytes);
  int swept = 0;
  PBA_RETURN_IF_ERROR(server->uploads_->Sweep(&swept));
  if (swept > 0) spdlog::info("removed {} expired or stray upload files", swept);
  bool created = false;
  const fs::path token_file = data_dir / kAdminTokenFile;
  PBA_RETURN_IF_ERROR(CreateFirstAdmin(*server->atlas_store_, kAdminUser, token_file, &created));
  if (created) {
    server->admin_token_file_ = token_file;
    spdlog::info("first start: created the user '{}'; its token is in {} (mode 0600)", kAdminUser,
                 token_file.string());
  }

  ExecutorOptions executor_options = ExecutorOptionsFor(options, data_dir, jobs_dir);
  server->atlas_jobs_ =
      std::make_unique<AtlasJobs>(*server->atlas_store_, server->atlas_hub_, *server->store_);
  executor_options.preparation = server->atlas_jobs_.get();
  AtlasStore* users = server->atlas_store_.get();
  executor_options.may_run = [users](const v1::Job& job) { return OwnerMayRun(*users, job); };
  AtlasJobs* atlas_jobs = server->atlas_jobs_.get();
  server->hub_.SetStateListener(
      [atlas_jobs](const v1::JobEvent& event) { atlas_jobs->PublishJobEvent(event); });
  PBA_RETURN_IF_ERROR(MakeExecutor(options, *server->store_, server->hub_,
                                   std::move(executor_options), &server->executor_));
  server->service_ =
      std::make_unique<JobServiceImpl>(*server->store_, *server->executor_, server->hub_,
                                       *server->atlas_store_, *server->uploads_, jobs_dir);
  server->service_->set_info(InfoOf(options));

  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  grpc::ServerBuilder builder;
  // gRPC's synchronous server would otherwise start a thread for every call
  // in flight without bound (each open Watch holds one); past this many a
  // new call is answered RESOURCE_EXHAUSTED at once, and the per-user
  // stream limits (stream_slots.h) keep one user from taking them all.
  grpc::ResourceQuota quota("pba-server");
  quota.SetMaxThreads(kMaxServerThreads);
  builder.SetResourceQuota(quota);
  int port = 0;
  std::shared_ptr<grpc::ServerCredentials> credentials = grpc::InsecureServerCredentials();
  if (!options.tls_cert.empty()) {
    grpc::SslServerCredentialsOptions ssl;
    ssl.pem_key_cert_pairs.push_back({key_pem, cert_pem});
    credentials = grpc::SslServerCredentials(ssl);
  }
  builder.AddListeningPort(options.listen, credentials, &port);
  builder.RegisterService(server->service_.get());
  server->atlas_service_ = std::make_unique<AtlasServiceImpl>(
      *server->atlas_store_, *server->uploads_, server->atlas_hub_);
  server->surface_views_ = std::make_unique<SurfaceViews>(SurfaceViewOptionsFor(options, data_dir));
  server->atlas_service_->set_surface_views(server->surface_views_.get());
  builder.RegisterService(server->atlas_service_.get());
  server->server_ = builder.BuildAndStart();
  if (server->server_ == nullptr || port == 0) {
    server->server_.reset();
    return Status::Io("cannot listen on " + options.listen);
  }
  const size_t colon = options.listen.rfind(':');
  server->address_ = options.listen.substr(0, colon) + ":" + std::to_string(port);
  if (!options.http_listen.empty()) PBA_RETURN_IF_ERROR(server->StartWeb(options));
  server->executor_->Start();
  // Per service, so that a probe can ask for the one it needs (the default
  // service "" is SERVING already).
  if (auto* health = server->server_->GetHealthCheckService()) {
    health->SetServingStatus(v1::JobService::service_full_name(), true);
    health->SetServingStatus(v1::AtlasService::service_full_name(), true);
  }
  *out = std::move(server);
  return Status::Ok();
}

PbaServer::~PbaServer() { Shutdown(); }

void PbaServer::Shutdown() {
  if (shut_down_) return;
  shut_down_ = true;
  // Watch streams end first (they would otherwise hold the drain to its
  // deadline), then unary calls get their drain time.
  if (web_ != nullptr) web_->Stop();
  hub_.Shutdown();
  atlas_hub_.Shutdown();
  if (atlas_service_ != nullptr) atlas_service_->Stop();
  if (server_ != nullptr) {
    if (auto* health = server_->GetHealthCheckService()) health->Shutdown();
    server_->Shutdown(std::chrono::system_clock::now() + options_.drain);
    server_->Wait();
  }
  if (executor_ != nullptr) executor_->Stop();
  server_.reset();
  service_.reset();
  atlas_service_.reset();
  executor_.reset();
  atlas_jobs_.reset();
  store_.reset();
  uploads_.reset();
  atlas_store_.reset();
}

}  // namespace pba
