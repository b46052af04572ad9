// What every Abaqus / CalculiX input deck PBA writes shares: the width of a
// data line's number field.
#pragma once

#include <string>

#include "core/number_format.h"

namespace pba {

// The widest a number may be in a deck: CalculiX reads every number of a
// data line in a field of at most 20 characters, and a longer one stops it
// (exit 201 on *NODE) or is silently cut.
constexpr int kAbaqusFieldWidth = 20;

// `value` for a data line of a deck: the shortest text that reads back as
// `value` when one fits in kAbaqusFieldWidth (0.45, not
// 0.45000000000000001), else as many significant digits as fit (13 for
// -1.2345678901234567e+200).
inline std::string AbaqusNumber(double value) { return RoundTripNumber(value, kAbaqusFieldWidth); }

}  // namespace pba
