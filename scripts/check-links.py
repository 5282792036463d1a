#!/usr/bin/env python3
"""Check every relative markdown link `](path)` / `](path#anchor)` in README.md and
docs/**/*.md: the file must exist relative to the linking file, and an anchor
into a .md file must match one of its headings (GitHub slugs).
Also checks that every path under the docs folder (and the lab's benchmarks page)
named in plain text in a tracked file, comments included, exists. Exits 1 on a
problem."""
import os, re, subprocess, sys, unicodedata

root = sys.argv[1] if len(sys.argv) > 1 else "."
os.chdir(root)
files = ["README.md"] + sorted(
    os.path.join(d, f) for d, _, fs in os.walk("docs") for f in fs if f.endswith(".md"))

def slug(h):
    h = h.strip().lower()
    h = re.sub(r"[`*_]", "", h)  # formatting
    h = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", h)
    out = []
    for ch in h:
        cat = unicodedata.category(ch)
        if ch in "-_ " or cat[0] in "LN":
            out.append("-" if ch == " " else ch)
    return "".join(out)

def anchors(path):
    res, seen, fence = set(), {}, False
    for line in open(path, encoding="utf-8"):
        if line.lstrip().startswith("```"):
            fence = not fence
            continue
        if fence:
            continue
        m = re.match(r"^(#{1,6})\s+(.*?)\s*#*\s*$", line)
        if m:
            s = slug(m.group(2))
            n = seen.get(s, 0)
            seen[s] = n + 1
            res.add(s if n == 0 else f"{s}-{n}")
    return res

link_re = re.compile(r"\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
bad = 0; count = 0
for f in files:
    fence = False
    for no, line in enumerate(open(f, encoding="utf-8"), 1):
        if line.lstrip().startswith("```"):
            fence = not fence
            continue
        if fence:
            continue
        for m in link_re.finditer(line):
            target = m.group(1)
            if re.match(r"^[a-z]+:", target):
                continue
            count += 1
            path, _, anchor = target.partition("#")
            full = os.path.normpath(os.path.join(os.path.dirname(f), path)) if path else f
            if not os.path.exists(full):
                print(f"{f}:{no}: missing {target} (-> {full})"); bad += 1; continue
            if anchor and full.endswith(".md") and anchor not in anchors(full):
                print(f"{f}:{no}: no anchor #{anchor} in {full}"); bad += 1
# textual repo-root paths anywhere in tracked files
tracked = subprocess.run(["git", "ls-files"], capture_output=True, text=True).stdout.split()
txt_re = re.compile(r"(?<![\w/.])((?:docs/[\w.,/*-]*[\w*])|BENCHMARKS\.md)")
tcount = 0
for f in tracked:
    if f.startswith(("fuzz/corpus", "fuzz/regressions", "tests/data")) or f.endswith((".png", ".exr", ".jsonl", ".pbgi", ".csv", ".svg", ".lock", ".glb", ".bin", ".jpg")):
        continue
    try:
        lines = open(f, encoding="utf-8").read().split("\n")
    except (UnicodeDecodeError, IsADirectoryError):
        continue
    for no, line in enumerate(lines, 1):
        for m in txt_re.finditer(line):
            p = m.group(1).rstrip(".,")
            # a docs/ mention inside a relative link is handled above
            if "{" in p or re.search(r"/[A-Z]+(/|$)", p):
                continue  # a placeholder such as docs/SCENE
            if "*" in p:
                import glob
                tcount += 1
                if not glob.glob(p):
                    print(f"{f}:{no}: textual glob {p} matches nothing"); bad += 1
                continue
            tcount += 1
            if not os.path.exists(p):
                # allow a path relative to the file itself
                rel = os.path.normpath(os.path.join(os.path.dirname(f), p))
                if os.path.exists(rel):
                    continue
                print(f"{f}:{no}: textual path {p} does not exist"); bad += 1
print(f"{count} relative links and {tcount} textual paths checked, {bad} problem(s)")
sys.exit(1 if bad else 0)
