// Numbers as text, the one place that decides how: exactly (a file that is
// read back, a parameter echoed as given) or briefly (a message).
#pragma once

#include <string>

namespace pba {

// The shortest text that reads back (strtod) as exactly `value`: 0.45, not
// 0.45000000000000001; 0.4999999, not 0.5; an exponent where that is shorter
// (1e-05). "nan", "inf" and "-inf" for the non-finite.
std::string RoundTripNumber(double value);

// RoundTripNumber when it has at most `max_width` characters, else as many
// significant digits as fit (a fixed-width field of a file format:
// -1.2345678901234567e+200 in 20 characters keeps 13 digits).
std::string RoundTripNumber(double value, int max_width);

// Six significant digits, as "%g" prints them: for messages and summaries,
// where a person reads the number. Not for a value that must read back.
std::string ShortNumber(double value);

}  // namespace pba
