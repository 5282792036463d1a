#!/usr/bin/env python3
"""The path tracer against Mitsuba 3 on a textured Mitsuba scene.

Renders tests/data/textured-box/textured-box.xml (a bitmap back wall, a
tiled checker floor through `to_uv`, a `mask` cut-out card) with Mitsuba 3
(variant llvm_ad_rgb, path, max_depth 3 = one bounce, box filter) and with
`pbgi reference --bounces 1` from the same XML, each at high spp, and prints
the bias and relative RMSE of pbgi's image against Mitsuba's (`pbgi compare`,
which takes the reference's own noise out). The same image against itself
with another seed shows the noise floor.

Install (once): pip install mitsuba==3.9.1; apt-get install -y libllvm19
Usage: scripts/mitsuba-textured.py [--spp 4096] [--pbgi-spp 2048]
           [--pbgi target/release/pbgi] [--out DIR]
"""

import argparse
import os
import re
import subprocess
import sys

import mitsuba as mi

mi.set_variant("llvm_ad_rgb")

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "tests", "data", "textured-box", "textured-box.xml")


def compare(pbgi, image, *references):
    out = subprocess.run(
        [pbgi, "compare", image, *references, "--scene", SCENE],
        check=True, capture_output=True, text=True,
    ).stdout
    m = re.search(r"relative RMSE ([0-9.]+), bias ([+-][0-9.]+)", out)
    if not m:
        sys.exit(f"cannot read pbgi compare's output: {out}")
    return 100 * float(m.group(1)), 100 * float(m.group(2))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spp", type=int, default=4096, help="Mitsuba's samples per pixel")
    ap.add_argument("--pbgi-spp", type=int, default=2048, help="pbgi reference's paths per pixel")
    ap.add_argument("--pbgi", default=os.path.join(ROOT, "target", "release", "pbgi"))
    ap.add_argument("--out", default="/tmp/pbgi-mitsuba-textured")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    scene = mi.load_file(SCENE, max_depth=3)
    mitsuba = []
    for seed in (1, 2):
        path = os.path.join(a.out, f"mitsuba-{seed}.exr")
        mi.Bitmap(mi.render(scene, spp=a.spp, seed=seed)).write(path)
        mitsuba.append(path)
    pbgi = os.path.join(a.out, "pbgi.exr")
    subprocess.run(
        [a.pbgi, "reference", SCENE, "--spp", str(a.pbgi_spp), "--bounces", "1", "-o", pbgi],
        check=True, capture_output=True,
    )
    side = os.path.join(a.out, "side-by-side.png")
    subprocess.run(
        [a.pbgi, "compare", pbgi, *mitsuba, "--scene", SCENE, "--side-by-side", side],
        check=True, capture_output=True,
    )
    rmse, bias = compare(a.pbgi, pbgi, *mitsuba)
    noise, floor = compare(a.pbgi, mitsuba[0], mitsuba[1])
    print(f"| image | against | relative RMSE | bias |")
    print(f"| --- | --- | --- | --- |")
    print(f"| pbgi reference, {a.pbgi_spp} spp | Mitsuba 3, 2 × {a.spp} spp | {rmse:.2f} % | {bias:+.2f} % |")
    print(f"| Mitsuba, seed 1 | Mitsuba, seed 2 | {noise:.2f} % | {floor:+.2f} % |")
    print(f"side by side: {side}")


if __name__ == "__main__":
    main()
