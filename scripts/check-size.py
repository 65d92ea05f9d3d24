#!/usr/bin/env python3
"""No source file over 1,000 lines and no function over 150 lines in
crates/*/src (CONTRIBUTING: files that are one thing, functions that fit on
a screen or two). Prints every offender as `path:line: what` and exits 1
when there is one; `--list N` prints every function longer than N lines
instead (for finding the next split).

Functions are found by their `fn` line and measured to the brace that
closes their body; strings, chars and comments are skipped when counting
braces. Generated code (a file whose first line says `@generated`) is
exempt. `scripts/size-exceptions.txt` lists the offenders still to be split
(`path` for a file, `path:fn` for a function), one a line: they are
reported but do not fail; an offender not listed fails, and so does a
listed one that is no longer over (take it off the list)."""
import re
import sys
from pathlib import Path

MAX_FILE = 1000
MAX_FN = 150
ROOT = Path(__file__).resolve().parent.parent
FN = re.compile(r"^\s*(pub(\([^)]*\))?\s+)?(const\s+)?(async\s+)?(unsafe\s+)?(extern\s+\"[^\"]*\"\s+)?fn\s+([A-Za-z_][A-Za-z0-9_]*)")


def strip(text):
    """The text with strings, chars and comments blanked (newlines kept)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append("".join(ch if ch == "\n" else " " for ch in text[i:j]))
            i = j
        elif c == "r" and re.match(r'r#*"', text[i:i + 10]) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'r(#*)"', text[i:])
            close = '"' + m.group(1)
            j = text.find(close, i + len(m.group(0)))
            j = n if j < 0 else j + len(close)
            out.append("".join(ch if ch == "\n" else " " for ch in text[i:j]))
            i = j
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            j += 1
            out.append("".join(ch if ch == "\n" else " " for ch in text[i:j]))
            i = j
        elif c == "'":
            m = re.match(r"'(\\.|\\u\{[0-9a-fA-F]+\}|\\x[0-9a-fA-F]{2}|[^\\'])'", text[i:])
            if m:
                out.append(" " * len(m.group(0)))
                i += len(m.group(0))
            else:  # a lifetime
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def functions(path):
    """(line, name, length) of every function with a body in the file."""
    lines = strip(path.read_text(encoding="utf-8")).split("\n")
    found = []
    for k, line in enumerate(lines):
        m = FN.match(line)
        if not m:
            continue
        depth, start, paren = 0, None, 0
        for j in range(k, len(lines)):
            for ch in lines[j]:
                if ch in "([":
                    paren += 1
                elif ch in ")]":
                    paren -= 1
                elif ch == "{":
                    depth += 1
                    start = j if start is None else start
                elif ch == "}":
                    depth -= 1
                elif ch == ";" and start is None and depth == 0 and paren == 0:
                    break  # a declaration without a body
            else:
                if start is not None and depth == 0:
                    found.append((k + 1, m.group(7), j - k + 1))
                    break
                continue
            break
    return found


def main():
    list_over = None
    if len(sys.argv) == 3 and sys.argv[1] == "--list":
        list_over = int(sys.argv[2])
    bad = []
    keys = []
    exceptions_file = ROOT / "scripts" / "size-exceptions.txt"
    exceptions = set()
    if exceptions_file.exists():
        for line in exceptions_file.read_text(encoding="utf-8").splitlines():
            line = line.split("#", 1)[0].strip()
            if line:
                exceptions.add(line)
    for path in sorted(ROOT.glob("crates/*/src/**/*.rs")):
        text = path.read_text(encoding="utf-8")
        if text.startswith("// @generated"):
            continue
        rel = path.relative_to(ROOT)
        n = text.count("\n")
        if list_over is None and n > MAX_FILE:
            bad.append(f"{rel}:1: {n} lines (at most {MAX_FILE} per source file)")
            keys.append(str(rel))
        for line, name, length in functions(path):
            if list_over is not None and length > list_over:
                bad.append(f"{length:5d} {rel}:{line}: fn {name}")
            elif list_over is None and length > MAX_FN:
                bad.append(f"{rel}:{line}: fn {name} is {length} lines (at most {MAX_FN})")
                keys.append(f"{rel}:{name}")
    if list_over is not None:
        for b in sorted(bad, reverse=True):
            print(b)
        return 0
    failing = [b for b, k in zip(bad, keys) if k not in exceptions]
    listed = [b for b, k in zip(bad, keys) if k in exceptions]
    stale = sorted(exceptions - set(keys))
    for b in listed:
        print(f"{b} [listed in size-exceptions.txt: still to split]")
    for b in failing:
        print(b)
    for k in stale:
        print(f"scripts/size-exceptions.txt: {k} is within the limits now: take it off the list")
    if failing or stale:
        print(f"check-size: {len(failing)} over the limits, {len(stale)} stale exceptions", file=sys.stderr)
        return 1
    print(f"check-size: every source file and function within its limit ({len(listed)} listed exceptions)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
