#!/usr/bin/env bash
# Run the test suite; pytest's exit code 5 (no tests collected) counts as a failure.
set -u
python3 -m pytest -q "$@"
rc=$?
if [ "$rc" -eq 5 ]; then
  echo "run_tests: pytest collected no tests" >&2
  exit 1
fi
exit "$rc"
