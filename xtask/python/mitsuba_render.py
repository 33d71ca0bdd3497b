"""Render a Mitsuba 3 scene for Lustre's references and tests.

Called by `cargo xtask reference` and by `tests/tests/mitsuba_equivalence.rs`;
it only needs the `mitsuba` and `numpy` packages (the `.mitsuba-venv`).

    python mitsuba_render.py --variant scalar_rgb (--scene SCENE.xml | --cornell-box)
        [--out IMAGE.exr] [--spp N] [--spp-per-pass N] [--seed S]
        [--width W --height H] [--max-depth D] [--load-only]

The image is the mean of ceil(spp / spp_per_pass) renders with seeds S, S+1,
... (an exact split for a box filter; with a Gaussian filter each pass is
normalised on its own); it is written as linear float32 RGB OpenEXR to a
temporary name and renamed. Progress goes to stderr; the last stdout line is
a JSON object with the settings, the Mitsuba version, the scene's load time,
the render time and the per-channel image mean.
"""

import argparse
import datetime
import json
import os
import sys
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variant", default="scalar_rgb")
    src = ap.add_mutually_exclusive_group(required=True)
    src.add_argument("--scene", help="Mitsuba 3 XML scene file")
    src.add_argument("--cornell-box", action="store_true", help="Mitsuba's own mi.cornell_box()")
    ap.add_argument("--out", help="output OpenEXR file")
    ap.add_argument("--spp", type=int, help="samples per pixel (default: the scene's)")
    ap.add_argument("--spp-per-pass", type=int, default=0, help="split the render into passes")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--width", type=int)
    ap.add_argument("--height", type=int)
    ap.add_argument("--max-depth", type=int, help="override the integrator's max_depth (--cornell-box only)")
    ap.add_argument("--load-only", action="store_true", help="load the scene, print what it holds, render nothing")
    args = ap.parse_args()

    import mitsuba as mi

    mi.set_variant(args.variant)

    if args.cornell_box:
        d = mi.cornell_box()
        film = d["sensor"]["film"]
        if args.width:
            film["width"] = args.width
        if args.height:
            film["height"] = args.height
        film["pixel_format"] = "rgb"
        film["component_format"] = "float32"
        if args.max_depth is not None:
            d["integrator"]["max_depth"] = args.max_depth
        if args.spp:
            d["sensor"]["sampler"]["sample_count"] = args.spp
        load_start = time.time()
        scene = mi.load_dict(d)
        load_seconds = time.time() - load_start
        source = "mi.cornell_box()"
    else:
        if args.width or args.height or args.max_depth is not None:
            ap.error("--width, --height and --max-depth apply to --cornell-box only (the XML holds them)")
        load_start = time.time()
        scene = mi.load_file(args.scene)
        load_seconds = time.time() - load_start
        source = args.scene

    sensor = scene.sensors()[0]
    film = sensor.film()
    size = [int(v) for v in film.size()]
    spp = args.spp or int(sensor.sampler().sample_count())
    integrator = scene.integrator()
    info = {
        "source": source,
        "variant": args.variant,
        "mitsuba_version": mi.__version__,
        "integrator": str(integrator).split("[")[0].strip(),
        "width": size[0],
        "height": size[1],
        "shapes": len(scene.shapes()),
        "emitters": len(scene.emitters()),
        "bsdfs": sorted({str(s.bsdf()).split("[")[0].strip() for s in scene.shapes() if s.bsdf() is not None}),
    }
    if args.load_only:
        print(json.dumps(info))
        return

    if not args.out:
        ap.error("--out is required unless --load-only")
    per_pass = args.spp_per_pass if args.spp_per_pass > 0 else spp
    passes = (spp + per_pass - 1) // per_pass
    import numpy as np

    total = None
    done = 0
    start = time.time()
    for i in range(passes):
        n = min(per_pass, spp - done)
        img = np.array(mi.render(scene, spp=n, seed=args.seed + i), dtype=np.float64)
        img = img[..., :3]
        total = img * n if total is None else total + img * n
        done += n
        elapsed = time.time() - start
        eta = elapsed / done * (spp - done)
        print(
            f"mitsuba: pass {i + 1}/{passes}: {done}/{spp} spp, {elapsed:.1f} s, about {eta:.0f} s left",
            file=sys.stderr,
            flush=True,
        )
    seconds = time.time() - start
    image = (total / done).astype(np.float32)
    if not np.all(np.isfinite(image)):
        raise SystemExit("mitsuba_render: the image holds NaN or infinite values")

    out = os.path.abspath(args.out)
    os.makedirs(os.path.dirname(out), exist_ok=True)
    tmp = f"{out}.tmp-{os.getpid()}.exr"
    try:
        mi.Bitmap(image, pixel_format=mi.Bitmap.PixelFormat.RGB).write(tmp)
        os.replace(tmp, out)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)

    info.update(
        {
            "out": out,
            "spp": done,
            "spp_per_pass": per_pass,
            "passes": passes,
            "seed": args.seed,
            "load_seconds": round(load_seconds, 3),
            "render_seconds": round(seconds, 3),
            "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "mean": [float(v) for v in image.reshape(-1, 3).mean(axis=0)],
        }
    )
    print(json.dumps(info))


if __name__ == "__main__":
    main()
