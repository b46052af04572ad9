// Element updates per second of the explicit engine's internal force
// (TledModel::InternalForce) on 1 and 2 threads, beside the memory
// bandwidth of the same machine measured in the same run by a STREAM triad
// a[i] = b[i] + s c[i] (McCalpin; 24 bytes per element of a, arrays of at
// least 4 times the last-level cache each). A benchmark, not a test:
// scripts/bench.sh runs it for docs/performance.md.
//
// The meshes: a cube of 36 mm cut into 1 mm cells, 6 tetrahedra each
// (279,936 TET4_ANP or TET4 elements, 50,653 nodes), and a cube of 66 mm of
// 1 mm bricks (287,496 HEX8, 300,763 nodes); one neo-Hookean material
// (mu = 1 kPa, K = 1 MPa, 1040 kg/m^3). Their per-element arrays (about
// 0.37 kB a tetrahedron, 104 MB in all; 0.82 kB a brick, 236 MB) are 3 and 7
// times a last-level cache of 32 MiB.
// The state is a smooth displacement (strains of a few per cent) and a
// smooth velocity that compresses about half the elements, so that every
// path (nodal pressure, bulk viscosity, hourglass control) runs.
//
// parallel_check, measured after each row, says whether the machine gave
// the benchmark both cores (ParallelCheck).
//
// Rates: mean_updates_per_s over all the row's evaluations, and
// best_updates_per_s of the fastest one (from which the implied bandwidth and
// its fraction of the triad's, itself the best of 20 passes).
//
// bytes_per_update is a model, not a measurement: what the kernel must move
// between memory and the cores per element at the least, every per-element
// array it reads or writes counted once per pass that touches it (a write as
// one transfer, as STREAM counts it), and the nodal arrays (u, v, the nodal
// pressures, f_int, the CSR offsets) once per pass, shared among the
// elements (nodes / elements of them each). See BytesPerUpdate.
#include <benchmark/benchmark.h>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <numbers>
#include <vector>

#include "explicit/explicit_setup.h"
#include "explicit/tled_model.h"
#include "pba/scene.h"
#include "scene/model_builder.h"

namespace pba {
namespace {

constexpr ElementType kElements[] = {ElementType::kTet4Anp, ElementType::kTet4, ElementType::kHex8};
constexpr const char* kElementNames[] = {"TET4_ANP", "TET4", "HEX8"};
constexpr int kCellsPerEdge[] = {36, 36, 66};

struct Case {
  Problem problem;
  ExplicitSetup setup;
  Eigen::VectorXd u, v, f;
};

// Builds the cube of element kind k once per process.
Case& CaseOf(int k) {
  static std::unique_ptr<Case> cases[3];
  if (cases[k]) return *cases[k];
  auto c = std::make_unique<Case>();
  const double edge = kCellsPerEdge[k];
  SceneSpec s;
  s.name = "tled-bench";
  s.geometry.kind = GeometrySpec::Kind::kBox;
  s.geometry.box.size_mm = {edge, edge, edge};
  s.mesh.element = kElements[k];
  s.mesh.element_size_mm = 1;
  s.material.kind = MaterialSpec::Kind::kNeoHookean;
  s.material.neo_hookean = {1000, 1e6};
  s.material.density_kg_per_m3 = 1040;
  BoundaryConditionSpec bottom;
  bottom.set = "bottom";
  bottom.kind = BoundaryConditionSpec::Kind::kFixed;
  s.boundary_conditions = {bottom};
  s.analysis.type = AnalysisSpec::Type::kExplicitDynamic;
  s.analysis.time.end_time_s = 1e-3;
  Status status = BuildProblem(s, BuildModelOptions(), &c->problem);
  if (status.ok()) status = MakeExplicitSetup(c->problem, &c->setup);
  if (!status.ok()) {
    std::fprintf(stderr, "tled_bench: %s\n", status.ToString().c_str());
    std::exit(1);
  }
  // u_i = 0.02 L sin(pi (X_i + X_(i+1)) / L), v_i = cos(2 pi X_i / L + i)
  // [m/s]: div v changes sign across the cube.
  const auto& x = c->problem.model.mesh.nodes;
  const double l = edge * 1e-3, pi = std::numbers::pi;
  c->u.resize(3 * x.rows());
  c->v.resize(3 * x.rows());
  for (Eigen::Index n = 0; n < x.rows(); ++n) {
    for (int i = 0; i < 3; ++i) {
      c->u(3 * n + i) = 0.02 * l * std::sin(pi * (x(n, i) + x(n, (i + 1) % 3)) / l);
      c->v(3 * n + i) = std::cos(2 * pi * x(n, i) / l + i);
    }
  }
  cases[k] = std::move(c);
  return *cases[k];
}

// The model of the bytes moved per element update (see the file comment),
// item by item from tled_model.cc; nodal arrays as 8-byte doubles or 4-byte
// ints per node, spread over the elements (one material: one nodal
// pressure group per node).
double BytesPerUpdate(const TledModel& t, bool anp) {
  const double npe = t.nodes_per_element();
  const double per_node = static_cast<double>(t.num_nodes()) / t.num_elements();
  const double conn = 4 * npe, grad = 24 * npe, force = 24 * npe, nodal = 24 * per_node;
  double bytes = 0;
  if (anp) {
    // Pass 1, V0 J: nodes, gradients, V0, u gathered; V0 J written.
    bytes += conn + grad + 8 + nodal + 8;
    // Pass 2, the nodal pressures: per group its offset, V0 sum, material
    // and pressure (written); its elements, and their V0 J.
    bytes += (4 + 8 + 4 + 8) * per_node + 4 * npe + 8;
    // Pass 3 reads them through each corner's group.
    bytes += 4 * npe + 8 * per_node;
  }
  // Pass 3, the element pass: nodes, gradients, material, V0, length, u and
  // v gathered; F (9 doubles), J, the pressure and the force buffer written.
  bytes += conn + grad + 4 + 8 + 8 + 2 * nodal + 72 + 8 + 8 + force;
  if (npe == 8) bytes += 8 * 32 + 8;  // gamma and the hourglass stiffness
  // Pass 4, the gather: offsets, corners, the force buffer read, f_int written.
  bytes += 4 * per_node + 4 * npe + force + nodal;
  return bytes;
}

// The last-level cache [bytes]: the kernel's own report (sysfs) first, as
// glibc's sysconf may count the host's caches rather than the guest's.
long LastLevelCache() {
  long size = 0;
  if (FILE* f = std::fopen("/sys/devices/system/cpu/cpu0/cache/index3/size", "r")) {
    char unit = 0;
    if (std::fscanf(f, "%ld%c", &size, &unit) == 2 && unit == 'K') size <<= 10;
    std::fclose(f);
  }
  if (size <= 0) size = sysconf(_SC_LEVEL3_CACHE_SIZE);
  return size > 0 ? size : 32L << 20;
}

// The STREAM triad's bandwidth on `threads` threads [bytes/s], the best of
// 20 passes over three arrays of max(4 x last-level cache, 64 MiB) each,
// each thread first touching its own part.
double TriadBandwidth(int threads) {
  static double cached[3] = {0, 0, 0};
  if (cached[threads] > 0) return cached[threads];
  const std::size_t n = std::max<std::size_t>(4 * LastLevelCache(), 64UL << 20) / sizeof(double);
  const auto a = std::make_unique_for_overwrite<double[]>(n);
  const auto b = std::make_unique_for_overwrite<double[]>(n);
  const auto c = std::make_unique_for_overwrite<double[]>(n);
  omp_set_num_threads(threads);
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < n; ++i) a[i] = 0, b[i] = 1, c[i] = 2;
  const double s = 3;
  double best = 1e30;
  for (int rep = 0; rep < 20; ++rep) {
    const auto t0 = std::chrono::steady_clock::now();
    double* pa = a.get();
    const double* pb = b.get();
    const double* pc = c.get();
#pragma omp parallel for schedule(static)
    for (std::size_t i = 0; i < n; ++i) pa[i] = pb[i] + s * pc[i];
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    best = std::min(best, dt);
  }
  benchmark::DoNotOptimize(a[n / 2]);
  cached[threads] = 24.0 * static_cast<double>(n) / best;
  return cached[threads];
}

// The speed-up of a loop of pure arithmetic (independent multiply-add
// chains, no memory traffic) from 1 to 2 threads, the best of 3 tries each:
// about 2 when both cores were the benchmark's, about 1 when another process
// held one (a shared machine), which the rows' 2-thread figures then show.
double ParallelCheck() {
  const auto seconds = [](int threads) {
    omp_set_num_threads(threads);
    double best = 1e30;
    for (int rep = 0; rep < 3; ++rep) {
      const auto t0 = std::chrono::steady_clock::now();
      double sum = 0;
#pragma omp parallel for schedule(static) reduction(+ : sum)
      for (int chain = 0; chain < 8; ++chain) {
        double x = 1 + chain;
        for (int i = 0; i < 5'000'000; ++i) x = x * 1.0000001 + 1e-9;
        sum += x;
      }
      benchmark::DoNotOptimize(sum);
      best = std::min(best,
                      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    return best;
  };
  return seconds(1) / seconds(2);
}

// Arguments: threads.
void BM_Triad(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  double bandwidth = 0;
  for (auto _ : state) bandwidth = TriadBandwidth(threads);
  state.counters["array_MiB"] =
      static_cast<double>(std::max<std::size_t>(4 * LastLevelCache(), 64UL << 20) >> 20);
  state.counters["triad_GB_per_s"] = bandwidth / 1e9;
}

// Arguments: the element (index into kElements); threads.
void BM_InternalForce(benchmark::State& state) {
  const int k = static_cast<int>(state.range(0)), threads = static_cast<int>(state.range(1));
  const double triad = TriadBandwidth(threads);
  Case& c = CaseOf(k);
  TledModel& t = *c.setup.tled;
  t.SetThreads(ThreadContext(threads));
  t.InternalForce(c.u, c.v, &c.f);  // first touch of f and the buffers
  double seconds = 0, fastest = 1e30;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const TledEvaluation eval = t.InternalForce(c.u, c.v, &c.f);
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    seconds += dt;
    fastest = std::min(fastest, dt);
    benchmark::DoNotOptimize(eval);
    benchmark::ClobberMemory();
  }
  state.SetLabel(kElementNames[k]);
  const double elements = t.num_elements();
  const double best = elements / fastest;
  const double bytes = BytesPerUpdate(t, kElements[k] == ElementType::kTet4Anp);
  state.counters["elements"] = elements;
  state.counters["mean_updates_per_s"] = elements * state.iterations() / seconds;
  // The fastest evaluation, as STREAM reports its fastest pass: on a shared
  // machine the mean is the other processes' as much as the kernel's.
  state.counters["best_updates_per_s"] = best;
  state.counters["bytes_per_update"] = bytes;
  state.counters["implied_GB_per_s"] = best * bytes / 1e9;
  state.counters["triad_GB_per_s"] = triad / 1e9;
  state.counters["of_triad"] = best * bytes / triad;
  state.counters["parallel_check"] = ParallelCheck();
}

BENCHMARK(BM_Triad)->ArgName("threads")->Arg(1)->Arg(2)->Iterations(1)->UseRealTime();

BENCHMARK(BM_InternalForce)
    ->ArgNames({"element", "threads"})
    ->ArgsProduct({{0, 1, 2}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);

}  // namespace
}  // namespace pba

BENCHMARK_MAIN();
