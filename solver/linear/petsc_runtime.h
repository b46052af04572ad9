// The process's PETSc (and MPI, when nobody started it): started on first
// use, finished at exit. PETSc is not thread-safe, so every use holds
// PetscLock; its errors come back as codes (never printed, never aborting)
// and PBA_PETSC turns them into Status.
#pragma once

#include <mutex>
#include <string>

#include "pba/status.h"

namespace pba {

// Starts PETSc once per process: MPI_Init_thread (serialized) when MPI is
// not running yet, then PetscInitialize without PETSc's signal handlers
// (the process keeps its own: pba-solve's SIGTERM cancels the run), without
// reading ~/.petscrc, and with the options database then cleared, so that
// PETSC_OPTIONS in the environment cannot change an answer: a scene's
// options are the only ones. Both are finished at exit. Idempotent and
// thread-safe; a failure is remembered and returned again.
Status InitializePetsc();

// The processes a solve runs on. A process launched by mpirun or srun
// (their environment says so) is one rank of MPI_COMM_WORLD; every rank
// runs the same solve, and the PETSc backends then share each linear solve
// between them (petsc_solver.cc). Any other process is rank 0 of 1.
struct ProcessRanks {
  int rank = 0;
  int size = 1;
  int on_node = 1;  // ranks on this machine (MPI's shared-memory split)
};

// Whether this process was launched as a rank of an MPI job (mpirun, srun).
bool LaunchedAsMpiRank();

// For a process LaunchedAsMpiRank: starts MPI and PETSc (InitializePetsc)
// now, so that every later decision knows the ranks, and reports them.
// Otherwise starts nothing and reports rank 0 of 1.
Status StartRanks(ProcessRanks* ranks);

// The ranks as they stand: MPI_COMM_WORLD's once MPI runs, else rank 0 of 1.
ProcessRanks CurrentRanks();

// The memory one solve may take on this machine [bytes]: its physical
// memory, or less where an address-space limit bounds each process
// (RLIMIT_AS: pba-server's --solver-memory), that limit times the ranks on
// the machine. Across the ranks of an MPI job the least of their figures,
// so that every rank decides alike: a collective call then, made by every
// rank at the same point.
double SolveMemoryBytes();

// Across the ranks of an MPI job, each of `count` values becomes the sum
// (SumOverRanks) or the largest (MaxOverRanks) of the ranks' values, on
// every rank: collective calls, made by every rank at the same point. A
// partitioned assembly adds up its rows with the sum, each entry having
// one nonzero term, so the result is exact and alike on every rank. In a
// process of its own they change nothing. They take PetscLock.
Status SumOverRanks(double* values, int count);
Status MaxOverRanks(int* values, int count);

// Ends the whole MPI job with `code` (MPI_Abort) when this process is one
// of several ranks: one rank's failure must not leave the others waiting
// for it in a collective call. Otherwise returns.
void AbortOtherRanks(int code);

// Held around every sequence of PETSc calls.
std::unique_lock<std::mutex> PetscLock();

// "PETSc error 73 (Object is in wrong state) in KSPSolve" for a failed call.
Status PetscFailure(int code, const char* call);

}  // namespace pba

// Runs a PETSc call and returns its failure as Status::Internal.
#define PBA_PETSC(call)                                                           \
  do {                                                                            \
    const int pba_petsc_code_ = static_cast<int>(call);                           \
    if (pba_petsc_code_ != 0) return ::pba::PetscFailure(pba_petsc_code_, #call); \
  } while (false)
