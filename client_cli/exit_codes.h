// Exit codes of `pba` (docs/cli.md lists them for scripts).
#pragma once

namespace pba::cli {

enum ExitCode : int {
  kExitOk = 0,
  kExitError = 1,         // any other error (the message says what)
  kExitUsage = 2,         // bad command line
  kExitUnavailable = 3,   // the server could not be reached
  kExitNotFound = 4,      // no such job or file
  kExitInvalid = 5,       // the server or the client rejected the input (bad scene)
  kExitJobFailed = 6,     // the job ended FAILED
  kExitJobCancelled = 7,  // the job ended CANCELLED
  kExitNotReady = 8,      // the job has no result yet (still queued or running)
  kExitConflict = 9,      // someone else's change came first: stale base or etag, lock held,
                          // name taken
  kExitDenied = 10,       // not logged in, or no right to do this in the project
};

}  // namespace pba::cli
