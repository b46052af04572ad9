#include "core/thread_context.h"

#include <dlfcn.h>
#include <omp.h>

#include <algorithm>

namespace pba {
namespace {

// OpenBLAS's thread count, found in the process at run time: the BLAS is
// chosen by the system (Debian's libblas.so.3 alternative), and the
// reference BLAS or another library has no such functions. Both null when
// the BLAS is not OpenBLAS.
struct OpenBlasThreads {
  using Get = int (*)();
  using Set = void (*)(int);
  Get get = nullptr;
  Set set = nullptr;
};

const OpenBlasThreads& FindOpenBlas() {
  static const OpenBlasThreads found = [] {
    OpenBlasThreads f;
    f.get =
        reinterpret_cast<OpenBlasThreads::Get>(::dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
    f.set =
        reinterpret_cast<OpenBlasThreads::Set>(::dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
    if (f.get == nullptr || f.set == nullptr) f = OpenBlasThreads();
    return f;
  }();
  return found;
}

}  // namespace

ThreadContext::ThreadContext() : threads_(std::max(1, omp_get_max_threads())) {}

ThreadContext::ThreadContext(int threads) : ThreadContext() {
  if (threads > 0) threads_ = threads;
}

LibraryThreadScope::LibraryThreadScope(const ThreadContext& context)
    : omp_threads_(omp_get_max_threads()), omp_dynamic_(omp_get_dynamic()), blas_threads_(0) {
  omp_set_dynamic(1);
  omp_set_num_threads(context.threads());
  const OpenBlasThreads& blas = FindOpenBlas();
  if (blas.set == nullptr) return;
  const int before = blas.get();
  if (before > context.threads()) {
    blas.set(context.threads());
    blas_threads_ = before;
  }
}

LibraryThreadScope::~LibraryThreadScope() {
  omp_set_num_threads(omp_threads_);
  omp_set_dynamic(omp_dynamic_);
  if (blas_threads_ > 0) FindOpenBlas().set(blas_threads_);
}

}  // namespace pba
