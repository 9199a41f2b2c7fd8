# SPDX-License-Identifier: MIT
# impact-ccd-bench: vertex-face and edge-edge CCD over the query files with exact ground truth
# (IMPACT_DATA_DIR/ccd-queries, or folders given on the command line); generated queries without.
impact_add_bench(impact-ccd-bench ccd_bench.cpp SMOKE_ARGS --generated 200 --no-sweep BAD_OPTION --repeat REAL_OPTION --tolerance)
