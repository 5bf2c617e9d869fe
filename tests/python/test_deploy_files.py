#!/usr/bin/python3
"""Static checks of the service's deployment files (no Docker or Kubernetes needed): the
compose `server` service, the Kubernetes manifests (restricted Pod Security Standard, the job
memory limit under the pod's, the image pinned by kustomize) and the Dockerfile (runtime set,
non-root user, health check)."""
import os
import re
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


def arg(args, name):
    """The value of --name=VALUE in a container's args, or None."""
    for a in args:
        if str(a).startswith(name + "="):
            return str(a)[len(name) + 1:]
    return None


def size_bytes(text):
    """Kubernetes quantities (16Gi, 512Mi, 2G) and the server's sizes (14G: powers of 1024)."""
    m = re.fullmatch(r"([0-9.]+)\s*([kKMGT]i?)?B?", str(text))
    if not m:
        raise ValueError("not a size: %r" % text)
    unit = m.group(2) or ""
    power = {"": 0, "k": 1, "K": 1, "M": 2, "G": 3, "T": 4}[unit[:1]]
    return float(m.group(1)) * 1024 ** power


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
with open(os.path.join(ROOT, "docker", "Dockerfile")) as f:
    dockerfile = f.read()
uid = re.search(r"useradd [^\n]*--uid (\d+)", dockerfile)
gid = re.search(r"groupadd [^\n]*--gid (\d+)", dockerfile)
check(uid and gid, "Dockerfile: a user and a group with fixed ids")
uid, gid = (int(uid.group(1)), int(gid.group(1))) if uid and gid else (None, None)
check(uid != 0 and re.search(r"^USER %s:%s$" % (uid, gid), dockerfile, re.M), "Dockerfile: USER uid:gid, numeric, not root")
check(re.search(r"chown %s:%s [^\n]*/spool" % (uid, gid), dockerfile), "Dockerfile: /spool owned by the user")

kustomization = kinds.get("Kustomization", [{}])[0]
pinned = {i.get("name"): i for i in kustomization.get("images", [])}
check("statefulset.yaml" in kustomization.get("resources", []), "kustomization: the StatefulSet")
for kind in ("StatefulSet", "Deployment"):
    for wl in kinds.get(kind, []):
        pod = wl["spec"]["template"]["spec"]
        c = pod["containers"][0]
        # The restricted Pod Security Standard, at the pod or the container level.
        psc, csc = pod.get("securityContext", {}), c.get("securityContext", {})
        merged = dict(psc, **csc)
        check(merged.get("runAsNonRoot") is True, "%s: runAsNonRoot" % kind)
        check(merged.get("runAsUser") == uid and merged.get("runAsGroup") == gid, "%s: runs as the image's user" % kind)
        check(psc.get("fsGroup") == gid, "%s: fsGroup makes the spool writable" % kind)
        check(merged.get("seccompProfile", {}).get("type") == "RuntimeDefault", "%s: seccomp RuntimeDefault" % kind)
        check(csc.get("allowPrivilegeEscalation") is False, "%s: allowPrivilegeEscalation false" % kind)
        check(csc.get("capabilities", {}).get("drop") == ["ALL"] and not csc.get("capabilities", {}).get("add"),
              "%s: capabilities drop ALL" % kind)
        check(not csc.get("privileged") and not any("hostPath" in v for v in pod.get("volumes", [])),
              "%s: no privileges, no host paths" % kind)
        mounts = {m["name"]: m for m in c.get("volumeMounts", [])}
        check(mounts.get("spool", {}).get("mountPath") == "/spool" and not mounts["spool"].get("readOnly"),
              "%s: spool mounted writable" % kind)
        # Each job's memory limit leaves room for the server under the container's limit.
        args = [str(a) for a in c["args"]]
        limit = c.get("resources", {}).get("limits", {}).get("memory")
        job_memory = arg(args, "--job-memory")
        workers = int(arg(args, "--workers") or 1)
        check(limit and job_memory and 0 < workers * size_bytes(job_memory) < size_bytes(limit),
              "%s: --workers x --job-memory below the memory limit" % kind)
        check(arg(args, "--max-attempts") and arg(args, "--retain"), "%s: --max-attempts and --retain" % kind)
        # A pinned image: by kustomize for the resources it builds, else by the tag itself.
        image = c["image"]
        name, _, tag = image.partition(":")
        if kind == "StatefulSet":
            entry = pinned.get(name, {})
            check(entry.get("digest") or entry.get("newTag") not in (None, "", "latest"),
                  "kustomization: images pins %s" % name)
        else:
            check(tag not in ("", "latest"), "%s: image tag pinned" % kind)

sts = kinds.get("StatefulSet", [{}])[0]
check(bool(sts.get("spec", {}).get("volumeClaimTemplates")), "StatefulSet: persistent spool per replica")
check(sts.get("spec", {}).get("serviceName") == "vdbwrap-replicas", "StatefulSet: headless service")

for needle in ("libgrpc++1.51", "libprotobuf32", "VDBWRAP_BUILD_SERVICE=ON", "vdbwrap-server --version", "/spool"):
    check(needle in dockerfile, "Dockerfile: " + needle)
# The image's health check asks the job server's own port through the gRPC health service.
healthcheck = re.search(r"^HEALTHCHECK ((?:[^\n]*\\\n)*[^\n]*)", dockerfile, re.M)  # with continued lines
healthcheck = healthcheck.group(1) if healthcheck else ""
check(re.search(r'"health", "--server", "(127\.0\.0\.1|localhost):50051"', healthcheck) and "--version" not in healthcheck,
      "Dockerfile: HEALTHCHECK runs vdbwrap health against port 50051")
check(any(str(a).startswith("--job-memory=") for a in server.get("command", [])), "compose: --job-memory")
check(any(str(a).startswith("--retain=") for a in server.get("command", [])), "compose: --retain")

if failures:
    print("deployment files: " + "; ".join(failures), file=sys.stderr)
    sys.exit(1)
print("deployment files: ok")
