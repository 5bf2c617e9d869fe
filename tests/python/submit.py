#!/usr/bin/python3
"""A minimal vdbwrap job client in Python: submits a mesh, follows the progress, downloads
the result (and the report). A thin command line over the Python package of
clients/python (imported from the source tree, so no install is needed).

It needs Debian's python3-grpcio, python3-protobuf and python3-yaml.

    /usr/bin/python3 tests/python/submit.py --server 127.0.0.1:50051 part.stl part_wrap.stl \
        --base-size-percent 1 [--token-file F] [--tls-ca ca.pem] [--report part_wrap.json]

Exit codes: those of `vdbwrap wrap` (0 ok, 2 bad arguments, 3 invalid input, 4 no valid
surface, 5 output not written, 1 other errors).
"""
import argparse
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.normpath(os.path.join(HERE, "..", "..", "clients", "python")))

import vdbwrap  # noqa: E402  (clients/python)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("input")
    ap.add_argument("output", help="result file; its extension picks the format (.stl .obj .off .ply .vtp .nas)")
    ap.add_argument("--server", required=True, help="HOST:PORT")
    ap.add_argument("--base-size-percent", type=float, help="--base-size N%% of the CLI")
    ap.add_argument("--levels", type=int)
    ap.add_argument("--volume", choices=["outside", "inside"])
    ap.add_argument("--params", help="a JSON or YAML parameter file (the WrapParameters message)")
    ap.add_argument("--token-file")
    ap.add_argument("--tls-ca", help="PEM file of the CA that signed the server's certificate")
    ap.add_argument("--report", help="write the JSON report here")
    args = ap.parse_args()

    token = None
    if args.token_file:
        with open(args.token_file) as f:
            token = f.read().strip()
    given = {k: v for k, v in (("base_size_percent", args.base_size_percent), ("levels", args.levels),
                               ("volume", args.volume)) if v is not None}

    def show(ev):
        print("[%7.2fs] %-10s %-15s %3.0f%%  %s" % (ev.elapsed_seconds, ev.state, ev.stage, 100 * ev.fraction,
                                                   ev.message), file=sys.stderr)

    try:
        with vdbwrap.Client(args.server, token=token, tls_ca=args.tls_ca) as client:
            result = client.wrap(args.input, args.output, params=args.params, on_progress=show, report=args.report,
                                 **given)
    except vdbwrap.VdbwrapError as e:
        print("submit.py: %s" % e, file=sys.stderr)
        return e.exit_code
    print("job %s: wrote %s (%d triangles)" % (result.job_id, result.output, result.output_triangles), file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
