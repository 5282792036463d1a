#!/usr/bin/env python3
"""Denoised path tracing for `pbgi report --denoised`: Mitsuba 3 and pbgi's
own path tracer, each image through Intel OIDN, timed from scene file to
denoised image.

Run it through scripts/denoised.sh, which makes the venv (mitsuba, drjit,
pyoidn) and, with --report, runs `pbgi report` in the same go so that every
curve is timed in one run on one machine.

For each spp it writes OUT/mitsuba-SPP.exr and OUT/pbgi-SPP.exr (denoised)
and OUT/denoised.csv, `label,spp,seconds,image`, which `pbgi report
--denoised OUT/denoised.csv` measures against its reference beside the
point-based curves and the plain path tracer.

What is timed:
* Mitsuba 3 (llvm_ad_rgb, all cores): mi.load_file + mi.render + the
  denoise, the JIT warmed by a first render of the scene. max_depth is
  bounces + 2 (3: direct light and one bounce, as pbgi's default).
* pbgi's path tracer: the whole `pbgi reference --spp SPP` process (scene
  load included) + reading its EXR + the denoise.
* OIDN: its RT filter, hdr on, quality high, colour only (no albedo or
  normal images: neither renderer writes them here), on the CPU.
With --repeat N each point is rendered N times and the fastest kept (the
first image is the one measured). The load average is printed before and
after: another busy process inflates every time.
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
import pyoidn
import mitsuba as mi

mi.set_variant("llvm_ad_rgb")
import drjit as dr  # noqa: E402  (after the variant)


def load(xml, bounces, resolution=None):
    """The scene with max_depth = bounces + 2, a box pixel filter where the
    file takes it as a parameter (Mitsuba refuses unused ones), and the
    film `resolution` (w, h) where the file takes `$resx` and `$resy`."""
    params = {"max_depth": bounces + 2}
    with open(xml) as f:
        text = f.read()
    if 'name="rfilter"' in text:
        params["rfilter"] = "box"
    if resolution:
        if "$resx" not in text or "$resy" not in text:
            sys.exit(f"{xml}: --resolution needs a film sized by $resx and $resy")
        params["resx"], params["resy"] = resolution
    return mi.load_file(xml, **params)


def denoise(rgb):
    """OIDN's RT filter on a linear HDR image (H, W, 3), float32."""
    return pyoidn.denoise(np.ascontiguousarray(rgb, dtype=np.float32), hdr=True, quality="high")


def write(path, rgb):
    mi.Bitmap(np.ascontiguousarray(rgb, dtype=np.float32)).write(path)


def write_csv(path, rows):
    """The list `pbgi report --denoised` reads: `label,spp,seconds,image`."""
    with open(path, "w") as f:
        f.write("label,spp,seconds,image\n")
        for label, spp, s, name in rows:
            f.write(f'"{label}",{spp},{s:.6f},{name}\n')


def read(path):
    b = mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, srgb_gamma=False)
    return np.array(b)


def mitsuba_point(xml, bounces, spp, seed, resolution=None):
    """(denoised image, seconds): load, render, denoise."""
    t = time.perf_counter()
    scene = load(xml, bounces, resolution)
    img = mi.render(scene, spp=spp, seed=seed)
    dr.eval(img)
    dr.sync_thread()
    out = denoise(np.array(img)[..., :3])
    return out, time.perf_counter() - t


def pbgi_point(pbgi, scene, bounces, spp, seed, tmp, resolution=None):
    """(denoised image, seconds): the whole `pbgi reference` process, the
    read and the denoise."""
    path = os.path.join(tmp, f"pbgi-raw-{spp}-{seed}.exr")
    size = ["--resolution", "%dx%d" % resolution] if resolution else []
    t = time.perf_counter()
    subprocess.run(
        [pbgi, "reference", scene, "--spp", str(spp), "--seed", str(seed),
         "--bounces", str(bounces), "-o", path] + size,
        check=True, capture_output=True, text=True,
    )
    out = denoise(read(path))
    return out, time.perf_counter() - t


def best_of(repeat, render):
    """The first render's image, the fastest of `repeat` renders' times."""
    image, seconds = render(0)
    for r in range(1, repeat):
        seconds = min(seconds, render(r)[1])
    return image, seconds


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", help="pbgi's name of the scene (built-in name or file)")
    ap.add_argument("--xml", help="the Mitsuba XML of the same scene (default: SCENE itself)")
    ap.add_argument("--pbgi", default="target/release/pbgi")
    ap.add_argument("--spp", default="1,4,16,64,256",
                    help="paths per pixel along both curves (comma-separated)")
    ap.add_argument("--bounces", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--resolution", metavar="WxH",
                    help="image size (the Mitsuba file's $resx and $resy, pbgi's --resolution)")
    ap.add_argument("--out", default="report/denoised")
    ap.add_argument("--no-mitsuba", action="store_true")
    ap.add_argument("--no-pbgi", action="store_true")
    a = ap.parse_args()
    xml = a.xml or a.scene
    spps = [int(s) for s in a.spp.split(",")]
    res = tuple(int(x) for x in a.resolution.split("x")) if a.resolution else None
    os.makedirs(a.out, exist_ok=True)
    print(f"load average {os.getloadavg()[0]:.2f}; Mitsuba {mi.__version__}, drjit "
          f"{dr.__version__}, {dr.thread_count()} threads; OIDN through pyoidn "
          f"{getattr(pyoidn, '__version__', '')}", flush=True)

    rows = []
    if not a.no_mitsuba:
        t = time.perf_counter()
        mitsuba_point(xml, a.bounces, 4, 1, res)  # the JIT and OIDN warm up
        print(f"Mitsuba + OIDN warm-up: {time.perf_counter() - t:.2f} s", flush=True)
        for i, spp in enumerate(spps):
            img, s = best_of(a.repeat, lambda r: mitsuba_point(xml, a.bounces, spp, 1000 * (i + 1) + r, res))
            name = f"mitsuba-{spp}.exr"
            write(os.path.join(a.out, name), img)
            rows.append(("Mitsuba 3 + OIDN", spp, s, name))
            print(f"Mitsuba 3 + OIDN, {spp} spp: {s:.3f} s", flush=True)
    if not a.no_pbgi:
        with tempfile.TemporaryDirectory() as tmp:
            for i, spp in enumerate(spps):
                img, s = best_of(
                    a.repeat, lambda r: pbgi_point(a.pbgi, a.scene, a.bounces, spp, 2000 * (i + 1) + r, tmp, res))
                name = f"pbgi-{spp}.exr"
                write(os.path.join(a.out, name), img)
                rows.append(("pbgi path tracer + OIDN", spp, s, name))
                print(f"pbgi path tracer + OIDN, {spp} spp: {s:.3f} s", flush=True)
    csv = os.path.join(a.out, "denoised.csv")
    write_csv(csv, rows)
    print(f"load average {os.getloadavg()[0]:.2f}; wrote {csv}")


if __name__ == "__main__":
    sys.exit(main())
