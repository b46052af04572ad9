// Report tables in three forms: aligned text for a terminal or log, CSV for
// a spreadsheet, JSON for a program. A report (the geometric validation,
// the mesh quality report) fills a ReportTable - columns, one row per item,
// an optional footer row such as an overall line - and FormatReportTable
// renders it; the report's own code never formats text itself, so all
// reports agree on the three forms.
//
//   text  title line, then the column headers, a rule, the rows, and, when
//         there is a footer, a rule and the footer row; text cells
//         left-aligned, numbers right-aligned; reals with the column's
//         decimals; a flag shows as "FLAG" when set, blank when not; a
//         non-finite real as "-".
//   CSV   (RFC 4180) the header line of column headers, one line per row,
//         the footer row last; no title; reals with 10 significant digits;
//         flags as true / false; a non-finite real as an empty field;
//         fields with a comma, a quote or a line break are quoted.
//   JSON  {"title": ..., "rows": [{key: value, ...}, ...], <footer_key>:
//         {key: value, ...}}, keys being the columns' keys; reals with 10
//         significant digits (null when not finite), integers, booleans,
//         strings escaped.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace pba {

enum class TableFormat { kText, kCsv, kJson };

struct ReportCell {
  enum class Kind { kText, kInteger, kReal, kFlag };
  Kind kind = Kind::kText;
  std::string text;
  int64_t integer = 0;
  double real = 0;
  bool flag = false;

  static ReportCell Text(std::string s);
  static ReportCell Integer(int64_t value);
  static ReportCell Real(double value);
  static ReportCell Flag(bool value);
};

struct ReportColumn {
  std::string header;  // text and CSV, e.g. "E [mm]"
  std::string key;     // JSON, e.g. "structural_error_mm"
  int decimals = 3;    // text form of reals
};

struct ReportTable {
  std::string title;
  std::vector<ReportColumn> columns;
  // Each row has one cell per column (checked).
  std::vector<std::vector<ReportCell>> rows;
  std::optional<std::vector<ReportCell>> footer;
  std::string footer_key = "overall";  // the footer's JSON key
};

std::string FormatReportTable(const ReportTable& table, TableFormat format);

}  // namespace pba
