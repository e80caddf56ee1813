#!/usr/bin/env bash
# Regenerates the protobuf and gRPC stubs in src/graspd/v1 from ../../proto (needs grpcio-tools,
# installed by `pip install -e '.[test]'`; $PYTHON names another interpreter that has it).
# tests/test_client.py fails when they are out of date.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
out="${1:-$here/src}"
rm -rf "$out/graspd"
mkdir -p "$out/graspd/v1"
${PYTHON:-python3} -m grpc_tools.protoc -I "$here/../../proto" --python_out="$out" --grpc_python_out="$out" \
  "$here"/../../proto/graspd/v1/*.proto
touch "$out/graspd/__init__.py" "$out/graspd/v1/__init__.py"
