#!/usr/bin/env python3
"""Fails when the test suite skipped a test it is not expected to skip.

    scripts/check_skips.py rust CARGO_TEST_LOG [ARTIFACTS]
    scripts/check_skips.py python JUNIT_XML

CARGO_TEST_LOG: the output of `cargo test` (stdout and stderr). ARTIFACTS: the output of the
same `cargo test ... --no-run --message-format=json`, which names the source file of each test
executable: cargo's "Running tests/roots.rs" is relative to the package, and two packages of
the workspace have a tests/roots.rs; with it, the test target is the source path relative to
the workspace root (verify/tests/roots.rs). JUNIT_XML: pytest's --junitxml report.

Prints the number of skipped (Python) or ignored (Rust) tests and compares them, by name, with
scripts/expected_skips.txt (the allow-list, with the reasons): a skip not on the list, or an
entry of the list that was not skipped, is an error (exit status 1). Used by scripts/test.sh.
"""

import pathlib
import re
import sys
import xml.etree.ElementTree as ET

ALLOW_LIST = pathlib.Path(__file__).resolve().parent / "expected_skips.txt"

# cargo's header of each test binary (stderr): "Running tests/soak.rs (target/...)",
# "Running unittests src/lib.rs (target/...)", "Doc-tests eopnp".
RUNNING = re.compile(r"^\s*Running (?:unittests )?(.+?) \((.*)\)\s*$")
DOC_TESTS = re.compile(r"^\s*Doc-tests (\S+)\s*$")
# libtest: "test soak_full ... ignored" or "test soak_full ... ignored, <reason>".
IGNORED = re.compile(r"^test (.+) \.\.\. ignored(, .*)?$")
RESULT = re.compile(r"^test result: \w+\. (\d+) passed; (\d+) failed; (\d+) ignored;")


def allow_list(kind):
    """{test: reason} of the allow-list's entries of `kind` ("rust" or "python")."""
    out = {}
    for number, line in enumerate(ALLOW_LIST.read_text().splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        entry, sep, reason = line.partition(" -- ")
        words = entry.split()
        if not sep or not reason.strip() or words[0] not in ("rust", "python"):
            sys.exit(f"{ALLOW_LIST}:{number}: expected `rust|python TEST -- reason`: {line}")
        if words[0] != kind:
            continue
        if kind == "rust":
            # Target and name may contain spaces ("unittests src/lib.rs", a doc test's
            # "src/lib.rs - Solver (line 12)"): the target ends at the first ": ".
            target, colon, name = entry[len("rust"):].strip().partition(": ")
            if not colon or not target or not name.strip():
                sys.exit(f"{ALLOW_LIST}:{number}: expected `rust TARGET: NAME -- reason`")
            test = (target, name.strip())
        else:
            if len(words) != 2:
                sys.exit(f"{ALLOW_LIST}:{number}: expected `python NODE_ID -- reason`")
            test = words[1]
        if test in out:
            sys.exit(f"{ALLOW_LIST}:{number}: {test} listed twice")
        out[test] = reason.strip()
    return out


def executables(artifacts):
    """{executable file name: source path relative to the current directory} of the test
    executables in `cargo ... --message-format=json` output."""
    import json

    root = pathlib.Path.cwd()
    out = {}
    for line in artifacts.splitlines():
        if not line.startswith("{"):
            continue
        msg = json.loads(line)
        exe = msg.get("executable")
        if msg.get("reason") != "compiler-artifact" or not exe:
            continue
        src = pathlib.Path(msg["target"]["src_path"])
        try:
            src = src.relative_to(root)
        except ValueError:
            pass
        out[pathlib.Path(exe).name] = str(src)
    return out


def rust_ignored(log, exes=None):
    """[(target, name)] of the ignored tests in a `cargo test` log, checked against the
    per-binary summaries' "N ignored". `exes`: executables() of the run, to name each target
    by its source path from the workspace root."""
    target = None
    ignored = []
    summed = 0
    summaries = 0
    for line in log.splitlines():
        m = RUNNING.match(line)
        if m:
            target = m.group(1)
            if exes is not None:
                exe = pathlib.Path(m.group(2)).name
                if exe not in exes:
                    sys.exit(f"{exe} ({target}) is not among the build's test executables")
                target = exes[exe]
            continue
        m = DOC_TESTS.match(line)
        if m:
            target = m.group(1)
            continue
        m = IGNORED.match(line)
        if m:
            if target is None:
                sys.exit(f"ignored test before any test binary's header: {line}")
            ignored.append((target, m.group(1)))
            continue
        m = RESULT.match(line)
        if m:
            summaries += 1
            summed += int(m.group(3))
    if summaries == 0:
        sys.exit("no `test result:` line: not the output of `cargo test`")
    if summed != len(ignored):
        sys.exit(
            f"the summaries count {summed} ignored tests but {len(ignored)} were named "
            "(`test NAME ... ignored` lines): is the log complete?"
        )
    return ignored, summaries


def python_skipped(junit):
    """[node id] of the skipped tests (xfail included) in a pytest JUnit XML report written
    with junit_family=xunit1 (which records each test's file)."""
    skipped = []
    total = 0
    for case in ET.parse(junit).getroot().iter("testcase"):
        total += 1
        if case.find("skipped") is None:
            continue
        file = case.get("file") or ""
        classname = case.get("classname") or ""
        module = file[:-3].replace("/", ".") if file.endswith(".py") else ""
        cls = classname[len(module) + 1:] if module and classname.startswith(module + ".") else ""
        parts = [file or classname] + ([cls] if cls else []) + [case.get("name") or "?"]
        skipped.append("::".join(parts))
    if total == 0:
        sys.exit(f"{junit}: no test case")
    return skipped, total


def compare(label, got, expected, show):
    """Prints the skips and the differences with the allow-list; returns whether they agree."""
    unexpected = [t for t in got if t not in expected]
    missing = [t for t in expected if t not in got]
    print(f"{label}: {len(got)} skipped/ignored, {len(expected)} expected")
    for t in got:
        print(f"  {show(t)}: {expected.get(t, 'NOT EXPECTED')}")
    for t in unexpected:
        print(f"error: {label}: {show(t)} was skipped/ignored; it is not in {ALLOW_LIST.name}",
              file=sys.stderr)
    for t in missing:
        print(f"error: {label}: {show(t)} is in {ALLOW_LIST.name} but was not skipped/ignored "
              "(remove the entry, or restore the skip)", file=sys.stderr)
    return not unexpected and not missing


def main(argv):
    most = {"rust": 4, "python": 3}.get(argv[1] if len(argv) > 1 else "", 0)
    if not 3 <= len(argv) <= most:
        sys.exit(__doc__)
    kind, path = argv[1], pathlib.Path(argv[2])
    if kind == "rust":
        exes = executables(pathlib.Path(argv[3]).read_text()) if len(argv) == 4 else None
        got, binaries = rust_ignored(path.read_text(errors="replace"), exes)
        ok = compare(f"Rust ({binaries} test binaries)", got, allow_list("rust"),
                     lambda t: f"{t[0]}: {t[1]}")
    else:
        got, total = python_skipped(path)
        ok = compare(f"Python ({total} tests)", got, allow_list("python"), str)
    if len(set(got)) != len(got):
        print(f"error: {kind}: a test is reported twice: {got}", file=sys.stderr)
        ok = False
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
