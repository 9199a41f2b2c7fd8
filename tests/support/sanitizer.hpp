// SPDX-License-Identifier: MIT
// IMPACT_TEST_SANITIZED is 1 in AddressSanitizer builds (GCC or Clang), else 0. Long tests use it
// to run fewer samples through the same code paths there; the Release run keeps the full counts.
#pragma once

#if defined(__SANITIZE_ADDRESS__)
#define IMPACT_TEST_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define IMPACT_TEST_SANITIZED 1
#endif
#endif
#ifndef IMPACT_TEST_SANITIZED
#define IMPACT_TEST_SANITIZED 0
#endif
