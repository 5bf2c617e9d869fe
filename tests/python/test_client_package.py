#!/usr/bin/python3
"""ctest driver for the Python package of clients/python: creates a venv in the build tree
(with Debian's grpcio, protobuf and yaml through --system-site-packages), pip-installs the
package offline, starts a real vdbwrap-server on loopback and runs the checks below with the
venv's interpreter, so that they use the installed package and not the source tree."""
import argparse
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
PACKAGE_SRC = os.path.normpath(os.path.join(HERE, "..", "..", "clients", "python"))


def fail(msg):
    print("test_client_package.py: FAIL: " + msg, file=sys.stderr)
    sys.exit(1)


def expect(cond, msg):
    if not cond:
        fail(msg)


def install(venv, work):
    """A fresh venv with the package installed from a copy of its sources (setuptools builds
    in the source folder: a copy keeps the tree clean)."""
    subprocess.run(["/usr/bin/python3", "-m", "venv", "--system-site-packages", "--clear", venv], check=True)
    src = os.path.join(work, "src")
    shutil.copytree(PACKAGE_SRC, src, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
    env = dict(os.environ, PIP_NO_INDEX="1", PIP_DISABLE_PIP_VERSION_CHECK="1")
    subprocess.run([os.path.join(venv, "bin", "python"), "-m", "pip", "install", "-q", "--no-build-isolation",
                    "--no-deps", src], check=True, env=env, timeout=300)


def start_server(server_bin, tmp, token):
    log_path = os.path.join(tmp, "server.log")
    log = open(log_path, "w")
    server = subprocess.Popen([server_bin, "--listen", "127.0.0.1:0", "--spool", os.path.join(tmp, "spool"),
                               "--token-file", token, "--workers", "1"], stderr=log, stdout=subprocess.DEVNULL)
    deadline = time.time() + 30
    while time.time() < deadline and server.poll() is None:
        m = re.search(r"listening on 127\.0\.0\.1:(\d+) ", open(log_path).read())
        if m:
            return server, log, "127.0.0.1:" + m.group(1)
        time.sleep(0.05)
    print(open(log_path).read(), file=sys.stderr)
    fail("the server did not start")


def driver(args):
    venv = os.path.abspath(args.venv)
    with tempfile.TemporaryDirectory(prefix="vdbwrap_pkg_") as tmp:
        install(venv, tmp)
        token = os.path.join(tmp, "token")
        with open(token, "w") as f:
            f.write("pkg-token\n")
        server, log, address = start_server(args.server_bin, tmp, token)
        try:
            rc = subprocess.run([os.path.join(venv, "bin", "python"), os.path.abspath(__file__), "--checks",
                                 "--address", address, "--token-file", token, "--cli", args.cli, "--data", args.data,
                                 "--work", tmp, "--venv", venv], timeout=900).returncode
        finally:
            server.send_signal(signal.SIGTERM)
            try:
                server.wait(timeout=30)
            except subprocess.TimeoutExpired:
                server.kill()
                server.wait()
            log.close()
        if rc != 0:
            print(open(os.path.join(tmp, "server.log")).read()[-4000:], file=sys.stderr)
            return rc
    print("test_client_package.py: ok")
    return 0


def vdbwrap_check(cli, mesh, work):
    """`vdbwrap check --require-valid --report`: its exit code and its JSON."""
    report = os.path.join(work, os.path.basename(mesh) + ".check.json")
    proc = subprocess.run([cli, "check", mesh, "--require-valid", "--report", report], capture_output=True, text=True,
                          timeout=300)
    with open(report) as f:
        return proc.returncode, json.load(f)


def checks(args):
    import vdbwrap

    expect(os.path.abspath(vdbwrap.__file__).startswith(args.venv + os.sep),
           "vdbwrap was imported from %s, not from the venv" % vdbwrap.__file__)
    with open(args.token_file) as f:
        token = f.read().strip()
    client = vdbwrap.Client(args.address, token=token)
    data = args.data

    # Client.wrap: submit, watch, download in one call.
    events = []
    out = os.path.join(args.work, "fuze_wrap.stl")
    report_path = os.path.join(args.work, "fuze_wrap.json")
    result = client.wrap(os.path.join(data, "fuze.obj"), out, base_size_percent=3, on_progress=events.append,
                         report=report_path)
    expect(os.path.getsize(out) > 84, "no result written")
    rc, diag = vdbwrap_check(args.cli, out, args.work)
    expect(rc == 0, "vdbwrap check --require-valid exited with %d" % rc)
    d = diag["diagnostics"]
    expect(d["valid_closed_surface"] and d["closed"] and d["manifold"] and d["outward"] and not d["self_intersecting"],
           "the downloaded result is not a valid closed surface: %s" % d)
    expect(d["triangles"] == result.output_triangles, "triangles %d, the job said %d" % (d["triangles"],
                                                                                         result.output_triangles))
    expect(result.report is not None and result.report["output"]["valid_closed_surface"] is True,
           "the job's report does not say the result is valid")
    with open(report_path) as f:
        expect(json.load(f) == result.report, "the report file differs from the job's report")
    # The job's report names the tool and the input as the CLI's does.
    version = subprocess.run([args.cli, "--version"], capture_output=True, text=True).stdout.split()[-1]
    expect(result.report.get("vdbwrap_version") == version,
           "report vdbwrap_version %r, the CLI is %r" % (result.report.get("vdbwrap_version"), version))
    expect(result.report.get("source") == {"file_name": "fuze.obj", "parts": [{"name": "default", "triangles": 1000}]},
           "report source %r" % (result.report.get("source"),))

    # Watch events arrived in order, and the last one is final.
    expect(len(events) >= 2, "only %d progress events" % len(events))
    expect(all(a.sequence < b.sequence for a, b in zip(events, events[1:])), "events out of order")
    expect(events[-1].state == "succeeded" and events[-1].final, "last event %s" % (events[-1],))
    expect(all(0.0 <= e.fraction <= 1.0 for e in events), "a fraction outside 0..1")
    expect(any(e.state == "running" and e.stage for e in events), "no running stage among the events")
    replay = list(client.watch(result.job_id))
    expect(replay and replay[-1].state == "succeeded", "watching an ended job does not end with its state")

    # jobs() lists it; cancelling a succeeded job is refused.
    listed = {j.job_id: j for j in client.jobs()}
    expect(listed.get(result.job_id) is not None and listed[result.job_id].state == "succeeded",
           "jobs() does not list the succeeded job")
    expect(listed[result.job_id].file_name == "fuze.obj", "jobs() file name %r" % listed[result.job_id].file_name)
    try:
        client.cancel(result.job_id)
        fail("cancelling a succeeded job was accepted")
    except vdbwrap.VdbwrapError as e:
        expect(e.code == "FAILED_PRECONDITION", "cancel of a succeeded job: %s" % e)

    # A long job: cancel it, its watch ends cancelled, then delete it.
    slow = client.submit(os.path.join(data, "fandisk.obj"), base_size_percent=0.15, levels=2)
    try:
        client.delete(slow)
        fail("deleting a job that has not ended was accepted")
    except vdbwrap.VdbwrapError as e:
        expect(e.code == "FAILED_PRECONDITION", "delete of a live job: %s" % e)
    cancelled = client.cancel(slow)
    expect(cancelled.state in ("cancelled", "queued", "running"), "cancel answered %s" % cancelled.state)
    last = list(client.watch(slow))[-1]
    expect(last.state == "cancelled" and last.error_kind == "CANCELLED", "cancelled job's last event: %s" % (last,))
    expect(client.status(slow).state == "cancelled", "the cancelled job's state")
    client.delete(slow)
    expect(slow not in {j.job_id for j in client.jobs()}, "a deleted job is still listed")
    try:
        client.status(slow)
        fail("status of a deleted job did not fail")
    except vdbwrap.NotFoundError as e:
        expect(e.code == "NOT_FOUND", "deleted job: %s" % e)

    # Bad parameters: a misspelt name is refused before any upload, naming the closest name.
    before = len(client.jobs())
    try:
        client.wrap(os.path.join(data, "fuze.obj"), os.path.join(args.work, "x.stl"), levls=1)
        fail("a misspelt parameter was accepted")
    except vdbwrap.ParameterError as e:
        expect(e.suggestion == "levels" and "levls" in str(e) and "did you mean 'levels'" in str(e),
               "misspelt parameter: %s" % e)
        expect(e.kind == "INVALID_ARGUMENT" and e.exit_code == 2, "kind %s exit %d" % (e.kind, e.exit_code))
    params_file = os.path.join(args.work, "params.yaml")
    with open(params_file, "w") as f:
        f.write("params:\n  base_size_percent: 3\n  volume: outsde\n")
    try:
        client.submit(os.path.join(data, "fuze.obj"), params=params_file)
        fail("a misspelt enum value in a YAML file was accepted")
    except vdbwrap.ParameterError as e:
        expect(e.suggestion == "outside", "misspelt volume: %s" % e)
    # Out of range: the server refuses it, with its error kind.
    try:
        client.submit(os.path.join(data, "fuze.obj"), levels=99)
        fail("levels 99 was accepted")
    except vdbwrap.ParameterError as e:
        expect(e.code == "INVALID_ARGUMENT" and e.kind == "INVALID_ARGUMENT" and "levels" in str(e),
               "levels 99: %s" % e)
    expect(len(client.jobs()) == before, "a refused submit created a job")

    # An unreadable mesh: the server's INVALID_INPUT.
    junk = os.path.join(args.work, "junk.stl")
    with open(junk, "wb") as f:
        f.write(b"solid junk\n  facet normal 0 0 1\n    outer loop\n      vertex 1 2\n")
    try:
        client.submit(junk)
        fail("an unreadable mesh was accepted")
    except vdbwrap.InputError as e:
        expect(e.kind == "INVALID_INPUT" and e.exit_code == 3, "junk mesh: %s" % e)

    # A job that fails: JobError with the pipeline's error kind, and no output.
    failed_out = os.path.join(args.work, "tube_inside.stl")
    try:
        client.wrap(os.path.join(data, "tube.obj"), failed_out, volume="inside", base_size_percent=3)
        fail("wrapping the inside of an open tube succeeded")
    except vdbwrap.JobError as e:
        expect(e.state == "failed" and e.kind == "WRAP_FAILED" and e.exit_code == 4 and e.job_id,
               "failed job: %s (state %s, kind %s)" % (e, e.state, e.kind))
        expect("encloses no volume" in e.message, "failed job's message: %s" % e.message)
        expect(not os.path.exists(failed_out), "a failed job left an output")
        client.delete(e.job_id)

    # A YAML parameter file in the form of WrapParameters, and a wrong token.
    with open(params_file, "w") as f:
        f.write("base_size_percent: 4\nvolume: outside\n")
    job = client.submit(os.path.join(data, "fuze.obj"), params=params_file)
    expect(list(client.watch(job))[-1].state == "succeeded", "the job from a YAML file did not succeed")
    params = client.status(job).report["parameters"]
    expect(params["base_size"] == "4%" and params["volume"] == "outside",
           "the YAML file's parameters were not used: %s" % params)
    client.delete(job)
    client.delete(result.job_id)
    try:
        vdbwrap.Client(args.address, token="wrong").jobs()
        fail("a wrong token was accepted")
    except vdbwrap.AuthenticationError as e:
        expect(e.code == "UNAUTHENTICATED", "wrong token: %s" % e)
    client.close()
    print("client checks: ok (%d progress events)" % len(events))
    return 0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--server-bin")
    ap.add_argument("--cli", required=True)
    ap.add_argument("--data", required=True)
    ap.add_argument("--venv", required=True)
    ap.add_argument("--checks", action="store_true", help="(internal) run the checks in the venv")
    ap.add_argument("--address")
    ap.add_argument("--token-file")
    ap.add_argument("--work")
    args = ap.parse_args()
    return checks(args) if args.checks else driver(args)


if __name__ == "__main__":
    sys.exit(main())
