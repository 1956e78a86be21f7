#!/usr/bin/env bash
# Run the test suite; pytest's exit code 5 (no tests collected) counts as a failure.
#
# `make bench` also runs the tests that use a trained model on models trained from another seed
# (NNIK_TEST_SEED_OFFSET=7) with torch's generic CPU kernels (ATEN_CPU_CAPABILITY=default): a model
# trained on another machine differs in its last bits, so an assertion that leans on one trained
# model's figures fails there, not on a user's machine.
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
run "$@"
