#!/usr/bin/env bash
# Runs CI as CI runs it: a fresh clone beside this checkout (so ../shared resolves), then .ci/run.
set -euo pipefail
top=$(git rev-parse --show-toplevel)
rm -rf "$top/../ci-check"
git clone -q "$top" "$top/../ci-check"
cd "$top/../ci-check" && CI=true bash .ci/run
