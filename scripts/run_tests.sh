#!/usr/bin/env bash
# Run the test suite; pytest's exit code 5 (no tests collected) counts as a failure.
#
# With no arguments, a second pass follows: the tests that use a trained model run again on models
# trained from another seed (NNIK_TEST_SEED_OFFSET) with torch's generic CPU kernels
# (ATEN_CPU_CAPABILITY=default). A model trained on another machine differs in its last bits (the
# product pins torch's thread count by problem size, but not the CPU's vector kernels), so an
# assertion that leans on one trained model's figures fails here, not on a user's machine.
#
# The tests run on NNIK_TEST_WORKERS processes (pytest-xdist; default: one a core), a test module
# whole on one of them (its module fixtures built once); the session fixtures that train or run a
# model are built once for all of them (tests/shared_build.py). OMP_WAIT_POLICY=PASSIVE: torch's
# threads in one worker sleep, not spin, while the other worker has the core.
set -u
export OMP_WAIT_POLICY="${OMP_WAIT_POLICY:-PASSIVE}"
run() {
  python3 -m pytest -q --durations=30 -n "${NNIK_TEST_WORKERS:-auto}" --dist loadscope "$@"
  local rc=$?
  if [ "$rc" -eq 5 ]; then
    echo "run_tests: pytest collected no tests" >&2
    return 1
  fi
  return "$rc"
}
run "$@" || exit $?
if [ "$#" -eq 0 ] && [ "${NNIK_SECOND_MODEL_PASS:-1}" = 1 ]; then
  echo "run_tests: second pass, models trained from seed + 7 with torch's generic CPU kernels"
  NNIK_TEST_SEED_OFFSET=7 ATEN_CPU_CAPABILITY=default run tests/firmware/gcode tests/test_cli_run.py || exit $?
fi
