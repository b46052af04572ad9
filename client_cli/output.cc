#include "output.h"

#include <algorithm>
#include <cstdio>
#include <ctime>

#include "codec/yaml_codec.h"

namespace pba::cli {

void PrintJson(const google::protobuf::Message& message) {
  const std::string out = codec::ToJson(message);
  std::fputs(out.c_str(), stdout);
  if (out.empty() || out.back() != '\n') std::fputc('\n', stdout);
}

void PrintTable(const std::vector<std::vector<std::string>>& rows) {
  std::vector<std::size_t> widths;
  for (const auto& row : rows) {
    if (widths.size() < row.size()) widths.resize(row.size(), 0);
    for (std::size_t i = 0; i < row.size(); ++i) widths[i] = std::max(widths[i], row[i].size());
  }
  for (const auto& row : rows) {
    std::string line;
    for (std::size_t i = 0; i < row.size(); ++i) {
      line += row[i];
      if (i + 1 < row.size()) line += std::string(widths[i] - row[i].size() + 2, ' ');
    }
    std::puts(line.c_str());
  }
}

std::string StateName(v1::Job::State state) {
  if (state == v1::Job::STATE_UNSPECIFIED) return "UNKNOWN";
  return v1::Job::State_Name(state);
}

bool IsTerminal(v1::Job::State state) {
  return state == v1::Job::SUCCEEDED || state == v1::Job::FAILED || state == v1::Job::CANCELLED;
}

std::string FormatTime(const google::protobuf::Timestamp& time) {
  if (time.seconds() == 0 && time.nanos() == 0) return "-";
  const std::time_t t = static_cast<std::time_t>(time.seconds());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%d %H:%M:%S", &tm);
  return buffer;
}

std::string FormatDuration(const google::protobuf::Timestamp& from,
                           const google::protobuf::Timestamp& to) {
  if (from.seconds() == 0 || to.seconds() == 0) return "-";
  const double seconds =
      static_cast<double>(to.seconds() - from.seconds()) + (to.nanos() - from.nanos()) * 1e-9;
  char buffer[32];
  if (seconds < 60) {
    std::snprintf(buffer, sizeof buffer, "%.1f s", seconds);
  } else {
    std::snprintf(buffer, sizeof buffer, "%d min %d s", static_cast<int>(seconds) / 60,
                  static_cast<int>(seconds) % 60);
  }
  return buffer;
}

void WatchDisplay::Show(const v1::JobEvent& event) {
  const int percent = static_cast<int>(std::clamp(event.progress(), 0.0, 1.0) * 100 + 0.5);
  if (!interactive_) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%-9s %3d%%  ", StateName(event.state()).c_str(), percent);
    std::string line =
        std::string(buffer) + (event.phase().empty() ? "" : event.phase() + ": ") + event.message();
    if (line != last_line_) std::puts(line.c_str());
    last_line_ = line;
    std::fflush(stdout);
    return;
  }
  constexpr int kWidth = 30;
  const int filled = percent * kWidth / 100;
  std::string bar = "[" + std::string(filled, '#') + std::string(kWidth - filled, '-') + "]";
  std::string text =
      event.phase().empty() ? event.message() : event.phase() + ": " + event.message();
  if (text.size() > 60) text = text.substr(0, 57) + "...";
  std::printf("\r\033[K%s %3d%% %-9s %s", bar.c_str(), percent, StateName(event.state()).c_str(),
              text.c_str());
  std::fflush(stdout);
  bar_drawn_ = true;
}

void WatchDisplay::Finish() {
  if (bar_drawn_) std::putchar('\n');
  bar_drawn_ = false;
  std::fflush(stdout);
}

}  // namespace pba::cli
