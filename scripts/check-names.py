#!/usr/bin/env python3
"""One name for each thing (docs/design.md §1): no folder of src/ or tests/
holds two modules whose names differ only by a short suffix (`bake` and
`baked`, `gather` and `gathers`), which say the same thing twice. A module
is a `.rs` file or a folder of them."""
import os
import sys

ROOTS = ["src", "tests"]


def modules(folder):
    out = set()
    for entry in os.listdir(folder):
        path = os.path.join(folder, entry)
        if entry.endswith(".rs"):
            out.add(entry[:-3])
        elif os.path.isdir(path) and any(f.endswith(".rs") for f in os.listdir(path)):
            out.add(entry)
    return out


def main():
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    problems = []
    folders = 0
    for top in ROOTS:
        for folder, _, _ in os.walk(os.path.join(root, top)):
            folders += 1
            names = sorted(modules(folder))
            for a in names:
                for b in names:
                    rest = b[len(a):]
                    if b != a and b.startswith(a) and len(rest) <= 3 and rest.isalpha():
                        rel = os.path.relpath(folder, root)
                        problems.append(f"{rel}: `{a}` and `{b}` differ only by a suffix")
    for p in problems:
        print(p)
    print(f"check-names: {folders} folders, {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
