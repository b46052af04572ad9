// Speed of pba-server on loopback: unary RPC latency, the atlas store's
// commit and download throughput for a 50 MiB geometry, trivial jobs per
// minute through the real pba-solve, and Watch fan-out to 50 watchers. Each
// benchmark starts its own PbaServer in-process on 127.0.0.1:0 with a fresh
// data directory under the system temp dir, and calls it through real
// channels with the admin token (sent to the job service too). A benchmark,
// not a test: scripts/bench.sh runs it for docs/performance.md.
#include <benchmark/benchmark.h>
#include <fcntl.h>
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "bench/bench_server.h"
#include "codec/yaml_codec.h"
#include "core/sha256.h"
#include "service/geometry_check.h"

namespace pba {
namespace {

using Clock = std::chrono::steady_clock;
using testing::BenchServer;
using testing::ErrorText;
using testing::kMiB;
using testing::kProject;

double Seconds(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

// The q-quantile (0..1) of `values` by the nearest-rank method; sorts them.
double Quantile(std::vector<double>* values, double q) {
  if (values->empty()) return 0;
  std::sort(values->begin(), values->end());
  const size_t rank = static_cast<size_t>(std::ceil(q * static_cast<double>(values->size())));
  return (*values)[std::clamp<size_t>(rank, 1, values->size()) - 1];
}

// A plate-contour structure: one plate, one square of 20 mm.
constexpr char kSquareContours[] =
    R"({"plates": [{"z_mm": 0, "polygons": [[[0, 0], [20, 0], [20, 20], [0, 20]]]}]})";

// The smallest useful job: a 10 mm cube in 5 mm tetrahedra (27 nodes),
// linear elastic, base held, top pressed 0.5 mm.
constexpr char kTinyScene[] = R"(
name: bench-tiny-box
geometry:
  box:
    size_mm: [10, 10, 10]
mesh:
  element: TET4
  element_size_mm: 5
material:
  name: brain tissue (linearised)
  linear_elastic:
    youngs_modulus_pa: 3000
    poissons_ratio: 0.45
boundary_conditions:
  - set: bottom
    fixed: {}
  - set: top
    displacement: {x_mm: 0, y_mm: 0, z_mm: -0.5}
analysis:
  type: LINEAR_STATIC
outputs:
  fields: [DISPLACEMENT]
)";

// --- 1. unary latency -------------------------------------------------------

// Health/Check is the floor: gRPC on loopback with neither a token check
// nor SQLite. WhoAmI adds the token check (a SHA-256 and one SQLite
// lookup), GetStructure the project role, structure and lock reads, ListJobs
// a page of kListedJobs jobs.
enum class Unary { kHealth, kWhoAmI, kGetStructure, kListJobs };
constexpr const char* kUnaryNames[] = {"Health/Check", "WhoAmI", "GetStructure", "ListJobs"};
constexpr int kUnaryWarmup = 100;
// Finished jobs in the store when ListJobs is timed (one page).
constexpr int kListedJobs = 20;

// Runs `count` tiny jobs to the end (SUCCEEDED); false with `error` if one
// did not, or they took longer than `timeout`.
bool RunTinyJobs(BenchServer& server, int count, std::chrono::seconds timeout, std::string* error) {
  v1::SubmitJobRequest submit;
  codec::ParseError parse_error;
  if (!codec::ParseYaml(kTinyScene, submit.mutable_scene(), &parse_error)) {
    *error = parse_error.ToString();
    return false;
  }
  for (int i = 0; i < count; ++i) {
    submit.set_request_id("bench-" + std::to_string(i));
    v1::Job job;
    const grpc::Status status =
        server.Call(server.jobs(), &v1::JobService::Stub::SubmitJob, submit, &job);
    if (!status.ok()) {
      *error = ErrorText("SubmitJob", status);
      return false;
    }
  }
  const auto deadline = Clock::now() + timeout;
  v1::ListJobsRequest list;
  list.set_page_size(500);
  while (true) {
    v1::ListJobsResponse response;
    const grpc::Status status =
        server.Call(server.jobs(), &v1::JobService::Stub::ListJobs, list, &response);
    if (!status.ok()) {
      *error = ErrorText("ListJobs", status);
      return false;
    }
    int succeeded = 0;
    for (const v1::Job& job : response.jobs()) {
      if (job.state() == v1::Job::SUCCEEDED) {
        ++succeeded;
      } else if (job.state() != v1::Job::QUEUED && job.state() != v1::Job::RUNNING) {
        *error =
            "job " + job.id() + " ended " + v1::Job::State_Name(job.state()) + ": " + job.error();
        return false;
      }
    }
    if (succeeded >= count) return true;
    if (Clock::now() > deadline) {
      *error = std::to_string(succeeded) + " of " + std::to_string(count) + " jobs done in time";
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

// Shuts a completion queue down and drains it, as its destructor requires.
struct ShutDownOnExit {
  grpc::CompletionQueue& queue;
  ~ShutDownOnExit() {
    queue.Shutdown();
    void* tag = nullptr;
    bool ok = false;
    while (queue.Next(&tag, &ok)) {
    }
  }
};

void BM_UnaryLatency(benchmark::State& state) {
  const auto rpc = static_cast<Unary>(state.range(0));
  state.SetLabel(kUnaryNames[state.range(0)]);
  BenchServer server(PBA_SOLVE_BIN, /*max_running=*/1);
  if (!server.error().empty()) return state.SkipWithError(server.error().c_str());
  grpc::Status setup = server.CreateProject();
  if (setup.ok()) setup = server.CreateStructure("cortex", v1::CONTOURS_JSON, kSquareContours);
  if (!setup.ok()) return state.SkipWithError(ErrorText("setup", setup).c_str());
  if (rpc == Unary::kListJobs) {
    std::string error;
    if (!RunTinyJobs(server, kListedJobs, std::chrono::seconds(60), &error)) {
      return state.SkipWithError(error.c_str());
    }
  }

  // Health/Check through the generic stub: its request is empty (zero bytes).
  grpc::GenericStub generic(server.channel());
  grpc::CompletionQueue queue;
  const ShutDownOnExit queue_shutdown{queue};
  const grpc::Slice empty("", 0);
  const grpc::ByteBuffer health_request(&empty, 1);
  auto health = [&]() -> grpc::Status {
    grpc::ClientContext context;
    server.Prepare(&context);
    auto reader =
        generic.PrepareUnaryCall(&context, "/grpc.health.v1.Health/Check", health_request, &queue);
    reader->StartCall();
    grpc::ByteBuffer response;
    grpc::Status status;
    reader->Finish(&response, &status, &response);
    void* tag = nullptr;
    bool ok = false;
    if (!queue.Next(&tag, &ok) || !ok) return grpc::Status(grpc::StatusCode::INTERNAL, "queue");
    return status;
  };

  // One call of the kind measured; its status.
  auto call = [&]() -> grpc::Status {
    switch (rpc) {
      case Unary::kHealth:
        return health();
      case Unary::kWhoAmI: {
        v1::User user;
        return server.Call(server.atlas(), &v1::AtlasService::Stub::WhoAmI, v1::WhoAmIRequest(),
                           &user);
      }
      case Unary::kGetStructure: {
        v1::Structure structure;
        return server.GetStructure("cortex", &structure);
      }
      case Unary::kListJobs: {
        v1::ListJobsResponse response;
        return server.Call(server.jobs(), &v1::JobService::Stub::ListJobs, v1::ListJobsRequest(),
                           &response);
      }
    }
    return grpc::Status(grpc::StatusCode::INTERNAL, "unknown rpc");
  };
  for (int i = 0; i < kUnaryWarmup; ++i) {
    const grpc::Status status = call();
    if (!status.ok()) return state.SkipWithError(ErrorText("warm-up", status).c_str());
  }
  std::vector<double> micros;
  micros.reserve(state.max_iterations);
  for (auto _ : state) {
    const auto start = Clock::now();
    const grpc::Status status = call();
    micros.push_back(1e6 * Seconds(start, Clock::now()));
    if (!status.ok()) {
      return state.SkipWithError(ErrorText(kUnaryNames[state.range(0)], status).c_str());
    }
  }
  state.counters["p50_us"] = Quantile(&micros, 0.50);
  state.counters["p99_us"] = Quantile(&micros, 0.99);
  state.counters["max_us"] = micros.back();
}

BENCHMARK(BM_UnaryLatency)
    ->ArgName("rpc")
    ->DenseRange(0, 3)
    ->Iterations(3000)
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

// --- 2. commit and download of a 50 MiB geometry ---------------------------

constexpr size_t kGeometryBytes = 50 * kMiB;

// A closed binary STL of about `bytes` bytes (the server checks that a
// surface is closed): a sphere of radius 50 mm + `seed` micrometres (so
// every revision is a new blob), 1024 meridians and as many parallels as
// the size asks, fans at the poles.
std::string LargeStl(size_t bytes, uint32_t seed) {
  constexpr int kMeridians = 1024;
  const int parallels =
      std::max<int>(3, static_cast<int>((bytes - 84) / 50 / (2 * kMeridians)) + 1);
  const double radius = 50 + 1e-3 * seed;
  const auto point = [&](int i, int j) -> std::array<float, 3> {
    if (i == 0) return {0, 0, static_cast<float>(radius)};
    if (i == parallels) return {0, 0, static_cast<float>(-radius)};
    const double theta = M_PI * i / parallels, phi = 2 * M_PI * (j % kMeridians) / kMeridians;
    return {static_cast<float>(radius * std::sin(theta) * std::cos(phi)),
            static_cast<float>(radius * std::sin(theta) * std::sin(phi)),
            static_cast<float>(radius * std::cos(theta))};
  };
  std::vector<std::array<std::array<float, 3>, 3>> triangles;
  for (int i = 0; i < parallels; ++i) {
    for (int j = 0; j < kMeridians; ++j) {
      if (i > 0) triangles.push_back({point(i, j), point(i + 1, j), point(i, j + 1)});
      if (i + 1 < parallels)
        triangles.push_back({point(i, j + 1), point(i + 1, j), point(i + 1, j + 1)});
    }
  }
  std::string stl(84 + 50 * triangles.size(), '\0');
  const std::string header = "pba server_bench " + std::to_string(seed);
  std::copy(header.begin(), header.end(), stl.begin());
  const auto count = static_cast<uint32_t>(triangles.size());
  std::memcpy(stl.data() + 80, &count, 4);
  for (size_t t = 0; t < triangles.size(); ++t) {
    std::memcpy(stl.data() + 84 + 50 * t + 12, triangles[t].data(), 36);
  }
  return stl;
}

// Writes `bytes` to a new file at `path` and fsyncs it; the time taken.
bool WriteAndSync(const std::filesystem::path& path, const std::string& bytes, double* seconds) {
  const auto start = Clock::now();
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) return false;
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n <= 0) break;
    done += static_cast<size_t>(n);
  }
  const bool ok = done == bytes.size() && ::fsync(fd) == 0;
  ::close(fd);
  *seconds = Seconds(start, Clock::now());
  return ok;
}

void BM_Geometry50MiB(benchmark::State& state) {
  BenchServer server(PBA_SOLVE_BIN, /*max_running=*/1);
  if (!server.error().empty()) return state.SkipWithError(server.error().c_str());
  grpc::Status setup = server.CreateProject();
  if (setup.ok()) setup = server.CreateStructure("skull", v1::STL, LargeStl(4096, 0));
  v1::Lock lock;
  if (setup.ok()) {
    v1::AcquireLockRequest acquire;
    acquire.set_project(kProject);
    acquire.set_structure("skull");
    acquire.set_lease_seconds(3600);
    setup = server.Call(server.atlas(), &v1::AtlasService::Stub::AcquireLock, acquire, &lock);
  }
  if (!setup.ok()) return state.SkipWithError(ErrorText("setup", setup).c_str());

  // The sphere's size, about kGeometryBytes (a whole number of triangles).
  const double mib = static_cast<double>(LargeStl(kGeometryBytes, 0).size()) / kMiB;
  double upload_s = 0, commit_s = 0, download_s = 0, first_chunk_s = 0, hash_s = 0, check_s = 0;
  int64_t head = 1;
  uint32_t seed = 1;
  for (auto _ : state) {
    // The content and its hash are the client's work before it sends: not timed.
    state.PauseTiming();
    const std::string content = LargeStl(kGeometryBytes, seed++);
    const auto hash_start = Clock::now();
    const std::string hash = Sha256Hex(content);
    hash_s += Seconds(hash_start, Clock::now());
    // The server's surface check of the same content, alone.
    const auto check_start = Clock::now();
    if (!CheckGeometryContent("upload_id", StructureFormat::kStl, content).ok()) {
      return state.SkipWithError("the sphere is not a closed surface");
    }
    check_s += Seconds(check_start, Clock::now());
    state.ResumeTiming();

    const auto start = Clock::now();
    v1::CommitStructureRequest commit;
    grpc::Status status = server.Upload(content, hash, commit.mutable_upload_id());
    if (!status.ok()) return state.SkipWithError(ErrorText("upload", status).c_str());
    const auto uploaded = Clock::now();
    commit.set_project(kProject);
    commit.set_structure("skull");
    commit.set_lock_id(lock.lock_id());
    commit.set_base_revision(head);
    commit.set_format(v1::STL);
    commit.set_message("a new surface");
    v1::Revision revision;
    status =
        server.Call(server.atlas(), &v1::AtlasService::Stub::CommitStructure, commit, &revision);
    if (!status.ok()) return state.SkipWithError(ErrorText("CommitStructure", status).c_str());
    head = revision.number();
    const auto committed = Clock::now();

    grpc::ClientContext context;
    server.Prepare(&context);
    v1::DownloadGeometryRequest download;
    download.set_project(kProject);
    download.set_structure("skull");
    auto reader = server.atlas().DownloadGeometry(&context, download);
    std::string received;
    received.reserve(kGeometryBytes);
    v1::DataChunk chunk;
    Clock::time_point first_chunk;
    while (reader->Read(&chunk)) {
      if (received.empty()) first_chunk = Clock::now();
      received.append(chunk.data());
    }
    status = reader->Finish();
    const auto downloaded = Clock::now();
    if (!status.ok()) return state.SkipWithError(ErrorText("DownloadGeometry", status).c_str());
    if (received != content) return state.SkipWithError("the download differs from the commit");

    upload_s += Seconds(start, uploaded);
    commit_s += Seconds(uploaded, committed);
    download_s += Seconds(committed, downloaded);
    first_chunk_s += Seconds(committed, first_chunk);
  }
  // The disk under the data directory, for comparison: the same bytes
  // written to a file there and fsynced, as the blob store does.
  double fsync_s = 0;
  if (!WriteAndSync(server.dir() / "fsync-reference", LargeStl(kGeometryBytes, 0), &fsync_s)) {
    return state.SkipWithError("cannot write the fsync reference file");
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["upload_MiB_per_s"] = mib * n / upload_s;
  state.counters["commit_rpc_s"] = commit_s / n;
  state.counters["commit_MiB_per_s"] = mib * n / (upload_s + commit_s);
  state.counters["download_MiB_per_s"] = mib * n / download_s;
  state.counters["download_first_chunk_s"] = first_chunk_s / n;
  state.counters["sha256_s"] = hash_s / n;
  state.counters["surface_check_s"] = check_s / n;
  state.counters["write_fsync_s"] = fsync_s;
}

BENCHMARK(BM_Geometry50MiB)->Iterations(3)->Unit(benchmark::kMillisecond)->UseRealTime();

// --- 3. trivial jobs per minute ----------------------------------------------

constexpr int kJobs = 40;

void BM_TinyJobsPerMinute(benchmark::State& state) {
  BenchServer server(PBA_SOLVE_BIN, /*max_running=*/2);
  if (!server.error().empty()) return state.SkipWithError(server.error().c_str());
  double seconds = 0;
  for (auto _ : state) {
    const auto start = Clock::now();
    std::string error;
    if (!RunTinyJobs(server, kJobs, std::chrono::seconds(90), &error)) {
      return state.SkipWithError(error.c_str());
    }
    seconds = Seconds(start, Clock::now());
  }
  // Where a job's time goes: from its start to its end on the server.
  v1::ListJobsRequest list;
  list.set_page_size(500);
  v1::ListJobsResponse response;
  const grpc::Status status =
      server.Call(server.jobs(), &v1::JobService::Stub::ListJobs, list, &response);
  if (!status.ok()) return state.SkipWithError(ErrorText("ListJobs", status).c_str());
  std::vector<double> run_ms;
  for (const v1::Job& job : response.jobs()) {
    const auto micros = [](const google::protobuf::Timestamp& t) {
      return 1e6 * static_cast<double>(t.seconds()) + 1e-3 * t.nanos();
    };
    run_ms.push_back(1e-3 * (micros(job.end_time()) - micros(job.start_time())));
  }
  state.counters["jobs"] = kJobs;
  state.counters["jobs_per_min"] = 60.0 * kJobs / seconds;
  state.counters["run_p50_ms"] = Quantile(&run_ms, 0.50);
  state.counters["run_p99_ms"] = Quantile(&run_ms, 0.99);
}

BENCHMARK(BM_TinyJobsPerMinute)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

// --- 4. Watch fan-out ---------------------------------------------------------

constexpr int kWatchers = 50;
constexpr int kChanges = 200;

// When each watcher received each METADATA_UPDATED event, by revision.
class Receipts {
 public:
  void Ready() {
    std::lock_guard lock(mutex_);
    ++ready_;
    changed_.notify_all();
  }
  void Received(int64_t revision) {
    const auto now = Clock::now();
    std::lock_guard lock(mutex_);
    auto& times = by_revision_[revision];
    times.push_back(now);
    ++total_;
    changed_.notify_all();
  }
  // Waits until `count` watchers are ready.
  bool WaitReady(int count, std::chrono::seconds timeout) {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, timeout, [&] { return ready_ >= count; });
  }
  // Waits until `count` receipts of `revision`; the last receipt's time.
  bool WaitAll(int64_t revision, int count, std::chrono::seconds timeout, Clock::time_point* last) {
    std::unique_lock lock(mutex_);
    const bool all = changed_.wait_for(lock, timeout, [&] {
      auto it = by_revision_.find(revision);
      return it != by_revision_.end() && static_cast<int>(it->second.size()) >= count;
    });
    if (!all) return false;
    const std::vector<Clock::time_point>& times = by_revision_[revision];
    *last = *std::max_element(times.begin(), times.end());
    return true;
  }
  int64_t total() {
    std::lock_guard lock(mutex_);
    return total_;
  }

 private:
  std::mutex mutex_;
  std::condition_variable changed_;
  int ready_ = 0;
  int64_t total_ = 0;
  std::map<int64_t, std::vector<Clock::time_point>> by_revision_;
};

void BM_WatchFanOut(benchmark::State& state) {
  BenchServer server(PBA_SOLVE_BIN, /*max_running=*/1);
  if (!server.error().empty()) return state.SkipWithError(server.error().c_str());
  grpc::Status setup = server.CreateProject();
  if (setup.ok()) setup = server.CreateStructure("cortex", v1::CONTOURS_JSON, kSquareContours);
  if (!setup.ok()) return state.SkipWithError(ErrorText("setup", setup).c_str());

  Receipts receipts;
  std::vector<std::unique_ptr<grpc::ClientContext>> contexts;
  std::vector<std::thread> watchers;
  std::atomic<int> failed_streams{0};
  for (int w = 0; w < kWatchers; ++w) {
    contexts.push_back(std::make_unique<grpc::ClientContext>());
    server.Prepare(contexts.back().get(), std::chrono::seconds(600));
    watchers.emplace_back([&, context = contexts.back().get()] {
      // Each watcher its own connection, as 50 people would have.
      const auto stub = v1::AtlasService::NewStub(server.NewChannel());
      v1::WatchRequest request;
      request.set_project(kProject);
      auto reader = stub->Watch(context, request);
      v1::AtlasEvent event;
      while (reader->Read(&event)) {
        if (event.kind() == v1::AtlasEvent::READY) receipts.Ready();
        if (event.kind() == v1::AtlasEvent::METADATA_UPDATED) receipts.Received(event.revision());
      }
      const grpc::Status status = reader->Finish();
      if (status.error_code() != grpc::StatusCode::CANCELLED) ++failed_streams;
    });
  }
  // Ends the streams and joins their threads.
  auto stop = [&] {
    for (auto& context : contexts) context->TryCancel();
    for (auto& thread : watchers) thread.join();
  };
  if (!receipts.WaitReady(kWatchers, std::chrono::seconds(30))) {
    stop();
    return state.SkipWithError("not every watcher got READY in 30 s");
  }

  std::vector<double> fan_out_ms;    // from the updater's answer
  std::vector<double> from_send_ms;  // from the updater's request
  int before_answer = 0;             // changes the last watcher had before the answer
  std::string error;
  int change = 0;
  for (auto _ : state) {
    for (int i = 0; i < kChanges && error.empty(); ++i, ++change) {
      v1::Structure structure;
      grpc::Status status = server.GetStructure("cortex", &structure);
      v1::UpdateMetadataRequest update;
      update.set_project(kProject);
      update.set_structure("cortex");
      update.set_etag(structure.metadata_etag());
      update.set_group_path("cerebrum/part" + std::to_string(change));
      update.set_message("regrouped");
      v1::UpdateMetadataResponse response;
      const auto sent = Clock::now();
      if (status.ok()) {
        status =
            server.Call(server.atlas(), &v1::AtlasService::Stub::UpdateMetadata, update, &response);
      }
      const auto returned = Clock::now();
      if (!status.ok()) {
        error = ErrorText("UpdateMetadata", status);
        break;
      }
      // One change at a time: the next starts when every watcher has this
      // one, so each latency is the fan-out of one event.
      Clock::time_point last;
      if (!receipts.WaitAll(response.revision().number(), kWatchers, std::chrono::seconds(10),
                            &last)) {
        error = "revision " + std::to_string(response.revision().number()) +
                " did not reach every watcher in 10 s";
        break;
      }
      // The server publishes before it answers, so the last watcher can
      // have the event before the updater has its answer: counted as 0.
      if (last <= returned) ++before_answer;
      fan_out_ms.push_back(std::max(0.0, 1e3 * Seconds(returned, last)));
      from_send_ms.push_back(1e3 * Seconds(sent, last));
    }
  }
  // Late or duplicate deliveries would show in the total.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  stop();
  if (!error.empty()) return state.SkipWithError(error.c_str());
  const int64_t expected = static_cast<int64_t>(kWatchers) * change;
  if (receipts.total() != expected || failed_streams > 0) {
    const std::string message = std::to_string(receipts.total()) + " events delivered, expected " +
                                std::to_string(expected) + "; " +
                                std::to_string(failed_streams.load()) + " streams failed";
    return state.SkipWithError(message.c_str());
  }
  state.counters["watchers"] = kWatchers;
  state.counters["changes"] = change;
  state.counters["events"] = static_cast<double>(receipts.total());
  state.counters["p50_ms"] = Quantile(&fan_out_ms, 0.50);
  state.counters["p99_ms"] = Quantile(&fan_out_ms, 0.99);
  state.counters["before_answer"] = before_answer;
  state.counters["send_p50_ms"] = Quantile(&from_send_ms, 0.50);
  state.counters["send_p99_ms"] = Quantile(&from_send_ms, 0.99);
}

BENCHMARK(BM_WatchFanOut)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace
}  // namespace pba

BENCHMARK_MAIN();
