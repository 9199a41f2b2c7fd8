# SPDX-License-Identifier: MIT
# impact-cloth-bench: the cloth collision step on the drape, twist, layers, spin and shot scenes,
# every step checked by the exact oracle (verify_cloth_state). The smoke run is a few steps of a
# coarse drape.
set(cloth_libs "")
if(TARGET impact::io)
  set(cloth_libs impact::io)
endif()
impact_add_bench(impact-cloth-bench cloth_bench.cpp LIBS ${cloth_libs} SMOKE_ARGS --scene drape --resolution 8 --steps 12 BAD_OPTION --steps REAL_OPTION --dt)
if(TARGET impact::io)
  target_compile_definitions(impact-cloth-bench PRIVATE IMPACT_HAVE_IO=1)
endif()
