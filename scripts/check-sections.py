#!/usr/bin/env python3
"""Quoted section names after a path (a docs page, or the lab's benchmarks page,
then a comma and "Section"; or a markdown link then ("Section")): the quoted
text must begin a heading or a bold lead of the target. Exits 1 on a miss."""
import os, re, subprocess, sys
os.chdir(sys.argv[1] if len(sys.argv) > 1 else ".")
tracked = subprocess.run(["git", "ls-files"], capture_output=True, text=True).stdout.split()
def norm(s):
    s = re.sub(r"[`*_]", "", s)
    s = re.sub(r"\s+", " ", s).strip().lower()
    return s.replace("’", "'")
leads_cache = {}
def leads(path):
    if path not in leads_cache:
        t = open(path, encoding="utf-8").read()
        out = [norm(m.group(1)) for m in re.finditer(r"^#{1,6}\s+(.*)$", t, re.M)]
        out += [norm(m.group(1)) for m in re.finditer(r"\*\*([^*]+)\*\*", t)]
        leads_cache[path] = out
    return leads_cache[path]
pat = re.compile(r"(?:\]\(([^)\s#]+\.md)(?:#[^)]*)?\)|(?<![\"\w/])((?:docs/[\w./-]+|BENCHMARKS)\.md|guide\.md|options\.md))`?\)?,?\s*\(?\s*\"([^\"]{3,90})\"")
bad = n = 0
for f in tracked:
    if not f.endswith((".md", ".rs", ".sh", ".py", ".toml")) and f != ".ci/run":
        continue
    lines = open(f, encoding="utf-8").read().split("\n")
    # strip comment leaders so a mention may wrap across comment lines
    text = " ".join(re.sub(r"^\s*(//[!/]?|#|>)\s?", "", l) for l in lines)
    for m in pat.finditer(text):
        path = m.group(1) or m.group(2)
        sec = norm(m.group(3))
        cand = [path, os.path.normpath(os.path.join(os.path.dirname(f), path))]
        tgt = next((c for c in cand if os.path.exists(c)), None)
        n += 1
        if tgt is None:
            print(f"{f}: {path} \"{m.group(3)}\": file missing"); bad += 1; continue
        if not any(l.startswith(sec) for l in leads(tgt)):
            print(f"{f}: {path} \"{m.group(3)}\": no heading or bold lead begins so in {tgt}"); bad += 1
print(f"{n} quoted section references checked, {bad} problem(s)")
sys.exit(1 if bad else 0)
