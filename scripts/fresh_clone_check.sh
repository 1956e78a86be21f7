#!/usr/bin/env bash
# What a new user meets: clone the committed main into a temporary folder and run the README's
# two commands there, verbatim (`make demo`, then `make test`). Usage: bash scripts/fresh_clone_check.sh
set -euo pipefail
repo="$(cd "$(dirname "$0")/.." && pwd)"
tmp="$(mktemp -d /tmp/nnik-fresh.XXXXXX)"
echo "fresh_clone_check: cloning main of $repo into $tmp"
git clone -q --branch main "$repo" "$tmp/nnik"
cd "$tmp/nnik"
for cmd in "make demo" "make test"; do
  echo "fresh_clone_check: \$ $cmd"
  start=$(date +%s)
  $cmd
  echo "fresh_clone_check: '$cmd' passed in $(( $(date +%s) - start )) s"
done
echo "fresh_clone_check: both README commands passed in $tmp/nnik"
