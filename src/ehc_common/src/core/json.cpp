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

std::string jsonLine(const Json& j) { return j.dump(); }

}  // namespace ehc_common
