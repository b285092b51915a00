#!/usr/bin/env python3
"""Summarises a `cargo test --no-fail-fast` log for tools/test.sh: every test binary that failed
(with its failing tests, or how it died when it printed no result), then one last line in the
form of cargo's own, `test result: ok. ...` or `test result: FAILED. ...`, totalled over all
binaries. Exits non-zero when anything failed, including cargo itself (a build error) or a
check named with --failed.

A test binary that died by a signal before reporting (a crash, not a failed assertion) is run
once more by tools/test.sh (`--crashed` lists them); given that run's log (`--rerun`), a binary
whose rerun passes counts with the rerun's result, and the last line names it as one that
crashed and then passed. One crash in a run of the suite here has been an intermittent
SIGSEGV in a binary that then passed 15 runs out of 15 (tests/reference.rs, 2026-12-04); a
crash that repeats fails.

`--self-test` checks the parser on a made-up log.
"""

import argparse
import re
import sys

SECTION = re.compile(r"^\s+(?:Running (?P<run>.+?)(?: \(.*\))?|Doc-tests (?P<doc>\S+))\s*$")
RESULT = re.compile(
    r"^test result: (?P<verdict>ok|FAILED)\. (?P<passed>\d+) passed; (?P<failed>\d+) failed; (?P<ignored>\d+) ignored"
)
CRASH = re.compile(r"process didn't exit successfully: .*?\((?P<why>[^)]*)\)\s*$")


def parse(lines):
    """[{name, result (a RESULT match or None), failures [test names], crash (str or None)}]."""
    binaries = []
    for line in lines:
        line = line.rstrip("\n")
        m = SECTION.match(line)
        if m:
            name = m.group("run") or f"doc-tests {m.group('doc')}"
            binaries.append({"name": name, "result": None, "failures": [], "crash": None, "lines": []})
            continue
        if not binaries:
            continue
        b = binaries[-1]
        if b["result"] is None and (r := RESULT.match(line)):
            b["result"] = r
            b["failures"] = failing_tests(b["lines"])
        elif c := CRASH.search(line):
            b["crash"] = c.group("why")
        else:
            b["lines"].append(line)
    return binaries


def failing_tests(lines):
    """The names cargo lists under the last `failures:` header of a binary's output."""
    starts = [i for i, l in enumerate(lines) if l == "failures:"]
    if not starts:
        return []
    names = []
    for l in lines[starts[-1] + 1 :]:
        if not l.strip():
            if names:
                break
            continue
        if not l.startswith("    "):
            break
        names.append(l.strip())
    return names


def crashed(binaries):
    """The binaries that died by a signal before reporting a result."""
    return [b for b in binaries if b["crash"] and "signal" in b["crash"] and b["result"] is None]


def cargo_test_name(name):
    """`tests/reference.rs` -> `reference` (the name `cargo test --test` takes), else None."""
    m = re.fullmatch(r"tests/(?P<name>[A-Za-z0-9_]+)\.rs", name)
    return m and m.group("name")


def summarise(lines, cargo_status, failed_checks, passed_checks, rerun_lines=()):
    binaries = parse(lines)
    reruns = {b["name"]: b for b in parse(rerun_lines)}
    flaky = []
    for i, b in enumerate(binaries):
        again = reruns.get(b["name"])
        if b in crashed(binaries) and again and again["result"] and again["result"].group("verdict") == "ok" \
                and not again["crash"]:
            flaky.append(f"{b['name']} ({b['crash']})")
            binaries[i] = again
    if flaky and cargo_status != 0 and all(b["result"] and not b["crash"] for b in binaries):
        cargo_status = 0  # cargo failed only for the binaries that passed on their rerun
    out = []
    total = {"passed": 0, "failed": 0, "ignored": 0}
    bad = []
    for b in binaries:
        r = b["result"]
        if r:
            for k in total:
                total[k] += int(r.group(k))
        if r and r.group("verdict") == "ok" and not b["crash"]:
            continue
        bad.append(b["name"])
        if r:
            out.append(f"[test] FAILED {b['name']}: {r.group('failed')} of "
                       f"{int(r.group('passed')) + int(r.group('failed'))} tests failed")
            out += [f"[test]     {t}" for t in b["failures"]]
        else:
            why = b["crash"] or "no test result"
            out.append(f"[test] FAILED {b['name']}: the binary died before reporting ({why})")
    for check in failed_checks:
        out.append(f"[test] FAILED {check}")
    notes = [f"{len(binaries)} test binaries" + (f", {len(bad)} failed: {', '.join(bad)}" if bad else "")]
    if flaky:
        notes.append(f"crashed, then passed when run again: {', '.join(flaky)}")
    if cargo_status != 0 and not bad:
        notes.append(f"cargo test exited with {cargo_status} before running everything (build error? see above)")
        out.append(f"[test] FAILED cargo test (exit status {cargo_status}, no failing binary found in its output)")
    notes += [f"{c}: FAILED" for c in failed_checks] + [f"{c}: ok" for c in passed_checks]
    ok = cargo_status == 0 and not bad and not failed_checks and binaries
    if not binaries and cargo_status == 0:
        notes.append("no test binary ran")
    verdict = "ok" if ok else "FAILED"
    out.append(f"test result: {verdict}. {total['passed']} passed; {total['failed']} failed; "
               f"{total['ignored']} ignored; {'; '.join(notes)}")
    return out, 0 if ok else 1


SAMPLE = """\
   Compiling hybrid-rt v0.1.0
     Running unittests src/lib.rs (target/debug/deps/hybrid_rt-1)

running 3 tests
test a ... ok
test b ... ignored
test c ... ok

test result: ok. 2 passed; 0 failed; 1 ignored; 0 measured; 0 filtered out; finished in 0.01s

     Running tests/soak.rs (target/debug/deps/soak-2)

running 2 tests
test keeps_flat ... FAILED
test other ... FAILED

failures:

---- keeps_flat stdout ----
failures:
    not_a_test_name

thread 'keeps_flat' panicked at tests/soak.rs:1:1:
host memory grows

failures:
    keeps_flat
    other

test result: FAILED. 0 passed; 2 failed; 0 ignored; 0 measured; 0 filtered out; finished in 1.00s

error: test failed, to rerun pass `--test soak`
     Running tests/viewer.rs (target/debug/deps/viewer-3)

running 1 test
error: test failed, to rerun pass `--test viewer`

Caused by:
  process didn't exit successfully: `target/debug/deps/viewer-3` (signal: 11, SIGSEGV: invalid memory reference)
   Doc-tests hybrid_rt

running 0 tests

test result: ok. 0 passed; 0 failed; 0 ignored; 0 measured; 0 filtered out; finished in 0.00s

error: 2 targets failed:
    `--test soak`
    `--test viewer`
"""


def self_test():
    lines = SAMPLE.splitlines()
    out, status = summarise(lines, 101, [], ["msrv check"])
    expected = [
        "[test] FAILED tests/soak.rs: 2 of 2 tests failed",
        "[test]     keeps_flat",
        "[test]     other",
        "[test] FAILED tests/viewer.rs: the binary died before reporting (signal: 11, SIGSEGV: invalid memory reference)",
        "test result: FAILED. 2 passed; 2 failed; 1 ignored; 4 test binaries, 2 failed: tests/soak.rs, "
        "tests/viewer.rs; msrv check: ok",
    ]
    good = [l for l in lines if "soak" not in l and "viewer" not in l]
    ok_out, ok_status = summarise(good[: good.index("error: 2 targets failed:")], 0, [], [])
    build_out, build_status = summarise(["error[E0425]: cannot find value `x`"], 101, ["msrv check"], [])
    no_soak = [l for l in lines if "soak" not in l and "keeps_flat" not in l and "other" not in l
               and not l.startswith("    `")]
    rerun = ["     Running tests/viewer.rs (target/debug/deps/viewer-3)", "",
             "test result: ok. 1 passed; 0 failed; 0 ignored; 0 measured; 0 filtered out; finished in 1.00s"]
    flaky_out, flaky_status = summarise(no_soak, 101, [], [], rerun)
    crash_again_out, crash_again_status = summarise(no_soak, 101, [], [], no_soak)
    checks = [
        (out == expected and status == 1, f"failing log: {out}"),
        (ok_status == 0 and ok_out[-1].startswith("test result: ok. 2 passed; 0 failed; 1 ignored; 2 test binaries"),
         f"passing log: {ok_out}"),
        (build_status == 1 and build_out[-1].startswith("test result: FAILED. 0 passed") and "msrv check: FAILED"
         in build_out[-1], f"build error: {build_out}"),
        (flaky_status == 0 and flaky_out[-1].startswith("test result: ok. 3 passed; 0 failed; 1 ignored; 3 test binaries")
         and "crashed, then passed when run again: tests/viewer.rs (signal: 11" in flaky_out[-1],
         f"crash that passed its rerun: {flaky_out}"),
        (crash_again_status == 1 and "1 failed: tests/viewer.rs" in crash_again_out[-1],
         f"crash that repeated: {crash_again_out}"),
        ([cargo_test_name(b["name"]) for b in crashed(parse(lines))] == ["viewer"], "--crashed"),
    ]
    for good_case, what in checks:
        if not good_case:
            print(f"[test] summary self-test FAILED on the {what}")
    return 0 if all(c for c, _ in checks) else 1


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("log", nargs="?", help="cargo test's output (stdout and stderr)")
    ap.add_argument("--cargo-status", type=int, default=0, help="cargo test's exit status")
    ap.add_argument("--failed", action="append", default=[], help="another check that failed (repeatable)")
    ap.add_argument("--passed", action="append", default=[], help="another check that passed (repeatable)")
    ap.add_argument("--rerun", action="append", default=[], help="the log of a crashed binary run again (repeatable)")
    ap.add_argument("--crashed", action="store_true",
                    help="print the `cargo test --test` names of the binaries that died by a signal, and exit")
    ap.add_argument("--self-test", action="store_true", help="check the parser on a made-up log and exit")
    args = ap.parse_args()
    if args.self_test:
        return self_test()
    if not args.log:
        ap.error("a log file is required")
    with open(args.log, encoding="utf-8", errors="replace") as f:
        lines = f.readlines()
    if args.crashed:
        print("\n".join(n for n in (cargo_test_name(b["name"]) for b in crashed(parse(lines))) if n))
        return 0
    rerun_lines = []
    for path in args.rerun:
        with open(path, encoding="utf-8", errors="replace") as f:
            rerun_lines += f.readlines()
    out, status = summarise(lines, args.cargo_status, args.failed, args.passed, rerun_lines)
    print("\n".join(out))
    return status


if __name__ == "__main__":
    sys.exit(main())
