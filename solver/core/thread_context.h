// ThreadContext: how many threads a solve may use, made once from
// SolveOptions::threads (SolveScene) and passed down with the Problem, as
// Ceres passes its ContextImpl. The solver's own OpenMP loops name it in
// their clauses,
//
//   #pragma omp parallel for num_threads(ctx.threads()) if (ctx.Parallel(n))
//
// and a call into a library that starts threads of its own (CHOLMOD,
// OpenBLAS) runs inside a LibraryThreadScope. Nothing sets OpenMP or BLAS
// state for good: two solves in one process may use different counts.
#pragma once

#include <cstddef>

namespace pba {

// Below this many items (elements, nodes, the elements of one colour) a
// loop runs on the calling thread: a Newton solve on a small mesh makes
// thousands of passes, and starting a team costs more than such a pass
// (milliseconds when the threads are oversubscribed).
inline constexpr int kMinParallelWork = 256;

class ThreadContext {
 public:
  // As many threads as OpenMP gives the calling thread: OMP_NUM_THREADS,
  // else one per core.
  ThreadContext();
  // `threads` threads; 0 as ThreadContext().
  explicit ThreadContext(int threads);

  // At least 1.
  int threads() const { return threads_; }
  // Whether a loop over `work` items is worth a team of threads.
  bool Parallel(std::size_t work) const {
    return threads_ > 1 && work >= static_cast<std::size_t>(kMinParallelWork);
  }

 private:
  int threads_;
};

// For its lifetime, bounds the threads of the libraries called from this
// thread by `context`, and restores what was there before:
//   - OpenMP: this thread's team size (nthreads-var) with dynamic teams
//     (dyn-var). CHOLMOD 3 asks for a fixed team of 4 (num_threads(4), its
//     compile-time CHOLMOD_OMP_NUM_THREADS), which only a dynamic team
//     bounded by nthreads-var keeps within the count; dynamic teams also
//     shrink on a loaded machine instead of oversubscribing it;
//   - OpenBLAS (CHOLMOD's supernodal factorisation calls BLAS and LAPACK):
//     openblas_set_num_threads, looked up at run time so that any other
//     BLAS the system provides still links; never raised above what
//     OpenBLAS had (OPENBLAS_NUM_THREADS is respected).
// OpenBLAS keeps one count per process: solves in one process that run
// at the same time with different counts share the one set last.
class LibraryThreadScope {
 public:
  explicit LibraryThreadScope(const ThreadContext& context);
  ~LibraryThreadScope();
  LibraryThreadScope(const LibraryThreadScope&) = delete;
  LibraryThreadScope& operator=(const LibraryThreadScope&) = delete;

 private:
  int omp_threads_;
  int omp_dynamic_;
  int blas_threads_;  // 0: no OpenBLAS, or left as it was
};

}  // namespace pba
