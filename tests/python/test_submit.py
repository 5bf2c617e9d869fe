#!/usr/bin/python3
"""ctest driver for the Python client: starts a vdbwrap-server on a free port with a
temporary spool and a token, runs submit.py against it, and checks the downloaded result
with `vdbwrap check --require-valid`."""
import argparse
import os
import re
import signal
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--server-bin", required=True)
    ap.add_argument("--cli", required=True)
    ap.add_argument("--data", required=True)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="vdbwrap_py_") as tmp:
        token = os.path.join(tmp, "token")
        with open(token, "w") as f:
            f.write("py-token\n")
        log_path = os.path.join(tmp, "server.log")
        log = open(log_path, "w")
        server = subprocess.Popen([args.server_bin, "--listen", "127.0.0.1:0", "--spool", os.path.join(tmp, "spool"),
                                   "--token-file", token], stderr=log, stdout=subprocess.DEVNULL)
        try:
            port = None
            deadline = time.time() + 30
            while port is None and time.time() < deadline and server.poll() is None:
                m = re.search(r"listening on 127\.0\.0\.1:(\d+) ", open(log_path).read())
                port = m.group(1) if m else None
                time.sleep(0.05)
            if port is None:
                print(open(log_path).read(), file=sys.stderr)
                print("test_submit.py: the server did not start", file=sys.stderr)
                return 1
            out = os.path.join(tmp, "fuze_wrap.obj")
            report = os.path.join(tmp, "fuze_wrap.json")
            rc = subprocess.run(["/usr/bin/python3", os.path.join(HERE, "submit.py"), "--server", "127.0.0.1:" + port,
                                 "--token-file", token, "--base-size-percent", "3", "--report", report,
                                 os.path.join(args.data, "fuze.obj"), out], timeout=300).returncode
            if rc != 0:
                print("test_submit.py: submit.py exited with %d" % rc, file=sys.stderr)
                return 1
            check = subprocess.run([args.cli, "check", out, "--require-valid"], capture_output=True, text=True, timeout=300)
            print(check.stdout)
            if check.returncode != 0:
                print("test_submit.py: the downloaded result is not a valid closed surface", file=sys.stderr)
                return 1
            if '"valid_closed_surface": true' not in open(report).read():
                print("test_submit.py: the report does not say the result is valid", file=sys.stderr)
                return 1
            # A wrong token is refused (exit code 2, UNAUTHENTICATED).
            with open(os.path.join(tmp, "bad"), "w") as f:
                f.write("nope")
            rc = subprocess.run(["/usr/bin/python3", os.path.join(HERE, "submit.py"), "--server", "127.0.0.1:" + port,
                                 "--token-file", os.path.join(tmp, "bad"), os.path.join(args.data, "fuze.obj"),
                                 os.path.join(tmp, "x.stl")], timeout=120, capture_output=True, text=True)
            if rc.returncode == 0 or "UNAUTHENTICATED" not in rc.stderr:
                print("test_submit.py: a wrong token was not refused: %d %s" % (rc.returncode, rc.stderr), file=sys.stderr)
                return 1
            print("test_submit.py: ok")
            return 0
        finally:
            server.send_signal(signal.SIGTERM)
            try:
                server.wait(timeout=30)
            except subprocess.TimeoutExpired:
                server.kill()
                server.wait()
            log.close()


if __name__ == "__main__":
    sys.exit(main())
