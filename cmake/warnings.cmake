# SPDX-License-Identifier: MIT
# impact_warnings: an INTERFACE target carrying warning (and optional sanitizer) flags for the
# project's own tests, benches and examples only; consumers of impact::impact never see them.
add_library(impact_warnings INTERFACE)
if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
  target_compile_options(impact_warnings INTERFACE -Wall -Wextra -Wpedantic -Wshadow)
  if(CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    # GoogleTest's TYPED_TEST_SUITE passes an empty variadic argument
    target_compile_options(impact_warnings INTERFACE -Wno-gnu-zero-variadic-macro-arguments)
  endif()
  if(IMPACT_WARNINGS_AS_ERRORS)
    target_compile_options(impact_warnings INTERFACE -Werror)
  endif()
  if(IMPACT_SANITIZE)
    target_compile_options(impact_warnings INTERFACE -fsanitize=address,undefined -fno-omit-frame-pointer
      -fno-sanitize-recover=all)
    target_link_options(impact_warnings INTERFACE -fsanitize=address,undefined)
  endif()
  if(IMPACT_TSAN)
    # ThreadSanitizer: not combinable with ASan; the build holds the concurrency tests only
    # (tests/CMakeLists.txt), which run the parallel paths and concurrent queries.
    target_compile_options(impact_warnings INTERFACE -fsanitize=thread -fno-omit-frame-pointer)
    target_link_options(impact_warnings INTERFACE -fsanitize=thread)
  endif()
endif()
