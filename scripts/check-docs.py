#!/usr/bin/env python3
"""Check the documentation against the binary.

    INCAL=target/release/incal python3 scripts/check-docs.py [FILE.md ...]

Default files: README.md, CONTRIBUTING.md and docs/src/*.md.

1. Links: every relative Markdown link `[text](path)` or `[text](path#anchor)`
   must name a file that exists, and an anchor must be a heading id (as
   mdBook makes it) or an `<a id="...">` of that file.
2. Examples: every ```sh block is run, line by line, with `incal` replaced by
   $INCAL, in one temporary directory per Markdown file (so a chapter's
   blocks build on each other). Lines that start with `cargo`, `cd`,
   `scripts/`, `mdbook`, `INCAL_UPDATE_SCHEMA`, `INCAL_FUZZ_TARGET` or contain a `[`-bracketed
   synopsis are skipped. A ```text block right after a ```sh block must
   appear in what that block printed: every line, except `...` lines and
   blank lines, must be a line of the output (trailing spaces ignored).
   A ```text block whose lines start with `$ incal` is a transcript: each
   command is run and the lines up to the next `$` must be in its output.

3. Python sessions: the ```pycon blocks of a file (`>>>` prompts, as a
   notebook or the interpreter shows them) are run together, in order, by
   `python -m doctest` (ELLIPSIS, NORMALIZE_WHITESPACE) with the Python
   of $INCAL_PYTHON (one with the incal package installed; the tests use
   target/py-venv/bin/python), in that file's temporary directory, with
   INCAL_BIN set to $INCAL. A file with such blocks and no $INCAL_PYTHON
   is a problem (say where the package is), never a silent skip.

Exit 0 when all is well; otherwise every problem is printed and exit 1.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
INCAL = os.environ.get("INCAL", os.path.join(ROOT, "target", "release", "incal"))
PYTHON = os.environ.get("INCAL_PYTHON")
SKIP = ("cargo", "cd ", "scripts/", "mdbook", "INCAL_UPDATE_SCHEMA", "INCAL_FUZZ_TARGET", "INCAL=", "#")

problems = []


def blocks(text):
    """(info, body, line) of every fenced block, in order."""
    out = []
    lines = text.split("\n")
    i = 0
    while i < len(lines):
        m = re.match(r"^(\s*)```(\S*)", lines[i])
        if m:
            indent, info = m.group(1), m.group(2)
            start = i
            body = []
            i += 1
            while i < len(lines) and not lines[i].strip().startswith("```"):
                body.append(lines[i][len(indent):] if lines[i].startswith(indent) else lines[i])
                i += 1
            out.append((info, body, start + 1))
        i += 1
    return out


def anchors(path):
    """Heading ids as mdBook makes them, and explicit <a id="...">."""
    ids = set()
    fence = False
    for l in open(path, encoding="utf-8").read().split("\n"):
        if l.strip().startswith("```"):
            fence = not fence
            continue
        if fence:
            continue
        m = re.match(r"^#{1,6}\s+(.*)$", l)
        if m:
            s = re.sub(r"\[([^]]*)\]\([^)]*\)", r"\1", m.group(1)).replace("`", "").lower()
            ids.add("".join(c for c in s.replace(" ", "-") if c.isalnum() or c in "-_"))
        ids.update(re.findall(r'<a id="([^"]+)"', l))
    return ids


def check_links(path, text):
    base = os.path.dirname(path)
    stripped = re.sub(r"```.*?```", "", text, flags=re.S)
    stripped = re.sub(r"`[^`\n]*`", "", stripped)
    for m in re.finditer(r"\]\(([^)\s]+)\)", stripped):
        target = m.group(1)
        if re.match(r"^[a-z]+:", target) or target.startswith("#"):
            continue
        file, _, anchor = target.partition("#")
        full = os.path.normpath(os.path.join(base, file)) if file else path
        if not os.path.exists(full):
            problems.append(f"{os.path.relpath(path, ROOT)}: link to missing file {target}")
        elif anchor and full.endswith(".md") and anchor not in anchors(full):
            problems.append(f"{os.path.relpath(path, ROOT)}: link to missing anchor {target}")


def run(cmd, cwd):
    shell = cmd.replace("cargo run --release -p incal-cli -- ", "incal ")
    shell = re.sub(r"(^|[|;&(]\s*)incal\b", lambda m: m.group(1) + INCAL, shell)
    p = subprocess.run(["bash", "-c", shell], cwd=cwd, capture_output=True, text=True, timeout=600)
    return p.returncode, p.stdout + p.stderr


def expect(path, line, want, got, cmd):
    have = {l.rstrip() for l in got.split("\n")}
    for w in want:
        w = w.rstrip()
        if not w or w.strip() == "..." or w.strip().startswith("..."):
            continue
        if w not in have:
            problems.append(f"{os.path.relpath(path, ROOT)}:{line}: expected line not printed by `{cmd[:70]}`:\n    {w}")
            return


def joined(body):
    """Lines of a sh block with backslash continuations and heredocs joined."""
    cmds = []
    cur = ""
    heredoc = None
    for l in body:
        if heredoc is not None:
            cur += "\n" + l
            if l.strip() == heredoc:
                cmds.append(cur)
                cur, heredoc = "", None
            continue
        if cur:
            cur += "\n" + l
        else:
            cur = l
        m = re.search(r"<<-?'?(\w+)'?", l)
        if m:
            heredoc = m.group(1)
            continue
        if cur.endswith("\\"):
            continue
        if cur.strip():
            cmds.append(cur)
        cur = ""
    if cur.strip():
        cmds.append(cur)
    return cmds


def check_examples(path, text):
    tmp = tempfile.mkdtemp(prefix="incal-docs-")
    # Examples name the repository's fixtures as from its root.
    os.symlink(os.path.join(ROOT, "crates"), os.path.join(tmp, "crates"))
    try:
        bl = blocks(text)
        last = None
        for info, body, line in bl:
            if info == "sh":
                out = ""
                for cmd in joined(body):
                    c = cmd.strip()
                    first = c.split("\n")[0]
                    if first.startswith("cargo run --release -p incal-cli -- "):
                        pass
                    elif first.startswith(SKIP) or re.search(r"\s\[--?\w|\[-o|FILE\]|\bRESULT\.json\b|\bA\.json\b", first):
                        continue
                    c = re.sub(r"\s+#[^'\"\n]*$", "", c) if "<<" not in c else c
                    rc, o = run(c, tmp)
                    out += o
                    if rc != 0:
                        problems.append(f"{os.path.relpath(path, ROOT)}:{line}: exit {rc}: {first}\n    {o.strip()[:300]}")
                last = (out, line, " / ".join(x.split('\n')[0] for x in joined(body))[:70])
            elif info == "text":
                if body and body[0].startswith("$ incal"):
                    i = 0
                    while i < len(body):
                        if body[i].startswith("$ "):
                            cmd = re.sub(r"\s+#.*$", "", body[i][2:])
                            j = i + 1
                            while j < len(body) and not body[j].startswith("$ "):
                                j += 1
                            _, o = run(cmd, tmp)
                            expect(path, line, body[i + 1:j], o, cmd)
                            i = j
                        else:
                            i += 1
                elif last is not None:
                    expect(path, line, body, last[0], last[2])
                last = None
            else:
                last = None
        check_python(path, [(body, line) for info, body, line in bl if info == "pycon"], tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def check_python(path, sessions, tmp):
    """Run the file's ```pycon blocks as one doctest session in `tmp`."""
    if not sessions:
        return
    rel = os.path.relpath(path, ROOT)
    if not PYTHON:
        problems.append(f"{rel}:{sessions[0][1]}: pycon blocks need INCAL_PYTHON (a Python with the incal package)")
        return
    script = os.path.join(tmp, "session.txt")
    with open(script, "w", encoding="utf-8") as f:
        for body, line in sessions:
            f.write("\n".join(body) + "\n\n")
    env = dict(os.environ, INCAL_BIN=INCAL)
    p = subprocess.run(
        [PYTHON, "-W", "ignore", "-m", "doctest", "-o", "ELLIPSIS", "-o", "NORMALIZE_WHITESPACE", script],
        cwd=tmp, capture_output=True, text=True, timeout=900, env=env,
    )
    if p.returncode != 0:
        problems.append(f"{rel}:{sessions[0][1]}: the Python session failed:\n    " + (p.stdout + p.stderr).strip()[:2000])


def main():
    files = sys.argv[1:]
    if not files:
        files = [os.path.join(ROOT, "README.md"), os.path.join(ROOT, "CONTRIBUTING.md")]
        src = os.path.join(ROOT, "docs", "src")
        if os.path.isdir(src):
            files += sorted(os.path.join(src, f) for f in os.listdir(src) if f.endswith(".md"))
    if not os.access(INCAL, os.X_OK):
        sys.exit(f"check-docs: no incal binary at {INCAL} (set INCAL=...)")
    for f in files:
        if not os.path.exists(f):
            continue
        text = open(f, encoding="utf-8").read()
        check_links(f, text)
        check_examples(f, text)
        print(f"checked {os.path.relpath(f, ROOT)}", file=sys.stderr)
    for p in problems:
        print(p)
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
