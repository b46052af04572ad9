#include "atlas/report_format.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <utility>

#include "core/format.h"

namespace pba {
namespace {

std::string Printf(const char* format, int precision, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, precision, value);
  return buffer;
}

// The exchange forms (CSV, JSON) keep 10 significant digits: more than any
// report's figures carry, fewer than the noise of the last bits.
std::string ExchangeReal(double value) { return Printf("%.*g", 10, value); }

std::string TextCell(const ReportCell& cell, const ReportColumn& column) {
  switch (cell.kind) {
    case ReportCell::Kind::kText:
      return cell.text;
    case ReportCell::Kind::kInteger:
      return std::to_string(cell.integer);
    case ReportCell::Kind::kReal:
      return std::isfinite(cell.real) ? Printf("%.*f", column.decimals, cell.real) : "-";
    case ReportCell::Kind::kFlag:
      return cell.flag ? "FLAG" : "";
  }
  return {};
}

std::string CsvCell(const ReportCell& cell) {
  switch (cell.kind) {
    case ReportCell::Kind::kText:
      return CsvQuoted(cell.text);
    case ReportCell::Kind::kInteger:
      return std::to_string(cell.integer);
    case ReportCell::Kind::kReal:
      return std::isfinite(cell.real) ? ExchangeReal(cell.real) : "";
    case ReportCell::Kind::kFlag:
      return cell.flag ? "true" : "false";
  }
  return {};
}

std::string JsonCell(const ReportCell& cell) {
  switch (cell.kind) {
    case ReportCell::Kind::kText:
      return JsonQuoted(cell.text);
    case ReportCell::Kind::kInteger:
      return std::to_string(cell.integer);
    case ReportCell::Kind::kReal:
      return std::isfinite(cell.real) ? ExchangeReal(cell.real) : "null";
    case ReportCell::Kind::kFlag:
      return cell.flag ? "true" : "false";
  }
  return {};
}

std::string JsonObject(const ReportTable& table, const std::vector<ReportCell>& row) {
  std::string out = "{";
  for (size_t c = 0; c < row.size(); ++c) {
    if (c > 0) out += ", ";
    out += JsonQuoted(table.columns[c].key) + ": " + JsonCell(row[c]);
  }
  return out + "}";
}

std::string FormatText(const ReportTable& table) {
  const size_t nc = table.columns.size();
  std::vector<std::vector<std::string>> cells;
  std::vector<std::vector<bool>> right;
  std::vector<size_t> width(nc, 0);
  const auto add = [&](const std::vector<ReportCell>& row) {
    std::vector<std::string> line(nc);
    std::vector<bool> align(nc);
    for (size_t c = 0; c < nc; ++c) {
      line[c] = TextCell(row[c], table.columns[c]);
      align[c] =
          row[c].kind == ReportCell::Kind::kInteger || row[c].kind == ReportCell::Kind::kReal;
      width[c] = std::max(width[c], line[c].size());
    }
    cells.push_back(std::move(line));
    right.push_back(std::move(align));
  };
  for (size_t c = 0; c < nc; ++c) width[c] = table.columns[c].header.size();
  for (const auto& row : table.rows) add(row);
  if (table.footer) add(*table.footer);

  // Headers follow the alignment of their column's first row.
  const auto render = [&](const std::vector<std::string>& line, const std::vector<bool>& align) {
    std::string out;
    for (size_t c = 0; c < nc; ++c) {
      if (c > 0) out += "  ";
      const std::string pad(width[c] - line[c].size(), ' ');
      out += align[c] ? pad + line[c] : line[c] + (c + 1 < nc ? pad : "");
    }
    while (!out.empty() && out.back() == ' ') out.pop_back();
    return out + "\n";
  };
  size_t total = 0;
  for (size_t c = 0; c < nc; ++c) total += width[c] + (c > 0 ? 2 : 0);
  const std::string rule = std::string(total, '-') + "\n";

  std::string out = table.title.empty() ? "" : table.title + "\n";
  std::vector<std::string> headers(nc);
  for (size_t c = 0; c < nc; ++c) headers[c] = table.columns[c].header;
  out += render(headers, right.empty() ? std::vector<bool>(nc, false) : right.front());
  out += rule;
  for (size_t r = 0; r < table.rows.size(); ++r) out += render(cells[r], right[r]);
  if (table.footer) out += rule + render(cells.back(), right.back());
  return out;
}

std::string FormatCsv(const ReportTable& table) {
  const auto line = [](const std::vector<ReportCell>& row) {
    std::string out;
    for (size_t c = 0; c < row.size(); ++c) out += (c > 0 ? "," : "") + CsvCell(row[c]);
    return out + "\n";
  };
  std::vector<ReportCell> headers;
  for (const ReportColumn& column : table.columns)
    headers.push_back(ReportCell::Text(column.header));
  std::string out = line(headers);
  for (const auto& row : table.rows) out += line(row);
  if (table.footer) out += line(*table.footer);
  return out;
}

std::string FormatJson(const ReportTable& table) {
  std::string out = "{\n  \"title\": " + JsonQuoted(table.title) + ",\n  \"rows\": [";
  for (size_t r = 0; r < table.rows.size(); ++r) {
    out += (r > 0 ? ",\n    " : "\n    ") + JsonObject(table, table.rows[r]);
  }
  out += table.rows.empty() ? "]" : "\n  ]";
  if (table.footer) {
    out += ",\n  " + JsonQuoted(table.footer_key) + ": " + JsonObject(table, *table.footer);
  }
  return out + "\n}\n";
}

}  // namespace

ReportCell ReportCell::Text(std::string s) {
  ReportCell cell;
  cell.kind = Kind::kText;
  cell.text = std::move(s);
  return cell;
}

ReportCell ReportCell::Integer(int64_t value) {
  ReportCell cell;
  cell.kind = Kind::kInteger;
  cell.integer = value;
  return cell;
}

ReportCell ReportCell::Real(double value) {
  ReportCell cell;
  cell.kind = Kind::kReal;
  cell.real = value;
  return cell;
}

ReportCell ReportCell::Flag(bool value) {
  ReportCell cell;
  cell.kind = Kind::kFlag;
  cell.flag = value;
  return cell;
}

std::string FormatReportTable(const ReportTable& table, TableFormat format) {
  // A row of the wrong width is a bug of the report that built it.
  for (const auto& row : table.rows) {
    if (row.size() != table.columns.size()) std::abort();
  }
  if (table.footer && table.footer->size() != table.columns.size()) std::abort();
  switch (format) {
    case TableFormat::kText:
      return FormatText(table);
    case TableFormat::kCsv:
      return FormatCsv(table);
    case TableFormat::kJson:
      return FormatJson(table);
  }
  return {};
}

}  // namespace pba
