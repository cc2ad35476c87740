#include "ehc_common/json.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace ehc_common {

Json jsonNumber(double v) {
  if (!std::isfinite(v)) return Json(nullptr);
  char text[32];
  std::snprintf(text, sizeof(text), "%.6g", v);
  return Json(std::strtod(text, nullptr));
}

std::string jsonLine(const Json& j) {
  // Text that is not valid UTF-8 (a name from a user's file, a fuzzed request) is replaced
  // with U+FFFD rather than thrown on: output never fails on content.
  return j.dump(-1, ' ', false, Json::error_handler_t::replace);
}

}  // namespace ehc_common
