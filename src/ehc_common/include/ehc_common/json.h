#pragma once
// JSON output of every EHC-MM tool and result file: nlohmann-json documents with insertion-ordered
// keys, written with the project's one number format (jsonNumber: 6 significant digits, the
// precision of every figure the project reports; non-finite numbers become null, never NaN
// text). ROS-free. Parsing input JSON (the Water2 API) also goes through nlohmann::json::parse.

#include <nlohmann/json.hpp>

#include <string>

namespace ehc_common {

/// A JSON document whose object keys keep the order they were inserted in.
using Json = nlohmann::ordered_json;

/// `v` rounded to 6 significant digits (the printed value of "%.6g"), or null if not finite.
Json jsonNumber(double v);

/// One line of compact JSON (no spaces, no trailing newline); invalid UTF-8 is replaced.
std::string jsonLine(const Json& j);

}  // namespace ehc_common
