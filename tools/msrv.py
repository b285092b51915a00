#!/usr/bin/env python3
"""Derives hybrid-rt's minimum supported Rust version and compares it with Cargo.toml's.

Only one toolchain is installed where this runs, so the minimum cannot be found by building
with older compilers. It is derived instead, as the highest of:
- the edition's first release (2024: 1.85);
- the `rust-version` every dependency declares, over Cargo.lock's resolved graph for the host
  platform (normal, build and dev dependencies: `cargo test` builds them all);
- the language features the code uses that were stabilized after that, found by scanning the
  package's sources (FEATURES below, each with the release-notes line it comes from);
- the standard-library items the code uses: clippy's `incompatible_msrv` lint, run with the
  edition's version as the MSRV, names each newer item with the release it is stable since.

tools/check-msrv.sh runs cargo and clippy and calls this with their JSON output; this file does
no building itself. `--self-test` checks the source scanner on small snippets.

Language changes that cannot be seen in the source text and are not scanned for (checked by hand
when this was written, 1.86-1.95): trait-object upcasting (1.86; no trait here has a
supertrait), temporary lifetime extension through tuple constructors (1.89), constants holding
references to mutable memory (1.90), pattern-binding drop order (1.91).
"""

import argparse
import json
import pathlib
import re
import sys

# The first release of each edition.
EDITION_FLOOR = {"2015": (1, 0), "2018": (1, 31), "2021": (1, 56), "2024": (1, 85)}

# Folders whose .rs files cargo compiles for this package (fuzz/ is a crate of its own).
SOURCE_DIRS = ("src", "tests", "benches", "examples")
SOURCE_FILES = ("build.rs",)


def version(text):
    """'1.88' or '1.88.0' -> (1, 88); the patch level never matters for a feature."""
    parts = text.strip().split(".")
    return (int(parts[0]), int(parts[1]) if len(parts) > 1 else 0)


def show(v):
    return f"{v[0]}.{v[1]}"


# ---------------------------------------------------------------------------------------------
# Source scanning: comments, strings and char literals are blanked first (newlines kept, so line
# numbers stay right), then each feature is looked for in what is left.


def blank_non_code(src):
    out = []
    i, n = 0, len(src)

    def blank(text):
        out.append("".join(c if c == "\n" else " " for c in text))

    while i < n:
        c = src[i]
        if src.startswith("//", i):
            j = src.find("\n", i)
            j = n if j < 0 else j
            blank(src[i:j])
            i = j
        elif src.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if src.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif src.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            blank(src[i:j])
            i = j
        elif (m := re.compile(r'(?:b|c)?r(#*)"').match(src, i)) and (i == 0 or not (src[i - 1].isalnum() or src[i - 1] == "_")):
            end = src.find('"' + m.group(1), m.end())
            j = n if end < 0 else end + 1 + len(m.group(1))
            blank(src[i:j])
            i = j
        elif c == '"' or (c in "bc" and src.startswith('"', i + 1) and (i == 0 or not (src[i - 1].isalnum() or src[i - 1] == "_"))):
            j = i + (1 if c == '"' else 2)
            while j < n and src[j] != '"':
                j += 2 if src[j] == "\\" else 1
            blank(src[i : j + 1])
            i = j + 1
        elif c == "'":
            # A char literal ('x', '\n', '\u{1F600}') or a lifetime/label ('a): only the former is blanked.
            m = re.compile(r"'(?:\\(?:u\{[0-9a-fA-F]+\}|x[0-9a-fA-F]{2}|.)|[^\\'\n])'").match(src, i)
            if m:
                blank(m.group(0))
                i = m.end()
            else:
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


TOKEN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*|&&|\|\||=>|::|[(){}\[\]]|\S")


def tokens(code):
    """(text, offset) of every token of blanked code: identifiers, the few operators the
    scanner needs, brackets, and any other single character."""
    return [(m.group(0), m.start()) for m in TOKEN.finditer(code)]


def conditions(toks):
    """For every `if` and `while`: (keyword offset, condition tokens at bracket depth 0, how it
    ended: '{' for an if/while body, '=>' for a match-arm guard)."""
    for k, (word, at) in enumerate(toks):
        if word not in ("if", "while"):
            continue
        depth, top = 0, []
        for text, _ in toks[k + 1 :]:
            if text in "([":
                depth += 1
            elif text in ")]":
                depth -= 1
                if depth < 0:
                    break
            elif depth == 0 and text in ("{", "=>"):
                yield at, top, text
                break
            elif depth == 0:
                top.append(text)
            if depth == 0 and text in (";", "}"):
                break


def let_chains(code, toks):
    for at, top, end in conditions(toks):
        if end == "{" and "let" in top and ("&&" in top or "||" in top):
            yield at


def if_let_guards(code, toks):
    for at, top, end in conditions(toks):
        if end == "=>" and "let" in top:
            yield at


def regex_feature(pattern):
    rx = re.compile(pattern)
    return lambda code, toks: (m.start() for m in rx.finditer(code))


def balanced(code, start):
    """The text from `start` (just after an opening parenthesis) to its closing one."""
    depth, j = 1, start
    while j < len(code) and depth:
        depth += {"(": 1, ")": -1}.get(code[j], 0)
        j += 1
    return code[start : j - 1]


def cfg_boolean_literals(code, toks):
    for m in re.finditer(r"\bcfg(?:_attr)?!?\s*\(", code):
        if re.search(r"\b(?:true|false)\b", balanced(code, m.end())):
            yield m.start()


def asm_goto(code, toks):
    for m in re.finditer(r"\b(?:naked_)?asm!\s*\(", code):
        if re.search(r"\blabel\s*\{", balanced(code, m.end())):
            yield m.start()


def use_bounds_in_traits(code, toks):
    """`use<..>` precise-capturing bounds inside a trait's body (outside traits: 1.82)."""
    for m in re.finditer(r"\btrait\s+[A-Za-z_]\w*[^{;]*\{", code):
        depth, j = 1, m.end()
        while j < len(code) and depth:
            depth += {"{": 1, "}": -1}.get(code[j], 0)
            j += 1
        for u in re.finditer(r"\buse\s*<", code[m.end() : j]):
            yield m.end() + u.start()


# (minimum release, feature, how it is found). Each is a Language line of the release notes
# shipped with the toolchain (share/doc/rust/html/releases.md), for releases after 1.85.
FEATURES = [
    ((1, 86), "#[target_feature] on a safe function", regex_feature(
        r"#\s*\[\s*target_feature\b[^\]]*\]\s*(?:#\s*\[[^\]]*\]\s*)*(?:pub(?:\s*\([^)]*\))?\s+)?(?:const\s+)?(?:async\s+)?fn\b")),
    ((1, 87), "precise capturing (use<..>) in a trait", use_bounds_in_traits),
    ((1, 87), "asm goto (label operands)", asm_goto),
    ((1, 88), "let chains", let_chains),
    ((1, 88), "naked functions", regex_feature(r"#\s*\[\s*(?:unsafe\s*\(\s*)?naked\s*[\])]")),
    ((1, 88), "cfg(true) / cfg(false)", cfg_boolean_literals),
    ((1, 89), "#[repr(u128)] / #[repr(i128)]", regex_feature(r"#\s*\[\s*repr\s*\([^)]*\b[iu]128\b")),
    ((1, 89), "inferred array length [x; _]", regex_feature(r";\s*_\s*\]")),
    ((1, 95), "if-let guards on match arms", if_let_guards),
]


def scan(code):
    """[(minimum release, feature, offset)] for everything FEATURES finds in blanked code."""
    toks = tokens(code)
    return [(v, name, at) for v, name, find in FEATURES for at in find(code, toks)]


def scan_package(root):
    files = [root / f for f in SOURCE_FILES if (root / f).is_file()]
    for d in SOURCE_DIRS:
        files += sorted((root / d).rglob("*.rs")) if (root / d).is_dir() else []
    hits = []
    for path in files:
        code = blank_non_code(path.read_text(encoding="utf-8"))
        for v, name, at in scan(code):
            hits.append((v, name, f"{path.relative_to(root)}:{code.count(chr(10), 0, at) + 1}"))
    return hits


# ---------------------------------------------------------------------------------------------


def dependency_versions(metadata):
    """[(rust-version, name version)] of every package in the resolved graph but the root."""
    root = metadata["resolve"]["root"]
    nodes = {n["id"]: n for n in metadata["resolve"]["nodes"]}
    packages = {p["id"]: p for p in metadata["packages"]}
    seen, todo = set(), [root]
    while todo:
        pid = todo.pop()
        if pid in seen:
            continue
        seen.add(pid)
        todo += [d["pkg"] for d in nodes[pid]["deps"]]
    out = []
    for pid in seen - {root}:
        p = packages[pid]
        if p.get("rust_version"):
            out.append((version(p["rust_version"]), f"{p['name']} {p['version']}"))
    return out, len(seen) - 1


def clippy_items(lines):
    """[(stable since, item at file:line)] from clippy's JSON messages for incompatible_msrv."""
    out = []
    for line in lines:
        try:
            msg = json.loads(line)
        except json.JSONDecodeError:
            continue
        m = msg.get("message") if msg.get("reason") == "compiler-message" else None
        if not m or (m.get("code") or {}).get("code") != "clippy::incompatible_msrv":
            continue
        since = re.findall(r"since `([0-9.]+)`", m["message"])
        span = next((s for s in m["spans"] if s["is_primary"]), m["spans"][0] if m["spans"] else None)
        where = f"{span['file_name']}:{span['line_start']}" if span else "?"
        text = span["text"][0]["text"].strip() if span and span["text"] else ""
        if since:
            out.append((version(since[-1]), f"{where} `{text[:60]}`"))
    return out


def check(args):
    root = pathlib.Path(args.root).resolve()
    metadata = json.load(open(args.metadata))
    pkg = next(p for p in metadata["packages"] if p["id"] == metadata["resolve"]["root"])
    declared = version(pkg["rust_version"]) if pkg.get("rust_version") else None

    reasons = []  # (version, what, where)
    reasons.append((EDITION_FLOOR[pkg["edition"]], f"edition {pkg['edition']}", "Cargo.toml"))
    deps, count = dependency_versions(metadata)
    if deps:
        top = max(v for v, _ in deps)
        names = sorted(n for v, n in deps if v == top)
        reasons.append((top, f"dependency rust-version ({count} packages in the graph)", ", ".join(names)))
    for v, name, where in scan_package(root):
        reasons.append((v, f"language: {name}", where))
    items = clippy_items(open(args.clippy))
    for v, where in items:
        reasons.append((v, "std API (clippy incompatible_msrv)", where))

    minimum = max(v for v, _, _ in reasons)
    print(f"[msrv] derived from: edition {pkg['edition']}, {count} dependencies (Cargo.lock, host platform), "
          f"the sources' language features, {len(items)} std items newer than the edition (clippy)")
    grouped = {}
    for v, what, where in sorted(reasons, key=lambda r: (r[0], r[1]), reverse=True):
        grouped.setdefault((v, what), []).append(where)
    for (v, what), wheres in grouped.items():
        more = f" (+{len(wheres) - 3} more)" if len(wheres) > 3 else ""
        print(f"[msrv]   {show(v):>5}  {what}: {', '.join(wheres[:3])}{more}")

    failures = []
    if declared is None:
        failures.append(f"Cargo.toml has no rust-version; the derived minimum is {show(minimum)}")
    elif declared < minimum:
        failures.append(f"Cargo.toml says rust-version = \"{show(declared)}\" but the code needs {show(minimum)}")
    elif declared > minimum:
        print(f"[msrv] note: Cargo.toml's rust-version {show(declared)} is above the derived minimum {show(minimum)}")
    readme = (root / "README.md").read_text(encoding="utf-8")
    needs = re.search(r"Needs: Rust ([0-9.]+)\+", readme)
    if declared and (not needs or version(needs.group(1)) != declared):
        failures.append(f"README.md's \"Needs: Rust X+\" line does not say {show(declared)} "
                        f"(found: {needs.group(0) if needs else 'no such line'})")
    for f in failures:
        print(f"[msrv] FAILED: {f}")
    if not failures:
        print(f"[msrv] ok: rust-version {show(declared)} = the derived minimum {show(minimum)}"
              if declared == minimum else f"[msrv] ok: rust-version {show(declared)} >= {show(minimum)}")
    return 1 if failures else 0


# ---------------------------------------------------------------------------------------------

SELF_TEST = [
    # (snippet, features expected, in order of FEATURES' names)
    ("if let Some(x) = a && x > 1 { }", ["let chains"]),
    ("if x > 1\n    && let Some(y) = b\n{ }", ["let chains"]),
    ("} else if let Some(x) = a && let Ok(y) = x { }", ["let chains"]),
    ("while let Some(x) = it.next() && x != 0 { }", ["let chains"]),
    ("if let Some(x) = a.iter().find(|p| p.a && p.b) { }", []),
    ("while let Some(x) = stack.pop() { }", []),
    ("if a && b || c { }", []),
    ("let Some(x) = y else { return };", []),
    ("let v = if a && b { 1 } else { 2 };", []),
    ("match x { Some(y) if y > 0 && y < 9 => {} _ => {} }", []),
    ("match x { Some(y) if let Ok(z) = f(y) => {} _ => {} }", ["if-let guards on match arms"]),
    ("// if let Some(x) = a && b {\n", []),
    ('let s = "if let Some(x) = a && b {";', []),
    ("let s = r#\"if let a = b && c {\"#;", []),
    ("let c = '{'; if let Some(x) = a { }", []),
    ("fn f<'a>(x: &'a str) { if let Some(c) = x.chars().next() && c == '\\'' { } }", ["let chains"]),
    ("#[cfg(false)]\nfn f() {}", ["cfg(true) / cfg(false)"]),
    ("#[cfg(all(test, not(true)))]\nfn f() {}", ["cfg(true) / cfg(false)"]),
    ("#[cfg(test)]\nfn f() { let t = true; }", []),
    ("if cfg!(false) { }", ["cfg(true) / cfg(false)"]),
    ("unsafe { asm!(\"jmp {}\", label { f() }) }", ["asm goto (label operands)"]),
    ("#[unsafe(naked)]\nextern \"C\" fn f() {}", ["naked functions"]),
    ("#[repr(u128)]\nenum E { A }", ["#[repr(u128)] / #[repr(i128)]"]),
    ("#[repr(u8)]\nenum E { A }", []),
    ("let a: [u8; 4] = [0; _];", ["inferred array length [x; _]"]),
    ("let a = [0u8; 4]; let _ = a;", []),
    ("trait T { fn f(&self) -> impl Sized + use<Self>; }", ["precise capturing (use<..>) in a trait"]),
    ("fn f<'a>(x: &'a u8) -> impl Sized + use<> { 1 }", []),
    ("#[target_feature(enable = \"avx2\")]\nfn f() {}", ["#[target_feature] on a safe function"]),
    ("#[target_feature(enable = \"avx2\")]\nunsafe fn f() {}", []),
]


def self_test():
    bad = 0
    for snippet, expected in SELF_TEST:
        found = [name for _, name, _ in scan(blank_non_code(snippet))]
        if sorted(found) != sorted(expected):
            bad += 1
            print(f"[msrv] self-test FAILED on {snippet!r}: found {found}, expected {expected}")
    print(f"[msrv] self-test: {len(SELF_TEST) - bad} of {len(SELF_TEST)} snippets scanned as expected")
    return 1 if bad else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--self-test", action="store_true", help="check the source scanner on snippets and exit")
    ap.add_argument("--metadata", help="`cargo metadata --format-version 1 --filter-platform HOST` output")
    ap.add_argument("--clippy", help="`cargo clippy --message-format=json` output, MSRV set to the edition's")
    ap.add_argument("--root", default=".", help="the package's folder (sources and README.md)")
    args = ap.parse_args()
    if args.self_test:
        return self_test()
    if not (args.metadata and args.clippy):
        ap.error("--metadata and --clippy are required (tools/check-msrv.sh passes them)")
    return check(args)


if __name__ == "__main__":
    sys.exit(main())
