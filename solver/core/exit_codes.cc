#include "core/exit_codes.h"

namespace pba {
namespace {

constexpr char kAll[] = "pba, pba-solve, pba-atlas";

constexpr ExitCodeInfo kTable[] = {
    {kExitOk, "ok", "success", kAll},
    {kExitError, "error", "an error with no code of its own", kAll},
    {kExitUsage, "usage", "bad command line", kAll},
    {kExitUnavailable, "unavailable", "the server could not be reached", "pba"},
    {kExitNotFound, "not_found", "no such job or file", "pba"},
    {kExitInvalid, "invalid", "the input was rejected", kAll},
    {kExitJobFailed, "job_failed", "the job ended FAILED", "pba"},
    {kExitCancelled, "cancelled", "cancelled", "pba, pba-solve"},
    {kExitNotReady, "not_ready", "the job has no result yet", "pba"},
    {kExitConflict, "conflict", "someone else's change came first", "pba"},
    {kExitDenied, "denied", "not logged in, or no right to do this", "pba"},
    {kExitNumerical, "numerical", "the solve broke down, or the scene cannot be solved as posed",
     "pba-solve"},
    {kExitMesh, "mesh", "the input cannot be meshed as given", "pba-atlas"},
    {kExitIo, "io", "reading or writing a file failed", "pba-solve, pba-atlas"},
};

}  // namespace

std::span<const ExitCodeInfo> ExitCodeTable() { return kTable; }

const ExitCodeInfo* FindExitCode(int code) {
  for (const ExitCodeInfo& info : kTable) {
    if (info.code == code) return &info;
  }
  return nullptr;
}

const char* ExitCodeName(int code) {
  const ExitCodeInfo* info = FindExitCode(code);
  return info != nullptr ? info->name : "unknown";
}

int ExitCodeForStatus(Status::Code code, ExitCode failed_computation) {
  switch (code) {
    case Status::Code::kOk:
      return kExitOk;
    case Status::Code::kInvalidArgument:
      return kExitInvalid;
    case Status::Code::kFailedPrecondition:
    case Status::Code::kNumerical:
      return failed_computation;
    case Status::Code::kIo:
      return kExitIo;
    case Status::Code::kCancelled:
      return kExitCancelled;
    default:
      return kExitError;
  }
}

}  // namespace pba
