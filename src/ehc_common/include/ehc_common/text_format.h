#pragma once
// Numbers and fields in the text EHC-MM writes for people and CSV files (messages, reasons,
// table cells).
// ROS-free. JSON numbers go through jsonNumber (json.h) instead.

#include <string>

namespace ehc_common {

/// `v` with `decimals` digits after the point ("%.*f"); a value that rounds to zero is written
/// without a sign ("0.000", never "-0.000"); NaN and infinities as "nan", "inf", "-inf".
std::string fixedDecimals(double v, int decimals);

/// `text` as one CSV field (RFC 4180): in double quotes, each inner double quote doubled, so
/// that commas, quotes and line breaks in it stay inside the field.
std::string csvField(const std::string& text);

}  // namespace ehc_common
