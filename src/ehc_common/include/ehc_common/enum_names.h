#pragma once
// One string map per enum: a table of {value, name} pairs and the look-ups over it, so that
// toString and fromString of an enum cannot disagree. ROS-free, header-only.
//   constexpr EnumNames<Colour, 2> kColourNames = {{{Colour::Red, "red"}, {Colour::Blue, "blue"}}};
//   std::string toString(Colour c) { return enumName(kColourNames, c, "Palette"); }

#include <array>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace ehc_common {

template <class E, std::size_t N>
using EnumNames = std::array<std::pair<E, const char*>, N>;

/// The name of `value`; throws std::invalid_argument "[owner] ..." if the table lacks it.
template <class E, std::size_t N>
std::string enumName(const EnumNames<E, N>& names, E value, const std::string& owner) {
  for (const auto& [v, name] : names)
    if (v == value) return name;
  throw std::invalid_argument("[" + owner + "] enum value " + std::to_string(static_cast<int>(value)) + " has no name");
}

/// The value named `s`; throws std::invalid_argument "[owner] unknown <what> 's' (expected ...)".
template <class E, std::size_t N>
E enumValue(const EnumNames<E, N>& names, const std::string& s, const std::string& owner, const std::string& what) {
  std::string known;
  for (const auto& [v, name] : names) {
    if (s == name) return v;
    known += (known.empty() ? "'" : ", '") + std::string(name) + "'";
  }
  throw std::invalid_argument("[" + owner + "] unknown " + what + " '" + s + "' (expected one of " + known + ")");
}

/// Every value of the table, in its order.
template <class E, std::size_t N>
std::vector<E> enumValues(const EnumNames<E, N>& names) {
  std::vector<E> out;
  for (const auto& entry : names) out.push_back(entry.first);
  return out;
}

}  // namespace ehc_common
