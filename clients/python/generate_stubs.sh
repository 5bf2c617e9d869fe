#!/usr/bin/env bash
# Regenerates the committed gRPC stubs (vdbwrap/v1/jobs_pb2*.py) from proto/ after a change of
# jobs.proto. Debian's protobuf-compiler and protobuf-compiler-grpc do it offline (Debian 12 has
# no python3-grpc-tools). tests/python/test_client_stubs.py fails while they differ.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
protoc -I "$here/../../proto" --python_out="$here" --grpc_out="$here" \
  --plugin=protoc-gen-grpc=/usr/bin/grpc_python_plugin "$here/../../proto/vdbwrap/v1/jobs.proto"
