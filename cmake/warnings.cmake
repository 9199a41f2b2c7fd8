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
    # UBSan's checks listed in IMPACT_UBSAN_SKIP are left out (empty keeps them all). The default
    # skips those that ASan covers or that have nothing to check in this code:
    #  - null and object-size flag an access through a null pointer or past its object, which ASan
    #    reports itself when the access happens (a fault at address 0, a red zone);
    #  - pointer-overflow flags address arithmetic that wraps; an access through it is ASan's again;
    #  - vptr checks the dynamic type of polymorphic objects, and the library has none;
    #  - alignment: Eigen's own assertions (on in these builds, which define no NDEBUG) check the
    #    alignment of its fixed-size vectorizable objects, and a misaligned operand of the wide
    #    trees' aligned SSE/AVX loads faults.
    # Together they took 26 % of clang 14's compile time of the CCD tests under ASan (38.6-41.5 s
    # of CPU against 51.9-56.4 s, side by side) and 13 % of their run (39.8 s against 45.7 s).
    # The fuzz targets (tests/fuzz), which read hostile input, keep every check.
    if(IMPACT_UBSAN_SKIP)
      target_compile_options(impact_warnings INTERFACE -fno-sanitize=${IMPACT_UBSAN_SKIP})
    endif()
    # No code for use-after-return detection: by default it is compiled into every function with
    # stack objects but only runs when ASAN_OPTIONS sets detect_stack_use_after_return=1, which the
    # runtimes of clang 14 and g++ 12 leave off. Without it the tests check the same (stack scopes
    # are still poisoned: use-after-scope stays on) and compile 14-19 % faster under clang 14.
    if(CMAKE_CXX_COMPILER_ID MATCHES "Clang")
      target_compile_options(impact_warnings INTERFACE -fsanitize-address-use-after-return=never)
    else()
      target_compile_options(impact_warnings INTERFACE --param=asan-use-after-return=0)
    endif()
  endif()
  if(IMPACT_TSAN)
    # ThreadSanitizer: not combinable with ASan; the build holds the concurrency tests only
    # (tests/CMakeLists.txt), which run the parallel paths and concurrent queries.
    target_compile_options(impact_warnings INTERFACE -fsanitize=thread -fno-omit-frame-pointer)
    target_link_options(impact_warnings INTERFACE -fsanitize=thread)
  endif()
endif()

# impact_directory_optimization(FLAG): the targets of the calling directory compile at FLAG (-O1,
# say) instead of the optimized build types' own level (Release, RelWithDebInfo, MinSizeRel; Debug
# and the sanitizer builds keep theirs); an empty FLAG changes nothing. g++'s maybe-uninitialized
# analysis depends on the optimizer, and at -O1 it takes copies of Eigen's comma-initialised
# matrices for reads of uninitialised memory: it is off wherever the level is lowered
# (-Wuninitialized stays, and the clang builds of .ci/run keep their own checks).
function(impact_directory_optimization flag)
  if(flag AND CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    add_compile_options($<$<CONFIG:Release,RelWithDebInfo,MinSizeRel>:${flag}>)
    if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
      add_compile_options($<$<CONFIG:Release,RelWithDebInfo,MinSizeRel>:-Wno-maybe-uninitialized>)
    endif()
  endif()
endfunction()
