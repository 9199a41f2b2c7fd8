// SPDX-License-Identifier: MIT
// Boost.Multiprecision's integers and rationals for the tests' exact oracles. GCC 12 at -O3 can
// report -Wmaybe-uninitialized inside cpp_int's limb storage once enough of a test is inlined
// around it (a false positive in Boost's code, not in the tests'): the warning is silenced for
// Boost's lines only, by the location-based diagnostic state around the include.
#pragma once

#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <boost/multiprecision/cpp_int.hpp>
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
