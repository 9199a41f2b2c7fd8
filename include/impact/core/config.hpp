// SPDX-License-Identifier: MIT
/// \file
/// Library-wide configuration: version, the IMPACT_ASSERT precondition macro and feature switches.
/// The core never prints, logs or exits: invalid input at validated entry points throws
/// impact::InvalidInput (core/error.hpp); preconditions of hot paths are IMPACT_ASSERTs.
#pragma once

#include <cassert>

#define IMPACT_VERSION_MAJOR 0
#define IMPACT_VERSION_MINOR 1
#define IMPACT_VERSION_PATCH 0

/// Precondition check for hot paths. Compiled out with NDEBUG, like assert; define
/// IMPACT_ASSERT before including any impact header to route it elsewhere.
#ifndef IMPACT_ASSERT
#define IMPACT_ASSERT(cond) assert(cond)
#endif

#if defined(__GNUC__) || defined(__clang__)
#define IMPACT_LIKELY(x) __builtin_expect(!!(x), 1)
#define IMPACT_UNLIKELY(x) __builtin_expect(!!(x), 0)
#else
#define IMPACT_LIKELY(x) (x)
#define IMPACT_UNLIKELY(x) (x)
#endif

/// Keeps a rarely taken function out of its callers (its stack frame and code stay off the hot
/// path).
#if defined(__GNUC__) || defined(__clang__)
#define IMPACT_NOINLINE __attribute__((noinline))
#elif defined(_MSC_VER)
#define IMPACT_NOINLINE __declspec(noinline)
#else
#define IMPACT_NOINLINE
#endif
