#!/bin/sh
# Regenerates every data file and plot of docs/validation.md (about 20 minutes on 2 cores).
# usage (from the repository root): validation/regenerate.sh [BUILD_DIR]   (default build,
# a Release build; the shared models are found as for the tests, or set SEM_SHARED_MODELS)
# The FEM reference validation/fem_cantilever.json is not regenerated here: run
# tools/fem/cantilever.py for that (needs gmsh and CalculiX, installed on demand).
set -e
B=${1:-build}
# the thread settings the sem command gives itself (see src/cli/main.c), for the study programs
export OMP_WAIT_POLICY="${OMP_WAIT_POLICY:-passive}"
export OPENBLAS_THREAD_TIMEOUT="${OPENBLAS_THREAD_TIMEOUT:-20}"
V=validation
FEM="--fem $V/fem_cantilever.json"
"$B"/study_deflection $FEM --gamma 1e7 > $V/deflection_g1e7.dat
"$B"/study_deflection $FEM --gamma 1e9 --no-files > $V/deflection_g1e9.dat
"$B"/study_deflection $FEM --gamma 1e10 --no-files > $V/deflection_g1e10.dat
"$B"/study_deflection $FEM > $V/deflection_default.dat
"$B"/study_deflection $FEM --no-generated --material stable_neohookean > $V/deflection_default_snh.dat
"$B"/study_deflection $FEM --no-generated --gamma 1e7 --material stable_neohookean > $V/deflection_snh.dat
"$B"/study_deflection $FEM --no-generated --gamma 1e7 --material linear > $V/deflection_linear.dat
"$B"/study_weight_gradient > $V/deflection_gradw.dat
"$B"/study_weight_gradient --delta 0.15 > $V/deflection_gradw_d015.dat
"$B"/study_scaling > $V/scaling.dat
"$B"/study_volume > $V/volume.dat
"$B"/sem bench --json > $V/bench.json
for p in deflection scaling volume; do gnuplot $V/$p.gp; done
