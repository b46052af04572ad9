// Status: how bad input and failed work travel between modules (no exceptions
// cross a module boundary). Numerical outcomes of a solve go in its Summary.
#pragma once

#include <string>
#include <utility>

namespace pba {

class Status {
 public:
  enum class Code {
    kOk = 0,
    kInvalidArgument,     // bad input; field() names the offending field path
    kFailedPrecondition,  // input is well formed but cannot be solved as posed
    kNumerical,           // the solve broke down (singular, diverged, NaN)
    kIo,                  // reading or writing a file failed
    kCancelled,           // the caller asked to stop
    kInternal,            // a bug
    // The codes below come from the shared atlas store (server/store), where
    // the caller needs to tell these refusals apart to react to them.
    kNotFound,           // the named resource does not exist
    kAlreadyExists,      // a create would duplicate a unique name
    kAborted,            // a concurrent change won (stale etag or base revision); re-read, retry
    kPermissionDenied,   // the caller's role does not allow the operation
    kUnauthenticated,    // no valid credentials
    kOutOfRange,         // a position past what exists (an upload chunk at the wrong offset)
    kResourceExhausted,  // a quota or a bounded pool is full; try again later
  };

  Status() = default;
  static Status Ok() { return Status(); }
  static Status InvalidArgument(std::string field, std::string message) {
    return Status(Code::kInvalidArgument, std::move(message), std::move(field));
  }
  static Status FailedPrecondition(std::string message) {
    return Status(Code::kFailedPrecondition, std::move(message));
  }
  // A valid input the mesh made from it cannot honour (a sensor outside the
  // meshed body, a patch that holds no face): `field` names the input.
  static Status FailedPrecondition(std::string field, std::string message) {
    return Status(Code::kFailedPrecondition, std::move(message), std::move(field));
  }
  static Status Numerical(std::string message) {
    return Status(Code::kNumerical, std::move(message));
  }
  static Status Io(std::string message) { return Status(Code::kIo, std::move(message)); }
  static Status Cancelled(std::string message) {
    return Status(Code::kCancelled, std::move(message));
  }
  static Status Internal(std::string message) {
    return Status(Code::kInternal, std::move(message));
  }
  static Status NotFound(std::string message) {
    return Status(Code::kNotFound, std::move(message));
  }
  static Status AlreadyExists(std::string message) {
    return Status(Code::kAlreadyExists, std::move(message));
  }
  static Status Aborted(std::string message) { return Status(Code::kAborted, std::move(message)); }
  static Status PermissionDenied(std::string message) {
    return Status(Code::kPermissionDenied, std::move(message));
  }
  static Status Unauthenticated(std::string message) {
    return Status(Code::kUnauthenticated, std::move(message));
  }
  // `field` names the position asked for ("offset").
  static Status OutOfRange(std::string field, std::string message) {
    return Status(Code::kOutOfRange, std::move(message), std::move(field));
  }
  // `field` names the quota or pool ("upload_quota", "diff_slots").
  static Status ResourceExhausted(std::string field, std::string message) {
    return Status(Code::kResourceExhausted, std::move(message), std::move(field));
  }

  bool ok() const { return code_ == Code::kOk; }
  Code code() const { return code_; }
  const std::string& message() const { return message_; }
  // Dotted path of the offending input field, e.g. "material.linear_elastic.poissons_ratio"
  // or "boundary_conditions[1].set"; empty when no single field is to blame.
  const std::string& field() const { return field_; }
  // The same failure (code and field), its message led by `context`, e.g.
  // "mesh.adapt cycle 3 (12000 elements): ". Ok stays ok.
  Status WithContext(const std::string& context) const {
    return ok() ? *this : Status(code_, context + message_, field_);
  }
  // "field: message" when a field is named, else the message.
  std::string ToString() const { return field_.empty() ? message_ : field_ + ": " + message_; }

 private:
  Status(Code code, std::string message, std::string field = {})
      : code_(code), message_(std::move(message)), field_(std::move(field)) {}
  Code code_ = Code::kOk;
  std::string message_;
  std::string field_;
};

// Returns early from the enclosing function when `expr` is not ok.
#define PBA_RETURN_IF_ERROR(expr)              \
  do {                                         \
    ::pba::Status pba_status_ = (expr);        \
    if (!pba_status_.ok()) return pba_status_; \
  } while (false)

}  // namespace pba
