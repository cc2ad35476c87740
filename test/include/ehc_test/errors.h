#pragma once
// Generic test helper of every package: the message an expression throws.

#include <stdexcept>
#include <string>

namespace ehc_test {

/// The message of the std::invalid_argument `f` throws ("" if it throws none).
template <class F>
std::string errorOf(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace ehc_test
