#!/usr/bin/env python3
"""Mitsuba 3 on pbgi's Cornell box: wall time and relative RMSE at several spp.

Renders the Cornell box with Mitsuba 3's `path` integrator (variant
llvm_ad_rgb, all cores, max_depth 3 = direct light + one indirect bounce,
like `pbgi reference --bounces 1`, box pixel filter), writes one EXR per spp,
measures each against a pbgi reference with `pbgi compare`, and prints a
markdown table plus the time a fit error = c / sqrt(t) gives for 5, 3, 2 %.
See docs/mitsuba.md for the numbers on the 2-core machine.

Install (once):
    pip install mitsuba==3.9.1        # brings drjit 1.5.0
    apt-get install -y libllvm19      # the LLVM JIT behind the llvm_ad_* variants
    # only if Dr.Jit does not find it by itself:
    # export DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so

Usage:
    scripts/mitsuba-cornell.py REFERENCE.exr [--scene cbox.xml] [--pbgi PATH]
        [--spp 16,64,256,1024,4096] [--repeat 3] [--out DIR]
e.g.
    scripts/mitsuba-cornell.py /work/refs/ref-all7.exr \
        --scene /work/shared/scenes/cornell-box/cbox.xml \
        --pbgi target/release/pbgi --out /tmp/mitsuba

REFERENCE is `pbgi reference cornell-box --spp 8192 -o REFERENCE.exr` (all
light, 1 bounce, seed 7). --scene is the Mitsuba export of the built-in
`cornell-box` (cbox.xml + meshes/); without it the scene is Mitsuba's own
`mi.cornell_box()`, the same box, with a box filter. Times are wall-clock
seconds of `mi.render` alone (scene loaded, kernels compiled by a warm-up
render first); the warm-up, JIT included, is printed as well. With --repeat N
each spp is rendered N times (other seeds) and the fastest time is kept, the
error being the first render's. Dr.Jit keeps compiled kernels in
~/.drjit: run with HOME=$(mktemp -d) to time the warm-up with a cold cache.
Another busy process on the machine inflates the wall times: the CPU
seconds of the render's threads are printed beside them (about twice the
wall time on an idle 2-core machine), and the load average before and after.
"""

import argparse
import math
import os
import re
import subprocess
import sys
import time

import mitsuba as mi

mi.set_variant("llvm_ad_rgb")
import drjit as dr  # noqa: E402  (after the variant)


def load_scene(xml):
    """The Cornell box at 256x256, max_depth 3, box filter."""
    if xml:
        return mi.load_file(xml, max_depth=3, rfilter="box", resx=256, resy=256)
    d = mi.cornell_box()
    d["integrator"]["max_depth"] = 3
    d["sensor"]["film"]["rfilter"] = {"type": "box"}
    return mi.load_dict(d)


def render(scene, spp, seed):
    """One render; (image, wall seconds, CPU seconds of all threads)."""
    t, c = time.perf_counter(), time.process_time()
    img = mi.render(scene, spp=spp, seed=seed)
    dr.eval(img)
    dr.sync_thread()
    return img, time.perf_counter() - t, time.process_time() - c


def compare(pbgi, image, reference):
    """(relative RMSE, bias) from `pbgi compare`."""
    out = subprocess.run(
        [pbgi, "compare", image, reference, "--scene", "cornell-box"],
        check=True, capture_output=True, text=True,
    ).stdout
    m = re.search(r"relative RMSE ([0-9.]+), bias ([+-][0-9.]+)", out)
    if not m:
        sys.exit(f"cannot read pbgi compare's output: {out}")
    return float(m[1]), float(m[2])


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("reference", help="pbgi reference EXR (all light, 1 bounce)")
    ap.add_argument("--scene", help="cbox.xml (default: mi.cornell_box())")
    ap.add_argument("--pbgi", default="target/release/pbgi")
    ap.add_argument("--spp", default="16,64,256,1024,4096")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--out", default="mitsuba-out")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    spps = [int(s) for s in a.spp.split(",")]

    scene = load_scene(a.scene)
    _, first, _ = render(scene, 16, seed=0)  # JIT-compiles the kernels
    _, warm, _ = render(scene, 16, seed=1)
    print(f"Mitsuba {mi.__version__}, drjit {dr.__version__}, llvm_ad_rgb, "
          f"{dr.thread_count()} threads; warm-up at 16 spp: first render "
          f"{first:.2f} s (JIT and kernel cache included), second {warm:.2f} s; "
          f"load average {os.getloadavg()[0]:.2f}\n")

    rows = []
    print("| spp | seconds | CPU seconds | rel. RMSE | bias |")
    print("| ---: | ---: | ---: | ---: | ---: |")
    for i, spp in enumerate(spps):
        seconds = []
        for r in range(a.repeat):
            img, t, cpu = render(scene, spp, seed=1000 * (i + 1) + r)
            seconds.append((t, cpu))
            if r == 0:
                path = os.path.join(a.out, f"mitsuba-{spp}spp.exr")
                mi.Bitmap(img).write(path)
        rmse, bias = compare(a.pbgi, path, a.reference)
        t, cpu = min(seconds)
        rows.append((spp, t, rmse))
        print(f"| {spp} | {t:.3f} | {cpu:.3f} | {rmse:.4f} | {bias:+.4f} |", flush=True)

    print(f"\nload average {os.getloadavg()[0]:.2f}")
    # error = c / sqrt(t): least squares on log(error) = log(c) - log(t) / 2.
    c = math.exp(sum(math.log(e) + 0.5 * math.log(t) for _, t, e in rows) / len(rows))
    print(f"fit error = {c:.4f} / sqrt(seconds):",
          ", ".join(f"{100 * e:g} % in {(c / e) ** 2:.2f} s" for e in (0.05, 0.03, 0.02)))


if __name__ == "__main__":
    main()
