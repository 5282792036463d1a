#!/usr/bin/env python3
"""Denoised path-traced frames of a camera path for `pbgi report
--camera-path PATH.json --denoised OUT/frames.csv`: Mitsuba 3 + Intel OIDN,
each frame's sensor moved to the path's pose, with a new seed per frame and
with the same seed for every frame.

Run it with the venv scripts/denoised.sh makes (mitsuba, drjit, pyoidn):

    target/denoise-venv/bin/python scripts/flicker-denoised.py SCENE.xml \
        PATH.json --spp 16,256 --out report/flicker/denoised

It writes OUT/mitsuba-{new,same}-SPP-FFFF.exr and OUT/frames.csv,
`label,spp,seconds,image`: seconds per frame (the scene loaded once, its
sensor moved per frame: render and denoise), the image a pattern with {}
for the frame number. A pose's "fov" is not passed on: the file's field of
view holds for every frame.
"""

import argparse
import json
import os
import sys
import time

from denoised import denoise, load, write, write_csv, mi, dr  # noqa: E402  (the variant is set there)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("xml")
    ap.add_argument("path")
    ap.add_argument("--spp", default="16,256")
    ap.add_argument("--bounces", type=int, default=1)
    ap.add_argument("--out", default="report/flicker/denoised")
    a = ap.parse_args()
    with open(a.path) as f:
        frames = json.load(f)["frames"]
    if any("fov" in p for p in frames):
        sys.exit(f"{a.path}: a pose's fov is not passed to Mitsuba here; leave it out")
    os.makedirs(a.out, exist_ok=True)
    scene = load(a.xml, a.bounces)
    sensor = scene.sensors()[0]
    params = mi.traverse(scene)
    # The sensor's parameters: the only object with a field of view.
    key = next(k for k in params.keys() if k.endswith(".x_fov"))[: -len("x_fov")] + "to_world"
    up0 = sensor.world_transform() @ mi.ScalarVector3f(0, 1, 0)
    mi.render(scene, spp=4, seed=1)  # the JIT and OIDN warm up
    denoise(mi.TensorXf(mi.render(scene, spp=4, seed=1)).numpy()[..., :3])
    rows = []
    for spp in [int(s) for s in a.spp.split(",")]:
        for policy in ("new", "same"):
            t = time.perf_counter()
            for k, pose in enumerate(frames):
                up = pose.get("up", list(up0))
                params[key] = mi.ScalarTransform4f().look_at(
                    origin=pose["origin"], target=pose["target"], up=up)
                params.update()
                seed = 1000 + k if policy == "new" else 1000
                img = mi.render(scene, spp=spp, seed=seed)
                dr.eval(img)
                out = denoise(img.numpy()[..., :3])
                write(os.path.join(a.out, f"mitsuba-{policy}-{spp}-{k:04}.exr"), out)
            s = (time.perf_counter() - t) / len(frames)
            label = f"Mitsuba 3 + OIDN, {policy} seed per frame" if policy == "new" else \
                "Mitsuba 3 + OIDN, the same seed each frame"
            rows.append((label, spp, s, f"mitsuba-{policy}-{spp}-{{}}.exr"))
            print(f"{label}, {spp} spp: {s:.3f} s per frame", flush=True)
    csv = os.path.join(a.out, "frames.csv")
    write_csv(csv, rows)
    print(f"wrote {csv}")


if __name__ == "__main__":
    sys.exit(main())
