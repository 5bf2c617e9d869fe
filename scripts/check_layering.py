#!/usr/bin/env python3
"""The include graph of core/ keeps its layers: a folder includes only folders below it, the
stages never include the API header vdbwrap/wrap.h (only the pipeline that implements it
does), and the CLI, the server and the API mapping include the core's public headers only.

Usage: scripts/check_layering.py [--graph]   (exit 1 on a violation; --graph prints the
folder-level include graph of core/ as "from -> to (count)" lines)
"""
import os, re, sys
from collections import Counter

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Lowest first: a folder may include itself and any folder before it.
LAYERS = ["common", "mesh", "io", "check", "prep", "grid", "extract", "fit", "post", "repair", "report", "pipeline"]
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def sources(folder):
    for dirpath, _, files in os.walk(os.path.join(ROOT, folder)):
        for f in files:
            if f.endswith((".h", ".cpp")):
                yield os.path.join(dirpath, f)


def includes(path):
    with open(path, encoding="utf-8", errors="replace") as fh:
        return INCLUDE.findall(fh.read())


def main():
    problems, graph = [], Counter()
    for path in sources("core"):
        rel = os.path.relpath(path, os.path.join(ROOT, "core"))
        folder = rel.split(os.sep)[0] if os.sep in rel else "."
        for inc in includes(path):
            top = inc.split("/")[0]
            if inc == "vdbwrap/wrap.h" and folder not in (".", "pipeline"):
                problems.append(f"core/{rel}: a stage includes the API header vdbwrap/wrap.h")
            if folder in LAYERS and top in LAYERS and top != folder:
                graph[(folder, top)] += 1
                if LAYERS.index(top) > LAYERS.index(folder):
                    problems.append(f"core/{rel}: {folder}/ includes {inc}, a layer above it")
    for outer in ("client", "server", "proto"):
        for path in sources(outer):
            rel = os.path.relpath(path, ROOT)
            for inc in includes(path):
                if inc.split("/")[0] in LAYERS:
                    problems.append(f"{rel}: includes the core's internal header {inc} (use the public vdbwrap/ headers)")
    if "--graph" in sys.argv:
        for (a, b), n in sorted(graph.items(), key=lambda kv: (LAYERS.index(kv[0][0]), LAYERS.index(kv[0][1]))):
            print(f"{a} -> {b} ({n})")
    for p in problems:
        print(p, file=sys.stderr)
    print(f"check_layering: {len(problems)} problem(s)", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
