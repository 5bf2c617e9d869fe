"""The vdbwrap.v1 gRPC stubs, generated from proto/vdbwrap/v1/jobs.proto (see generate_stubs.sh)."""
