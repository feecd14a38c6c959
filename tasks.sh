#!/usr/bin/env bash
# The README's two commands:  ./tasks.sh run   (main job)   and   ./tasks.sh test   (test suite).
# Each first runs scripts/setup.sh, which installs whatever is missing and is quick otherwise.
# ./tasks.sh docs builds the API reference (docs/, Sphinx) into docs/_build/html.
#
# Two stacks: Debian's DOLFINx 0.5.2 (.venv, the default) and today's DOLFINx 0.11 from the
# dolfinx-solver-real wheel (.venv-current). `test` runs the suite on both (their default suites side by side,
# then the collective tests) and fails if the second stack cannot be set up; `run` and `bench` use
# DOLFINX_FRETTING_STACK (debian by default, or current).
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
cd "$here"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OPENBLAS_NUM_THREADS=1
stack=${DOLFINX_FRETTING_STACK:-debian}
case "$stack" in
  debian|default) venv=.venv ;;
  current) venv=.venv-current ;;
  *) echo "DOLFINX_FRETTING_STACK=$stack: allowed debian, current" >&2; exit 2 ;;
esac
cmd=${1:-}
[ $# -gt 0 ] && shift

loud() {  # a message nobody can miss in a CI log
  local line="################################################################################"
  printf '\n%s\n# %s\n%s\n\n' "$line" "$*" "$line" >&2
}

# The default suite (pytest, not slow) of one stack, into LOG: run_pytest NAME PYTHON LOG [pytest options]. The two
# stacks' suites run at the same time (each is one process; the machines have 2 cores), each into its own log,
# printed whole once both have finished; pytest's cache is off (both would write .pytest_cache at once).
run_pytest() {  # run in the background: the job becomes pytest itself (exec), so the trap below reaches it
  local name=$1 python=$2 log=$3
  shift 3
  exec >"$log" 2>&1
  echo "[test] $name stack: $("$python" -c 'from mpi4py import MPI; import dolfinx; print("DOLFINx", dolfinx.__version__)' \
    2>/dev/null || echo 'DOLFINx not importable')"
  exec "$python" -m pytest -q -p no:cacheprovider -m "not slow" tests "$@"
}

# run_parallel NAME PYTHON LAUNCHER...: the collective tests on 2 and 3 ranks (python -m mpi4py: an error on one
# rank aborts them all), one stack after the other (they start several processes each). Non-zero if any failed.
run_parallel() {
  local name=$1 python=$2 status=0 n
  shift 2
  for n in 2 3; do
    echo "[test] $name stack, ${1##*/} -n $n: tests/test_parallel.py"
    "$@" -n "$n" "$python" -m mpi4py -m pytest -q -p no:cacheprovider tests/test_parallel.py || status=1
  done
  return $status
}

case "$cmd" in
  run)
    scripts/setup.sh "$stack"
    exec "$venv/bin/dolfinx-fretting" run stromberg-block --out results/stromberg-block "$@" ;;
  test)
    scripts/setup.sh debian
    current_ready=1
    if ! scripts/setup.sh current; then
      current_ready=0
      loud "The second stack (DOLFINx 0.11, .venv-current) could not be set up: its tests do NOT run." \
           "See the [setup] messages above. This test run FAILS."
    fi
    # tests/test_stacks.py runs the scenes on both stacks itself: it must fail, not skip, without the second.
    export DOLFINX_FRETTING_BOTH_STACKS=1
    # The FCLIB problems (../shared/fclib beside the clone, as on CI) must be there: their absence fails the
    # suite instead of skipping a validation row (DOLFINX_FRETTING_EXPECT_FCLIB=0 to run without them).
    export DOLFINX_FRETTING_EXPECT_FCLIB=${DOLFINX_FRETTING_EXPECT_FCLIB:-1}
    # tests/test_docs.py builds the API reference with Sphinx (the docs extra, which setup.sh installs into
    # .venv): without Sphinx it must fail, not skip. The reference is built on the debian stack only.
    export DOLFINX_FRETTING_EXPECT_DOCS=1
    times=()
    status=0
    logs=$(mktemp -d)
    # an interrupt stops both suites (background jobs of a script ignore SIGINT) and the whole test run
    trap 'kill $(jobs -p) 2>/dev/null; rm -rf "$logs"; echo "[test] interrupted" >&2; exit 130' INT TERM
    t0=$SECONDS
    run_pytest debian .venv/bin/python "$logs/debian.log" "$@" &
    debian_pid=$!
    if [ $current_ready = 1 ]; then
      # test_stacks.py runs in the debian suite (it starts both stacks in subprocesses): not twice; nor the docs build.
      run_pytest current .venv-current/bin/python "$logs/current.log" --ignore=tests/test_stacks.py \
        --ignore=tests/test_docs.py "$@" &
      current_pid=$!
    fi
    wait $debian_pid && debian_status=passed || debian_status=FAILED
    cat "$logs/debian.log"
    if [ $current_ready = 1 ]; then
      wait $current_pid && current_status=passed || current_status=FAILED
      cat "$logs/current.log"
    fi
    times+=("both stacks' default suites side by side: $((SECONDS - t0)) s (debian $debian_status"\
"$([ $current_ready = 1 ] && echo ", current $current_status" || echo ", current NOT RUN (set-up failed)"))")
    [ $debian_status = passed ] && { [ $current_ready = 0 ] || [ $current_status = passed ]; } || status=1
    [ $current_ready = 1 ] || status=1
    rm -rf "$logs"
    t0=$SECONDS
    run_parallel debian .venv/bin/python mpirun --oversubscribe && mpi_status=passed || mpi_status=FAILED
    [ $mpi_status = passed ] || status=1
    times+=("debian MPI: $((SECONDS - t0)) s ($mpi_status)")
    if [ $current_ready = 1 ]; then
      t0=$SECONDS
      run_parallel current .venv-current/bin/python .venv-current/bin/mpiexec && mpi_status=passed || mpi_status=FAILED
      [ $mpi_status = passed ] || status=1
      times+=("current MPI: $((SECONDS - t0)) s ($mpi_status)")
    fi
    echo "[test] wall time: ${times[*]/%/;}"
    if [ $status != 0 ]; then
      loud "./tasks.sh test FAILED: ${times[*]/%/;}"
    fi
    exit $status ;;
  docs)
    # The reference is built and tested (tests/test_docs.py) on the debian stack; -W: a warning is an error,
    # -n: every reference to the package must resolve.
    scripts/setup.sh debian
    .venv/bin/python -m sphinx -W -n --keep-going -b html docs docs/_build/html "$@"
    echo "[docs] docs/_build/html/index.html" ;;
  bench)
    scripts/setup.sh "$stack"
    exec "$venv/bin/python" -m pytest -q -m slow tests "$@" ;;
  *)
    echo "usage: [DOLFINX_FRETTING_STACK=debian|current] ./tasks.sh run [run options]" \
         "| test [pytest options] | docs [sphinx-build options] | bench" >&2
    exit 2 ;;
esac
