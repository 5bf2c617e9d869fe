#!/usr/bin/python3
"""A minimal vdbwrap job client in Python: submits a mesh, follows the progress, downloads
the result (and the report). Proves the vdbwrap.v1 API is usable from another language.

It needs Debian's python3-grpcio and python3-protobuf, protoc and grpc_python_plugin
(protobuf-compiler, protobuf-compiler-grpc). The stubs are generated from proto/ into a
temporary folder at every run.

    /usr/bin/python3 tests/python/submit.py --server 127.0.0.1:50051 part.stl part_wrap.stl \
        --base-size-percent 1 [--token-file F] [--tls-ca ca.pem] [--report part_wrap.json]

Exit codes: those of `vdbwrap wrap` (0 ok, 2 bad arguments, 3 invalid input, 4 no valid
surface, 5 output not written, 1 other errors).
"""
import argparse
import importlib
import os
import subprocess
import sys
import tempfile
import uuid

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_PROTO_DIR = os.path.normpath(os.path.join(HERE, "..", "..", "proto"))
CHUNK = 1 << 20


def load_stubs(proto_dir, out_dir):
    """Runs protoc with the Python and gRPC Python plugins; returns (pb2, pb2_grpc)."""
    cmd = ["protoc", "-I", proto_dir, "--python_out=" + out_dir, "--grpc_out=" + out_dir,
           "--plugin=protoc-gen-grpc=/usr/bin/grpc_python_plugin",
           os.path.join(proto_dir, "vdbwrap", "v1", "jobs.proto")]
    subprocess.run(cmd, check=True)
    sys.path.insert(0, out_dir)
    return (importlib.import_module("vdbwrap.v1.jobs_pb2"), importlib.import_module("vdbwrap.v1.jobs_pb2_grpc"))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("input")
    ap.add_argument("output", help="result file; its extension picks the format (.stl .obj .off .ply)")
    ap.add_argument("--server", required=True, help="HOST:PORT")
    ap.add_argument("--base-size-percent", type=float, help="--base-size N%% of the CLI")
    ap.add_argument("--levels", type=int)
    ap.add_argument("--volume", choices=["outside", "inside"])
    ap.add_argument("--token-file")
    ap.add_argument("--tls-ca", help="PEM file of the CA that signed the server's certificate")
    ap.add_argument("--report", help="write the JSON report here")
    ap.add_argument("--proto-dir", default=DEFAULT_PROTO_DIR)
    args = ap.parse_args()

    import grpc  # Debian: python3-grpcio

    with tempfile.TemporaryDirectory(prefix="vdbwrap_stubs_") as stub_dir:
        pb, pb_grpc = load_stubs(args.proto_dir, stub_dir)

        formats = {"stl": pb.MESH_FORMAT_STL, "obj": pb.MESH_FORMAT_OBJ, "off": pb.MESH_FORMAT_OFF, "ply": pb.MESH_FORMAT_PLY}
        out_ext = os.path.splitext(args.output)[1].lower().lstrip(".")
        if out_ext not in formats:
            print("submit.py: unknown output format %r" % out_ext, file=sys.stderr)
            return 2

        metadata = []
        if args.token_file:
            with open(args.token_file) as f:
                metadata.append(("authorization", "Bearer " + f.read().strip()))
        if args.tls_ca:
            with open(args.tls_ca, "rb") as f:
                channel = grpc.secure_channel(args.server, grpc.ssl_channel_credentials(root_certificates=f.read()))
        else:
            channel = grpc.insecure_channel(args.server)
        stub = pb_grpc.JobsStub(channel)

        params = pb.WrapParameters()
        if args.base_size_percent is not None:
            params.base_size_percent = args.base_size_percent
        if args.levels is not None:
            params.levels = args.levels
        if args.volume:
            params.volume = pb.VOLUME_INSIDE if args.volume == "inside" else pb.VOLUME_OUTSIDE
        spec = pb.JobSpec(file_name=os.path.basename(args.input), params=params, output_format=formats[out_ext],
                          idempotency_key=str(uuid.uuid4()), size_bytes=os.path.getsize(args.input))

        def requests():
            yield pb.SubmitRequest(spec=spec)
            with open(args.input, "rb") as f:
                while True:
                    data = f.read(CHUNK)
                    if not data:
                        return
                    yield pb.SubmitRequest(chunk=data)

        try:
            reply = stub.Submit(requests(), metadata=metadata)
        except grpc.RpcError as e:
            print("submit.py: %s: %s" % (e.code().name, e.details()), file=sys.stderr)
            kinds = [v for k, v in (e.trailing_metadata() or []) if k == "vdbwrap-error-kind"]
            return int(kinds[0]) if kinds else 1
        job_id = reply.job_id
        print("job %s accepted" % job_id, file=sys.stderr)

        last = None
        for ev in stub.Watch(pb.JobId(job_id=job_id), metadata=metadata):
            print("[%7.2fs] %-10s %-15s %3.0f%%  %s" % (ev.elapsed_seconds, pb.JobState.Name(ev.state)[10:].lower(),
                                                       ev.stage, 100 * ev.fraction, ev.message), file=sys.stderr)
            last = ev
        status = stub.GetStatus(pb.JobId(job_id=job_id), metadata=metadata)
        if status.state != pb.JOB_STATE_SUCCEEDED:
            print("submit.py: job %s %s: %s" % (job_id, pb.JobState.Name(status.state), status.error_message),
                  file=sys.stderr)
            kind = status.error_kind
            return kind if 1 <= kind <= 6 else 1
        assert last is not None and last.state == pb.JOB_STATE_SUCCEEDED

        tmp = args.output + ".tmp"
        size = None
        got = 0
        with open(tmp, "wb") as f:
            for chunk in stub.Download(pb.DownloadRequest(job_id=job_id), metadata=metadata):
                if size is None:
                    size = chunk.total_size
                f.write(chunk.data)
                got += len(chunk.data)
        if got != size:
            print("submit.py: download incomplete (%d of %s bytes)" % (got, size), file=sys.stderr)
            return 5
        os.replace(tmp, args.output)
        if args.report:
            with open(args.report, "w") as f:
                f.write(status.report_json)
        print("wrote %s (%d bytes, %d triangles)" % (args.output, got, status.output_triangles), file=sys.stderr)
        return 0


if __name__ == "__main__":
    sys.exit(main())
