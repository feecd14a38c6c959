#!/usr/bin/env bash
# The README's two commands:  ./tasks.sh run   (main job)   and   ./tasks.sh test   (test suite).
# Each first runs scripts/setup.sh, which installs whatever is missing and is quick otherwise.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
cd "$here"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OPENBLAS_NUM_THREADS=1
cmd=${1:-}
[ $# -gt 0 ] && shift
case "$cmd" in
  run)
    scripts/setup.sh
    exec .venv/bin/dolfinx-fretting run stromberg-block --out results/stromberg-block "$@" ;;
  test)
    scripts/setup.sh
    # The FCLIB problems (../shared/fclib beside the clone, as on CI) must be there: their absence fails the
    # suite instead of skipping a validation row (DOLFINX_FRETTING_EXPECT_FCLIB=0 to run without them).
    export DOLFINX_FRETTING_EXPECT_FCLIB=${DOLFINX_FRETTING_EXPECT_FCLIB:-1}
    .venv/bin/python -m pytest -q -m "not slow" tests "$@"
    # The collective tests on 2 and 3 ranks (python -m mpi4py: an error on one rank aborts them all).
    for n in 2 3; do
      echo "[test] mpirun -n $n: tests/test_parallel.py"
      mpirun -n "$n" --oversubscribe .venv/bin/python -m mpi4py -m pytest -q -p no:cacheprovider tests/test_parallel.py
    done ;;
  bench)
    scripts/setup.sh
    exec .venv/bin/python -m pytest -q -m slow tests "$@" ;;
  *)
    echo "usage: ./tasks.sh run [run options] | test [pytest options] | bench" >&2; exit 2 ;;
esac
