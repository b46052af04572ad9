#include "linear/petsc_runtime.h"

#include <mpi.h>
#include <petscsys.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <iterator>

#include "core/format.h"

namespace pba {
namespace {

std::mutex& Mutex() {
  static std::mutex mutex;
  return mutex;
}

bool started_mpi = false;  // this process's MPI was started here (and is finished here)
int ranks_on_node = 1;     // found at the start (a collective call, made by every rank then)

void FinishAtExit() {
  const std::lock_guard<std::mutex> lock(Mutex());
  PetscBool running = PETSC_FALSE;
  if (PetscInitialized(&running) == 0 && running) PetscFinalize();
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (started_mpi && !finalized) MPI_Finalize();
}

// The signals whose handling belongs to the process (pba-solve cancels on
// SIGTERM, and crash handlers print where it stopped); MPI and PETSc may
// install their own at start, so these are put back. SIGCHLD stays MPI's.
constexpr int kOwnSignals[] = {SIGTERM, SIGINT, SIGHUP, SIGQUIT, SIGPIPE, SIGUSR1, SIGUSR2,
                               SIGSEGV, SIGBUS, SIGFPE, SIGILL,  SIGABRT, SIGALRM};

Status Start() {
  struct sigaction saved[std::size(kOwnSignals)];
  for (std::size_t i = 0; i < std::size(kOwnSignals); ++i) {
    sigaction(kOwnSignals[i], nullptr, &saved[i]);
  }
  int mpi_running = 0;
  MPI_Initialized(&mpi_running);
  if (!mpi_running) {
    // Several threads may use PETSc, one at a time (PetscLock).
    int provided = 0;
    if (MPI_Init_thread(nullptr, nullptr, MPI_THREAD_SERIALIZED, &provided) != MPI_SUCCESS) {
      return Status::Internal("MPI could not be started for PETSc");
    }
    started_mpi = true;
  }
  MPI_Comm node = MPI_COMM_NULL;
  if (MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node) ==
      MPI_SUCCESS) {
    MPI_Comm_size(node, &ranks_on_node);
    MPI_Comm_free(&node);
  }
  static char program[] = "pba";
  static char skip_rc[] = "-skip_petscrc";
  static char no_handler[] = "-no_signal_handler";
  static char* args[] = {program, skip_rc, no_handler, nullptr};
  int argc = 3;
  char** argv = args;
  const PetscErrorCode code = PetscInitialize(&argc, &argv, nullptr, nullptr);
  for (std::size_t i = 0; i < std::size(kOwnSignals); ++i) {
    sigaction(kOwnSignals[i], &saved[i], nullptr);
  }
  if (code != 0) return Status::Internal(Format("PETSc could not be started (error %d)", code));
  // Errors come back as codes, quietly: PBA reports them as Status.
  PetscPushErrorHandler(PetscReturnErrorHandler, nullptr);
  // What PETSC_OPTIONS or the command line put in the options database is
  // dropped: every option a solve uses is set by PBA from the scene.
  PetscOptionsClear(nullptr);
  std::atexit(FinishAtExit);
  return Status::Ok();
}

}  // namespace

Status InitializePetsc() {
  static const Status started = [] {
    const std::lock_guard<std::mutex> lock(Mutex());
    return Start();
  }();
  return started;
}

bool LaunchedAsMpiRank() {
  // Open MPI's mpirun, PMIx (srun --mpi=pmix, mpirun of other MPIs), PMI-2.
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_SIZE"}) {
    if (std::getenv(name) != nullptr) return true;
  }
  return false;
}

ProcessRanks CurrentRanks() {
  ProcessRanks ranks;
  int initialized = 0, finalized = 0;
  MPI_Initialized(&initialized);
  MPI_Finalized(&finalized);
  if (!initialized || finalized) return ranks;
  MPI_Comm_rank(MPI_COMM_WORLD, &ranks.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks.size);
  ranks.on_node = std::max(1, ranks_on_node);
  return ranks;
}

Status StartRanks(ProcessRanks* ranks) {
  *ranks = ProcessRanks();
  if (!LaunchedAsMpiRank()) return Status::Ok();
  PBA_RETURN_IF_ERROR(InitializePetsc());
  *ranks = CurrentRanks();
  return Status::Ok();
}

double SolveMemoryBytes() {
  const ProcessRanks ranks = CurrentRanks();
  const double physical =
      static_cast<double>(::sysconf(_SC_PHYS_PAGES)) * static_cast<double>(::sysconf(_SC_PAGESIZE));
  double memory = physical > 0 ? physical : 0;
  struct rlimit space {};
  if (::getrlimit(RLIMIT_AS, &space) == 0 && space.rlim_cur != RLIM_INFINITY) {
    memory = std::min(memory, static_cast<double>(space.rlim_cur) * ranks.on_node);
  }
  if (ranks.size > 1) {
    double least = memory;
    if (MPI_Allreduce(&memory, &least, 1, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD) == MPI_SUCCESS) {
      memory = least;
    }
  }
  return memory;
}

Status SumOverRanks(double* values, int count) {
  if (CurrentRanks().size <= 1) return Status::Ok();
  const auto lock = PetscLock();
  if (MPI_Allreduce(MPI_IN_PLACE, values, count, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD) !=
      MPI_SUCCESS) {
    return Status::Internal("the MPI ranks could not add up their values");
  }
  return Status::Ok();
}

Status MaxOverRanks(int* values, int count) {
  if (CurrentRanks().size <= 1) return Status::Ok();
  const auto lock = PetscLock();
  if (MPI_Allreduce(MPI_IN_PLACE, values, count, MPI_INT, MPI_MAX, MPI_COMM_WORLD) != MPI_SUCCESS) {
    return Status::Internal("the MPI ranks could not compare their values");
  }
  return Status::Ok();
}

void AbortOtherRanks(int code) {
  if (CurrentRanks().size > 1) MPI_Abort(MPI_COMM_WORLD, code);
}

std::unique_lock<std::mutex> PetscLock() { return std::unique_lock<std::mutex>(Mutex()); }

Status PetscFailure(int code, const char* call) {
  const char* text = nullptr;
  PetscErrorMessage(code, &text, nullptr);
  return Status::Internal(
      Format("PETSc error %d (%s) in %s", code, text != nullptr ? text : "unknown", call));
}

}  // namespace pba
