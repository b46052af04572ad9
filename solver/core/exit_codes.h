// The exit codes of pba, pba-solve and pba-atlas: one table, so that a
// number means one thing whichever program returns it (docs/cli.md, "Exit
// codes", lists them with the programs that can return each). pba's 0-10 are
// kept as scripts know them; the solver programs' own outcomes follow them.
#pragma once

#include <span>

#include "pba/status.h"

namespace pba {

// A plain enum: main() returns these, and callers compare them with ints.
enum ExitCode : int {
  kExitOk = 0,
  kExitError = 1,        // any other error, a bug included; the message says what
  kExitUsage = 2,        // bad command line (an unknown option, a missing argument)
  kExitUnavailable = 3,  // pba: the server could not be reached
  kExitNotFound = 4,     // pba: no such job or file
  kExitInvalid = 5,      // the input was rejected (a bad scene, option value or atlas source)
  kExitJobFailed = 6,    // pba: the job ended FAILED
  kExitCancelled = 7,    // pba: the job ended CANCELLED; pba-solve: stopped by SIGTERM/SIGINT
  kExitNotReady = 8,     // pba: the job has no result yet (still queued or running)
  kExitConflict = 9,     // pba: someone else's change came first: stale base or etag, lock
                         // held, name taken
  kExitDenied = 10,      // pba: not logged in, or no right to do this in the project
  kExitNumerical = 11,   // pba-solve: the solve broke down, or the scene cannot be solved as
                         // posed (Status kNumerical, kFailedPrecondition)
  kExitMesh = 12,        // pba-atlas: the input cannot be meshed as given (the same Status codes)
  kExitIo = 13,          // pba-solve, pba-atlas: reading or writing a file failed
};

// One row of the table, as docs/cli.md shows it.
struct ExitCodeInfo {
  int code;
  const char* name;      // snake_case, stable: "io"
  const char* meaning;   // a short phrase for messages: "reading or writing a file failed"
  const char* programs;  // which can return it: "pba-solve, pba-atlas"
};

// Every exit code, in order of number.
std::span<const ExitCodeInfo> ExitCodeTable();

// The row of `code`; nullptr for a number not in the table.
const ExitCodeInfo* FindExitCode(int code);

// The name of `code` ("io"), or "unknown".
const char* ExitCodeName(int code);

// The exit code of pba-solve or pba-atlas ending on a Status with `code`:
// kOk 0, kInvalidArgument 5, kCancelled 7, kIo 13, kFailedPrecondition and
// kNumerical `failed_computation` (kExitNumerical for a solve, kExitMesh for
// pba-atlas's meshing), anything else 1.
int ExitCodeForStatus(Status::Code code, ExitCode failed_computation);

}  // namespace pba
