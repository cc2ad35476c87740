#pragma once
// A randomized test's seed: drawn fresh on every run and printed, or the one EHC_TEST_SEED gives,
// so that a failure seen once reruns exactly (EHC_TEST_SEED=<printed seed> <test binary>).

#include <cstdlib>
#include <iostream>
#include <random>
#include <string>

namespace ehc_test {

/// The seed of the check `what`: EHC_TEST_SEED if set, else a fresh one in [1, 999999] (short to
/// print, and the experiments' run seeds, seed x 1000 + set x 10 + index, stay within 32 bits);
/// printed either way.
inline unsigned testSeed(const std::string& what) {
  const char* given = std::getenv("EHC_TEST_SEED");
  const unsigned seed = given ? static_cast<unsigned>(std::stoul(given)) : 1u + std::random_device{}() % 999999u;
  std::cout << "[" << what << "] seed " << seed << " (rerun: EHC_TEST_SEED=" << seed << ")" << std::endl;
  return seed;
}

}  // namespace ehc_test
