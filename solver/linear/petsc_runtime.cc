#include "linear/petsc_runtime.h"

#include <mpi.h>
#include <petscsys.h>

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

std::unique_lock<std::mutex> PetscLock() { return std::unique_lock<std::mutex>(Mutex()); }

Status PetscFailure(int code, const char* call) {
  const char* text = nullptr;
  PetscErrorMessage(code, &text, nullptr);
  return Status::Internal(
      Format("PETSc error %d (%s) in %s", code, text != nullptr ? text : "unknown", call));
}

}  // namespace pba
