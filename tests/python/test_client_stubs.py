#!/usr/bin/python3
"""ctest: the gRPC stubs committed in clients/python/vdbwrap/v1 match proto/vdbwrap/v1/jobs.proto.

The stubs are committed (Debian 12 has no python3-grpc-tools, and a committed stub makes the
package installable without protoc). This compares what they describe, not their bytes, so a
different protoc version that generates other text still passes:
- the message and enum definitions: the FileDescriptorProto inside jobs_pb2 equals the one
  protoc builds from proto/ now;
- the service: JobsStub registers every method of the proto, with its path, its streaming
  kind and the right request and reply types.
After a change of jobs.proto, run clients/python/generate_stubs.sh.
"""
import argparse
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "clients", "python"))

from google.protobuf import descriptor_pb2  # noqa: E402

from vdbwrap.v1 import jobs_pb2, jobs_pb2_grpc  # noqa: E402


class RecordingChannel:
    """Stands in for a grpc.Channel: records what JobsStub registers."""

    def __init__(self):
        self.methods = {}

    def _add(kind):
        def register(self, path, request_serializer=None, response_deserializer=None):
            self.methods[path] = (kind, request_serializer, response_deserializer)
            return path

        return register

    unary_unary = _add((False, False))
    unary_stream = _add((False, True))
    stream_unary = _add((True, False))
    stream_stream = _add((True, True))


def clear_json_names(messages):
    for m in messages:
        for f in m.field:
            f.ClearField("json_name")
        clear_json_names(m.nested_type)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--protoc", default="protoc")
    ap.add_argument("--proto-dir", default=os.path.join(ROOT, "proto"))
    args = ap.parse_args()
    errors = []

    with tempfile.TemporaryDirectory(prefix="vdbwrap_stubs_") as tmp:
        out = os.path.join(tmp, "jobs.pb")
        subprocess.run([args.protoc, "-I", args.proto_dir, "--descriptor_set_out=" + out,
                        os.path.join(args.proto_dir, "vdbwrap", "v1", "jobs.proto")], check=True)
        with open(out, "rb") as f:
            fresh = descriptor_pb2.FileDescriptorSet.FromString(f.read()).file[0]
    committed = descriptor_pb2.FileDescriptorProto.FromString(jobs_pb2.DESCRIPTOR.serialized_pb)
    # --descriptor_set_out fills in the derived json_name, the Python output leaves it out.
    for fd in (fresh, committed):
        clear_json_names(fd.message_type)
    if committed != fresh:
        names = lambda fd: {m.name: m for m in list(fd.message_type) + list(fd.enum_type) + list(fd.service)}  # noqa
        old, new = names(committed), names(fresh)
        changed = sorted(n for n in set(old) | set(new) if old.get(n) != new.get(n))
        errors.append("jobs_pb2.py differs from jobs.proto in: " + ", ".join(changed or ["file options"]))

    channel = RecordingChannel()
    jobs_pb2_grpc.JobsStub(channel)
    service = fresh.service[0]
    for method in service.method:
        path = "/%s.%s/%s" % (fresh.package, service.name, method.name)
        if path not in channel.methods:
            errors.append("JobsStub lacks %s" % path)
            continue
        kind, serializer, deserializer = channel.methods.pop(path)
        if kind != (method.client_streaming, method.server_streaming):
            errors.append("%s: streaming %s, the proto says %s" % (path, kind, (method.client_streaming,
                                                                              method.server_streaming)))
        request = getattr(jobs_pb2, method.input_type.rsplit(".", 1)[1])
        reply = getattr(jobs_pb2, method.output_type.rsplit(".", 1)[1])
        if serializer != request.SerializeToString or deserializer != reply.FromString:
            errors.append("%s: request or reply type differs from the proto" % path)
    errors += ["JobsStub has %s, which the proto does not" % p for p in channel.methods]

    for e in errors:
        print("test_client_stubs.py: " + e, file=sys.stderr)
    if errors:
        print("test_client_stubs.py: run clients/python/generate_stubs.sh", file=sys.stderr)
        return 1
    print("test_client_stubs.py: ok (%d messages, %d methods)" % (len(fresh.message_type), len(service.method)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
