#!/usr/bin/python3
"""Static checks of the service's deployment files (no Docker or Kubernetes needed): the
compose `server` service, the Kubernetes manifests and the Dockerfile's runtime set."""
import os
import sys

import yaml  # Debian: python3-yaml

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)


def load_all(path):
    with open(os.path.join(ROOT, path)) as f:
        return [d for d in yaml.safe_load_all(f) if d]


compose = load_all("docker/compose.yaml")[0]
server = compose["services"].get("server", {})
check(server.get("entrypoint") == ["/opt/vdbwrap/bin/vdbwrap-server"], "compose: server entrypoint")
check(any(str(a).startswith("--spool=/spool") for a in server.get("command", [])), "compose: --spool=/spool")
check(any(str(a).startswith("--listen=0.0.0.0:50051") for a in server.get("command", [])), "compose: --listen")
check(any(str(v).startswith("spool:/spool") for v in server.get("volumes", [])), "compose: spool volume")
check("spool" in (compose.get("volumes") or {}), "compose: named volume spool")
check("health" in server.get("healthcheck", {}).get("test", []), "compose: health check with `vdbwrap health`")

kinds = {}
for name in ("service.yaml", "statefulset.yaml", "deployment.yaml", "kustomization.yaml"):
    for doc in load_all(os.path.join("deploy", "k8s", name)):
        kinds.setdefault(doc["kind"], []).append(doc)
check(len(kinds.get("Service", [])) == 2, "k8s: two Services")
for svc in kinds.get("Service", []):
    check(svc["spec"]["ports"][0]["port"] == 50051, "k8s: Service port 50051")
for kind in ("StatefulSet", "Deployment"):
    check(kind in kinds, "k8s: a %s" % kind)
    for wl in kinds.get(kind, []):
        c = wl["spec"]["template"]["spec"]["containers"][0]
        check(c["command"] == ["/opt/vdbwrap/bin/vdbwrap-server"], "%s: command" % kind)
        probe = c.get("readinessProbe", {}).get("grpc", {})
        check(probe.get("port") == 50051 and probe.get("service") == "vdbwrap.v1.Jobs", "%s: gRPC readiness probe" % kind)
        check("grpc" in c.get("livenessProbe", {}), "%s: gRPC liveness probe" % kind)
        check(any(a.startswith("--spool=") for a in c["args"]), "%s: --spool" % kind)
        check(any(a.startswith("--token-file=") for a in c["args"]), "%s: --token-file" % kind)
        labels = wl["spec"]["selector"]["matchLabels"]
        check(all(wl["spec"]["template"]["metadata"]["labels"].get(k) == v for k, v in labels.items()), "%s: labels" % kind)
sts = kinds.get("StatefulSet", [{}])[0]
check(bool(sts.get("spec", {}).get("volumeClaimTemplates")), "StatefulSet: persistent spool per replica")
check(sts.get("spec", {}).get("serviceName") == "vdbwrap-replicas", "StatefulSet: headless service")

with open(os.path.join(ROOT, "docker", "Dockerfile")) as f:
    dockerfile = f.read()
for needle in ("libgrpc++1.51", "libprotobuf32", "VDBWRAP_BUILD_SERVICE=ON", "vdbwrap-server --version", "/spool"):
    check(needle in dockerfile, "Dockerfile: " + needle)

if failures:
    print("deployment files: " + "; ".join(failures), file=sys.stderr)
    sys.exit(1)
print("deployment files: ok")
