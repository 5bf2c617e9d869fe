#!/usr/bin/python3
"""The options reference cannot drift from the programs (issue 34).

Runs `vdbwrap --help` and `vdbwrap COMMAND --help` for every command the binary has, and
`vdbwrap-server --help` when given, and compares their long options with the docs:

- docs/cli.md, the full reference: for each command, the options in the tables of the
  sections whose heading names it (`## `vdbwrap wrap``, or several commands in backticks)
  must be exactly the options of its --help. `submit` also takes the options documented for
  `wrap` and `repair` (its help must hold no option documented nowhere, and its own sections
  no option its help lacks).
- README.md, the summary: the options in the tables of its command sections must exist in
  that command's --help, and its `wrap` section must list every option of `wrap --help`.
- docs/service.md: the table of "Starting the server" is exactly `vdbwrap-server --help`.
- Every `--option` written in backticks anywhere in docs/cli.md exists in some --help.

Usage: test_readme_options.py --cli build/client/vdbwrap [--server-bin build/server/vdbwrap-server]
"""
import argparse
import os
import re
import subprocess
import sys

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
REMOTE = {"submit", "wait", "jobs", "cancel", "delete", "health"}
INHERITS = {"submit": ("wrap", "repair")}  # submit takes wrap's options, and with --repair repair's
LONG = re.compile(r"(?<![\w-])--[a-z][a-z0-9-]*")

failures = []


def fail(what):
    failures.append(what)


def help_text(argv):
    run = subprocess.run(argv + ["--help"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if run.returncode != 0:
        raise SystemExit("%s --help exited %d:\n%s" % (" ".join(argv), run.returncode, run.stdout))
    return run.stdout


def help_options(text):
    """The long options a CLI11 --help defines: the first word of each line that starts
    with two spaces and a dash ('-o,--output', '--sliver-removal,--no-sliver-removal{false}')."""
    opts = set()
    for line in text.splitlines():
        m = re.match(r"^  (-\S+)", line)
        if not m:
            continue
        for name in re.sub(r"\{[^}]*\}", "", m.group(1)).split(","):
            if name.startswith("--") and name != "--help":
                opts.add(name)
    return opts


def subcommands(text):
    """The names listed under 'Subcommands:' of the top-level --help."""
    names, inside = [], False
    for line in text.splitlines():
        if line.startswith("Subcommands:"):
            inside = True
            continue
        if inside:
            m = re.match(r"^  ([a-z][a-z-]*)\s", line)
            if m:
                names.append(m.group(1))
            elif line.strip() and not line.startswith(" "):
                break
    return names


def strip_fences(lines):
    """The lines outside ``` blocks."""
    out, fenced = [], False
    for line in lines:
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        if not fenced:
            out.append(line)
    return out


def documented(path, commands):
    """{command: set of long options} from the first cell of the table rows in the sections
    whose heading names the command in backticks (`vdbwrap wrap` or `wrap`). A heading naming
    commands starts a section; a heading as high or higher that names none ends it; deeper
    headings stay inside it."""
    with open(path) as f:
        lines = strip_fences(f.read().splitlines())
    result = {}
    current, level = [], 0
    for line in lines:
        h = re.match(r"^(#+)\s+(.*)", line)
        if h:
            named = []
            for span in re.findall(r"`([^`]+)`", h.group(2)):
                word = span[len("vdbwrap "):] if span.startswith("vdbwrap ") else span
                if word in commands:
                    named.append(word)
            if named:
                current, level = named, len(h.group(1))
                for c in named:
                    result.setdefault(c, set())
            elif current and len(h.group(1)) <= level:
                current = []
            continue
        if current and line.startswith("|") and not re.match(r"^\|[\s|:-]+\|?\s*$", line):
            first = line.split("|")[1]
            for c in current:
                result[c].update(LONG.findall(first))
    return result


def section_table(path, heading):
    """Long options in the first cell of the table rows under the heading (to the next
    heading as high or higher)."""
    with open(path) as f:
        lines = strip_fences(f.read().splitlines())
    opts, level = set(), 0
    for line in lines:
        h = re.match(r"^(#+)\s+(.*)", line)
        if h:
            if h.group(2).strip() == heading:
                level = len(h.group(1))
            elif level and len(h.group(1)) <= level:
                level = 0
            continue
        if level and line.startswith("|"):
            opts.update(LONG.findall(line.split("|")[1]))
    return opts


def names(s):
    return ", ".join(sorted(s))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cli", required=True, help="the built vdbwrap")
    ap.add_argument("--server-bin", help="the built vdbwrap-server (checks docs/service.md)")
    args = ap.parse_args()

    cmds = subcommands(help_text([args.cli]))
    if "wrap" not in cmds:
        raise SystemExit("no subcommands found in `vdbwrap --help`")
    helps = {c: help_options(help_text([args.cli, c])) for c in cmds}
    every = set().union(*helps.values())
    known = set(cmds) | REMOTE | {"check", "repair", "wrap"}

    cli_md = os.path.join(ROOT, "docs", "cli.md")
    docs = documented(cli_md, known)
    for c in cmds:
        if c not in docs:
            fail("docs/cli.md: no section for `vdbwrap %s` (a heading naming it in backticks)" % c)
            continue
        inherited = set().union(*(docs.get(p, set()) for p in INHERITS.get(c, ())))
        missing = helps[c] - docs[c] - inherited
        if missing:
            fail("docs/cli.md: `vdbwrap %s --help` has %s, not in its option tables" % (c, names(missing)))
        extra = docs[c] - helps[c]
        if extra:
            fail("docs/cli.md: `vdbwrap %s` documents %s, which `vdbwrap %s --help` does not have" % (c, names(extra), c))
    for c in docs:
        if c not in cmds and c not in REMOTE:  # remote commands are absent without the service
            fail("docs/cli.md: documents `vdbwrap %s`, which `vdbwrap --help` does not list" % c)

    with open(cli_md) as f:
        prose = "\n".join(strip_fences(f.read().splitlines()))
    for span in re.findall(r"`([^`\n]+)`", prose):
        if "did you mean" in span:  # the example of a mistyped option
            continue
        for opt in LONG.findall(span):
            if opt not in every and opt != "--help":
                fail("docs/cli.md: mentions `%s`, an option of no command" % opt)

    readme = os.path.join(ROOT, "README.md")
    summary = documented(readme, known)
    if "wrap" not in summary:
        fail("README.md: no `vdbwrap wrap` options section")
    for c, opts in summary.items():
        if c not in helps:
            continue
        extra = opts - helps[c]
        if extra:
            fail("README.md: `vdbwrap %s` lists %s, which `vdbwrap %s --help` does not have" % (c, names(extra), c))
    if "wrap" in summary:
        missing = helps["wrap"] - summary["wrap"]
        if missing:
            fail("README.md: `vdbwrap wrap --help` has %s, not in the README's wrap options" % names(missing))

    if args.server_bin:
        server = help_options(help_text([args.server_bin])) - {"--version"}
        doc = section_table(os.path.join(ROOT, "docs", "service.md"), "Starting the server")
        if server - doc:
            fail("docs/service.md: `vdbwrap-server --help` has %s, not in \"Starting the server\"" % names(server - doc))
        if doc - server:
            fail("docs/service.md: \"Starting the server\" lists %s, which `vdbwrap-server --help` does not have"
                 % names(doc - server))

    counted = sum(len(v) for v in helps.values())
    if failures:
        print("The options reference has drifted from --help (add the option to the docs, or drop it there):")
        for f in failures:
            print("  " + f)
        return 1
    print("ok: %d commands, %d options (with repeats) match docs/cli.md and README.md%s"
          % (len(cmds), counted, "; the server's match docs/service.md" if args.server_bin else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
