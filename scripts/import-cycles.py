#!/usr/bin/env python3
"""Checks that the modules under src/ import each other without cycles.

A file's imports are its `use crate::…`, `use super::…` and `use self::…`
paths (and `crate::…` paths written inline in code); each is resolved to the
file that defines the module it names. Re-exports (`pub use`) and `mod`
lines are declarations of a folder's interface, not imports, and are left
out; so are comments and a file's `#[cfg(test)] mod tests`.
Exits 1 and prints each cycle if there is one.
"""
import os
import re
import sys

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src")


def module_of(path):
    rel = os.path.relpath(path, ROOT)[:-3].split(os.sep)
    if rel[-1] in ("mod", "lib"):
        rel = rel[:-1]
    if rel and rel[0] == "bin":
        return None
    return tuple(rel)


files = {}
for dirpath, _, names in os.walk(ROOT):
    for n in names:
        if n.endswith(".rs"):
            p = os.path.join(dirpath, n)
            m = module_of(p)
            if m is not None:
                files[m] = p


def resolve(base, parts):
    """The longest prefix of base + parts that is a module file."""
    full = list(base) + parts
    for k in range(len(full), 0, -1):
        if tuple(full[:k]) in files:
            return tuple(full[:k])
    return None


def code_of(text):
    """The text without comments (doc links are not imports) and without a
    trailing `#[cfg(test)] mod tests { … }`."""
    i = text.find("#[cfg(test)]\nmod tests {")
    text = text if i < 0 else text[:i]
    return re.sub(r"//[^\n]*", "", text)


edges = {m: set() for m in files}
for m, p in files.items():
    text = code_of(open(p, encoding="utf-8").read())
    # `use` statements (possibly spanning lines), not re-exports.
    for u in re.finditer(r"(?m)^\s*use\s+([^;]+);", text):
        path = u.group(1)
        prefix = path.split("{")[0].strip().rstrip(":")
        inner = path[len(path.split("{")[0]):].strip("{} \n")
        targets = [prefix] if not inner else [prefix + "::" + x.strip() for x in re.split(r",(?![^{]*})", inner) if x.strip()]
        for t in targets:
            segs = [s for s in t.split("::") if s]
            if not segs:
                continue
            if segs[0] == "crate":
                r = resolve((), segs[1:])
            elif segs[0] == "super":
                # `super` of a file module is its folder; of a folder's
                # `mod.rs`, the folder's parent.
                base = list(m)
                while segs and segs[0] == "super":
                    base = base[:-1]
                    segs = segs[1:]
                r = resolve(tuple(base), segs)
            elif segs[0] == "self":
                r = resolve(m, segs[1:])
            elif (m + (segs[0],)) in files:
                r = resolve(m, segs)
            else:
                r = None
            if r is not None and r != m:
                edges[m].add(r)
    for u in re.finditer(r"\bcrate::([a-z_][a-z0-9_]*(?:::[a-z_][a-z0-9_]*)*)", text):
        r = resolve((), u.group(1).split("::"))
        if r is not None and r != m:
            edges[m].add(r)

# Tarjan's strongly connected components.
index, low, stack, on, sccs = {}, {}, [], set(), []
counter = [0]


def strong(v):
    index[v] = low[v] = counter[0]
    counter[0] += 1
    stack.append(v)
    on.add(v)
    for w in edges[v]:
        if w not in index:
            strong(w)
            low[v] = min(low[v], low[w])
        elif w in on:
            low[v] = min(low[v], index[w])
    if low[v] == index[v]:
        comp = []
        while True:
            w = stack.pop()
            on.discard(w)
            comp.append(w)
            if w == v:
                break
        if len(comp) > 1:
            sccs.append(comp)


sys.setrecursionlimit(10000)
for v in sorted(edges):
    if v not in index:
        strong(v)

name = lambda m: "::".join(m) or "crate"
if sccs:
    for c in sccs:
        print("import cycle:", ", ".join(sorted(name(m) for m in c)))
        for m in sorted(c):
            print("   ", name(m), "->", ", ".join(sorted(name(t) for t in edges[m] if t in c)))
    sys.exit(1)
print(f"import-cycles: {len(files)} modules, no cycle")
