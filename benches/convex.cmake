# SPDX-License-Identifier: MIT
# impact-convex-bench: boolean, distance and penetration queries between convex shapes (impact's
# convex layer, target impact::convex) against FCL's shape primitives on the same poses; without
# FCL it runs without the FCL rows, without libccd it is not built. Its mesh rows (mesh against each
# shape) take --mesh FILE through impact::io when assimp is there.
if(TARGET impact::convex)
  impact_add_bench(impact-convex-bench convex_bench.cpp LIBS impact::convex SMOKE_ARGS --pairs 6 --mesh-poses 4 --min-time 0 BAD_OPTION --pairs REAL_OPTION --min-time)
  if(TARGET impact::io)  # --mesh FILE through the assimp loader
    target_link_libraries(impact-convex-bench PRIVATE impact::io)
    target_compile_definitions(impact-convex-bench PRIVATE IMPACT_HAVE_IO=1)
  endif()
  # Qhull (Debian libqhull-dev, the reentrant libqhull_r), the peer of the --hulls rows, through
  # pkg-config or find_library; without it those rows say "qhull absent".
  find_package(PkgConfig QUIET)
  if(PkgConfig_FOUND)
    pkg_check_modules(IMPACT_QHULL QUIET IMPORTED_TARGET qhull_r)
  endif()
  if(IMPACT_QHULL_FOUND)
    target_link_libraries(impact-convex-bench PRIVATE PkgConfig::IMPACT_QHULL)
    target_compile_definitions(impact-convex-bench PRIVATE IMPACT_HAVE_QHULL=1)
  else()
    find_library(IMPACT_QHULL_LIBRARY qhull_r)
    find_path(IMPACT_QHULL_INCLUDE libqhull_r/qhull_ra.h)
    if(IMPACT_QHULL_LIBRARY AND IMPACT_QHULL_INCLUDE)
      target_link_libraries(impact-convex-bench PRIVATE ${IMPACT_QHULL_LIBRARY})
      target_include_directories(impact-convex-bench SYSTEM PRIVATE ${IMPACT_QHULL_INCLUDE})
      target_compile_definitions(impact-convex-bench PRIVATE IMPACT_HAVE_QHULL=1)
    else()
      message(STATUS "impact: qhull (libqhull_r) not found, impact-convex-bench --hulls runs without its qhull rows")
    endif()
  endif()
  # the hull rows as a second smoke run: small sets only (and the small knight mesh when the data
  # folder is set), so that it stays well under a second
  set(impact_hull_smoke_args --hulls --hull-max-points 1000 --hull-reps 1 --min-time 0)
  if(IMPACT_DATA_DIR AND TARGET impact::io)
    list(APPEND impact_hull_smoke_args --mesh ${IMPACT_DATA_DIR}/meshes/knight.off)
  endif()
  add_test(NAME impact-convex-bench-hulls-smoke
    COMMAND ${CMAKE_COMMAND} -DEXE=$<TARGET_FILE:impact-convex-bench> "-DARGS=${impact_hull_smoke_args}"
            -DJSON=${CMAKE_CURRENT_BINARY_DIR}/impact-convex-bench-hulls-smoke.json -P ${CMAKE_CURRENT_SOURCE_DIR}/smoke.cmake)
  set_tests_properties(impact-convex-bench-hulls-smoke PROPERTIES LABELS "bench-smoke")
  if(TARGET fcl)
    target_link_libraries(impact-convex-bench PRIVATE fcl)
    target_compile_definitions(impact-convex-bench PRIVATE IMPACT_HAVE_FCL=1)
  else()
    message(STATUS "impact: FCL not found, impact-convex-bench runs without the FCL rows")
  endif()
else()
  message(STATUS "impact: libccd not found, impact-convex-bench is not built")
endif()
