#!/usr/bin/env python3
"""The numbers of the documents, from the commands that print them.

    python3 scripts/refresh_docs.py                 # run every block's command, paste its output
    python3 scripts/refresh_docs.py --only accuracy # only the blocks whose command contains this
    python3 scripts/refresh_docs.py --check         # run the deterministic blocks, fail if stale
    python3 scripts/refresh_docs.py --deterministic # refresh the deterministic blocks only
    python3 scripts/refresh_docs.py --list          # the blocks and their commands

A block of a document (README.md, CONTRIBUTING.md, python/README.md, docs/*.md; not
docs/history/, which keeps what was measured then) is written as

    <!-- output [OPTIONS]: COMMAND -->
    ...what COMMAND printed...
    <!-- end output -->

COMMAND runs with bash from the repository root; its standard output replaces the block's
content. OPTIONS, comma-separated: `fence` wraps the output in a ```text fence; `check` marks a
command whose output does not depend on the machine or the time (seeded accuracy tables, counts),
which `--check` runs and compares, so that CI fails when a document no longer says what its
command prints. Blocks without `check` (timings) are refreshed by hand, on a quiet machine, with
the commit they were measured on named in the commit message.
"""

import argparse
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BLOCK = re.compile(
    r"(<!-- output(?: \[(?P<opts>[^\]]*)\])?: (?P<cmd>.*?) -->\n)(?P<body>.*?)(<!-- end output -->)",
    re.S,
)


def documents():
    """docs/ first (in name order: a block may read a file an earlier block's command wrote,
    e.g. the comparison's `target/compare/summary.md`), then the READMEs and the guide."""
    docs = sorted(p for p in (ROOT / "docs").glob("*.md"))
    docs += [ROOT / "README.md", ROOT / "CONTRIBUTING.md", ROOT / "python" / "README.md"]
    return [d for d in docs if d.exists()]


def run(cmd, cache):
    if cmd not in cache:
        print(f"$ {cmd}", file=sys.stderr, flush=True)
        r = subprocess.run(["bash", "-c", cmd], cwd=ROOT, capture_output=True, text=True)
        if r.returncode != 0:
            sys.stderr.write(r.stderr[-4000:])
            sys.exit(f"command failed ({r.returncode}): {cmd}")
        cache[cmd] = r.stdout
    return cache[cmd]


def render(out, opts):
    out = out.rstrip("\n") + "\n"
    if "fence" in opts:
        out = "```text\n" + out + "```\n"
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", help="only the blocks whose command contains this text")
    ap.add_argument("--check", action="store_true", help="compare the `check` blocks, write nothing")
    ap.add_argument("--list", action="store_true", help="list the blocks")
    ap.add_argument("--deterministic", action="store_true", help="refresh the `check` blocks only")
    args = ap.parse_args()
    cache = {}
    stale = []
    count = 0
    for doc in documents():
        text = doc.read_text()
        rel = doc.relative_to(ROOT)

        def replace(m):
            nonlocal count
            opts = {o.strip() for o in (m.group("opts") or "").split(",") if o.strip()}
            cmd = m.group("cmd")
            if args.list:
                print(f"{rel}: [{', '.join(sorted(opts))}] {cmd}")
                return m.group(0)
            if args.only and args.only not in cmd:
                return m.group(0)
            if (args.check or args.deterministic) and "check" not in opts:
                return m.group(0)
            count += 1
            body = render(run(cmd, cache), opts)
            if args.check:
                if body != m.group("body"):
                    stale.append(f"{rel}: the output of `{cmd}` differs from the document")
                return m.group(0)
            return m.group(1) + body + m.group(5)

        new = BLOCK.sub(replace, text)
        if not args.check and not args.list and new != text:
            doc.write_text(new)
            print(f"updated {rel}", file=sys.stderr)
    if args.check:
        for s in stale:
            print(s)
        if stale:
            sys.exit(1)
        print(f"{count} deterministic blocks match their commands")


if __name__ == "__main__":
    main()
