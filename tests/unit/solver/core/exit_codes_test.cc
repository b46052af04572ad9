// The one exit-code table of pba, pba-solve and pba-atlas
// (core/exit_codes.h): no number means two things, pba's numbers stay what
// scripts know, the mapping from Status codes is the one docs/cli.md shows,
// and docs/cli.md's table is the code's.
#include "core/exit_codes.h"

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace pba {
namespace {

// Every enumerator with the name it must have. Two enumerators sharing a
// number would give one of them the other's name.
const std::vector<std::pair<ExitCode, std::string>>& Enumerators() {
  static const std::vector<std::pair<ExitCode, std::string>> all = {
      {kExitOk, "ok"},
      {kExitError, "error"},
      {kExitUsage, "usage"},
      {kExitUnavailable, "unavailable"},
      {kExitNotFound, "not_found"},
      {kExitInvalid, "invalid"},
      {kExitJobFailed, "job_failed"},
      {kExitCancelled, "cancelled"},
      {kExitNotReady, "not_ready"},
      {kExitConflict, "conflict"},
      {kExitDenied, "denied"},
      {kExitNumerical, "numerical"},
      {kExitMesh, "mesh"},
      {kExitIo, "io"},
  };
  return all;
}

TEST(ExitCodesTest, NoTwoNamesShareANumber) {
  std::set<int> codes;
  std::set<std::string> names;
  int previous = -1;
  for (const ExitCodeInfo& info : ExitCodeTable()) {
    SCOPED_TRACE(info.code);
    EXPECT_GT(info.code, previous) << "the table is in order of number, each once";
    previous = info.code;
    EXPECT_TRUE(codes.insert(info.code).second);
    EXPECT_TRUE(names.insert(info.name).second) << info.name;
    EXPECT_NE(std::string(info.meaning), "");
    EXPECT_NE(std::string(info.programs), "");
  }
  EXPECT_EQ(ExitCodeTable().size(), Enumerators().size());
  for (const auto& [code, name] : Enumerators()) {
    EXPECT_EQ(ExitCodeName(code), name) << "exit code " << code;
  }
  EXPECT_STREQ(ExitCodeName(14), "unknown");
  EXPECT_EQ(FindExitCode(-1), nullptr);
}

// Users' scripts test these numbers: pba's 0-10 as they always were, the
// solver programs' after them.
TEST(ExitCodesTest, NumbersScriptsDependOn) {
  const std::vector<int> expected = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13};
  std::vector<int> actual;
  for (const auto& [code, name] : Enumerators()) actual.push_back(code);
  EXPECT_EQ(actual, expected);
}

TEST(ExitCodesTest, StatusCodesMapAsDocumented) {
  using Code = Status::Code;
  for (ExitCode computation : {kExitNumerical, kExitMesh}) {
    SCOPED_TRACE(computation);
    EXPECT_EQ(ExitCodeForStatus(Code::kOk, computation), kExitOk);
    EXPECT_EQ(ExitCodeForStatus(Code::kInvalidArgument, computation), kExitInvalid);
    EXPECT_EQ(ExitCodeForStatus(Code::kFailedPrecondition, computation), computation);
    EXPECT_EQ(ExitCodeForStatus(Code::kNumerical, computation), computation);
    EXPECT_EQ(ExitCodeForStatus(Code::kIo, computation), kExitIo);
    EXPECT_EQ(ExitCodeForStatus(Code::kCancelled, computation), kExitCancelled);
    for (Code other : {Code::kInternal, Code::kNotFound, Code::kAlreadyExists, Code::kAborted,
                       Code::kPermissionDenied, Code::kUnauthenticated, Code::kOutOfRange,
                       Code::kResourceExhausted}) {
      EXPECT_EQ(ExitCodeForStatus(other, computation), kExitError);
    }
  }
}

// docs/cli.md, "Exit codes": the cells of each table row, trimmed.
std::vector<std::vector<std::string>> TableRows(const std::string& text,
                                                const std::string& header) {
  std::vector<std::vector<std::string>> rows;
  const size_t at = text.find(header);
  if (at == std::string::npos) return rows;
  std::istringstream lines(text.substr(at));
  std::string line;
  std::getline(lines, line);  // the header
  std::getline(lines, line);  // |---|
  while (std::getline(lines, line) && line.rfind("|", 0) == 0) {
    std::vector<std::string> cells;
    std::string cell;
    for (size_t i = 1; i < line.size(); ++i) {
      if (line[i] == '|' && line[i - 1] != '\\') {
        const size_t first = cell.find_first_not_of(' ');
        const size_t last = cell.find_last_not_of(' ');
        cells.push_back(first == std::string::npos ? "" : cell.substr(first, last - first + 1));
        cell.clear();
      } else {
        cell += line[i];
      }
    }
    rows.push_back(cells);
  }
  return rows;
}

std::string CliDoc() {
  std::ifstream in(PBA_CLI_DOC);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(ExitCodesTest, DocsListTheTable) {
  const std::string doc = CliDoc();
  const auto rows = TableRows(doc, "| code | name | meaning | returned by |");
  ASSERT_EQ(rows.size(), ExitCodeTable().size()) << "docs/cli.md's exit-code table";
  for (size_t i = 0; i < rows.size(); ++i) {
    const ExitCodeInfo& info = ExitCodeTable()[i];
    ASSERT_EQ(rows[i].size(), 4u) << "row " << i;
    EXPECT_EQ(rows[i][0], std::to_string(info.code));
    EXPECT_EQ(rows[i][1], "`" + std::string(info.name) + "`");
    EXPECT_EQ(rows[i][3], info.programs) << "exit code " << info.code;
  }
}

TEST(ExitCodesTest, DocsShowTheStatusMapping) {
  const std::map<std::string, Status::Code> codes = {
      {"INVALID_ARGUMENT", Status::Code::kInvalidArgument},
      {"FAILED_PRECONDITION", Status::Code::kFailedPrecondition},
      {"NUMERICAL", Status::Code::kNumerical},
      {"IO", Status::Code::kIo},
      {"CANCELLED", Status::Code::kCancelled},
      {"INTERNAL", Status::Code::kInternal},
  };
  const auto rows = TableRows(CliDoc(), "| error code | pba-solve | pba-atlas |");
  std::set<std::string> seen;
  for (const std::vector<std::string>& row : rows) {
    ASSERT_EQ(row.size(), 3u);
    const std::regex name("`([A-Z_]+)`");
    for (std::sregex_iterator it(row[0].begin(), row[0].end(), name), end; it != end; ++it) {
      const std::string code = (*it)[1];
      SCOPED_TRACE(code);
      ASSERT_TRUE(codes.count(code)) << "a Status code the test does not know";
      seen.insert(code);
      EXPECT_EQ(row[1], std::to_string(ExitCodeForStatus(codes.at(code), kExitNumerical)));
      if (row[2] != "-") {  // pba-atlas has no cancel
        EXPECT_EQ(row[2], std::to_string(ExitCodeForStatus(codes.at(code), kExitMesh)));
      }
    }
  }
  EXPECT_EQ(seen.size(), codes.size()) << "docs/cli.md's error-code table misses a code";
}

}  // namespace
}  // namespace pba
