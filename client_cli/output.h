// Output helpers of the client: tables, times, JSON, and the watch display.
#pragma once

#include <google/protobuf/message.h>
#include <google/protobuf/timestamp.pb.h>

#include <string>
#include <vector>

#include "pba/v1/job.pb.h"

namespace pba::cli {

// Proto3 JSON of `message` on stdout, one document.
void PrintJson(const google::protobuf::Message& message);

// Rows of cells printed with aligned columns; the first row is the header.
void PrintTable(const std::vector<std::vector<std::string>>& rows);

std::string StateName(v1::Job::State state);
// "2026-11-22 17:30:49" in UTC, or "-" when unset.
std::string FormatTime(const google::protobuf::Timestamp& time);
// Seconds between two timestamps as "1.2 s" / "3 min 4 s", or "-".
std::string FormatDuration(const google::protobuf::Timestamp& from,
                           const google::protobuf::Timestamp& to);
bool IsTerminal(v1::Job::State state);

// Shows job events: a redrawn bar on a terminal, one plain line per event
// otherwise (logs, pipes, CI).
class WatchDisplay {
 public:
  explicit WatchDisplay(bool interactive) : interactive_(interactive) {}
  void Show(const v1::JobEvent& event);
  void Finish();

 private:
  bool interactive_;
  bool bar_drawn_ = false;
  std::string last_line_;
};

}  // namespace pba::cli
