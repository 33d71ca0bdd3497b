"""Embree's half of the comparison that `cargo xtask bench embree` runs.

Usage: embree_bench.py <dir> [runs]

Reads what `cargo run --release -p lustre-geometry --example embree_compare`
wrote in <dir> (triangles.f32, <set>.rays.f32), builds an Embree scene of the
same triangles with embreex (`EmbreeScene` + `TriangleMesh`, not robust), and
traces every ray set `runs` times with `EmbreeScene.run(origins, directions,
output=1)`: the closest hit's primID, distance, barycentrics and geometric
normal of every ray. Only the `run` call is timed; the arrays are prepared
before, and the scene is committed (the BVH built) by a run on one ray first.

embreex's `run` calls `rtcIntersect1` once per ray, in order, on the calling
thread: tracing is single-threaded by construction. The process is pinned to
one CPU while embreex is imported and the scene built, so Embree's task
system (TBB) starts with one thread; the CPU affinity is restored before
tracing (the Rust side is not pinned either, and the machine may be shared).
The process's CPU time of each run is recorded beside its wall time: a ratio
above 1 would mean more than one thread worked.

Writes <set>.embree.t.f32 and <set>.embree.id.i32 (distance and primID; inf
and -1 for a miss) and embree.json (versions, settings, times in ns).
"""

import json
import os
import sys
import time


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    directory = sys.argv[1]
    runs = int(sys.argv[2]) if len(sys.argv) == 3 else 5
    if runs < 1:
        sys.exit("runs must be at least 1")
    # One CPU: the one this process runs on now.
    cpu = os.sched_getaffinity(0)
    pinned = min(cpu)
    os.sched_setaffinity(0, {pinned})

    import numpy as np
    from importlib.metadata import version
    from embreex import rtcore, rtcore_scene
    from embreex.mesh_construction import TriangleMesh

    triangles = np.fromfile(os.path.join(directory, "triangles.f32"), dtype="<f4")
    triangles = np.ascontiguousarray(triangles.reshape(-1, 3, 3))
    device = rtcore.EmbreeDevice()
    scene = rtcore_scene.EmbreeScene(device, robust=False)
    TriangleMesh(scene, triangles)
    build = time.perf_counter()
    first = scene.run(
        np.zeros((1, 3), dtype=np.float32), np.ones((1, 3), dtype=np.float32)
    )
    build_ms = (time.perf_counter() - build) * 1e3
    del first
    os.sched_setaffinity(0, cpu)
    sets = {}
    for name in ("coherent", "incoherent"):
        rays = np.fromfile(os.path.join(directory, f"{name}.rays.f32"), dtype="<f4")
        rays = rays.reshape(-1, 6)
        origins = np.ascontiguousarray(rays[:, :3])
        directions = np.ascontiguousarray(rays[:, 3:])
        wall, cpu_time = [], []
        for _ in range(runs):
            w0, c0 = time.perf_counter_ns(), time.process_time_ns()
            result = scene.run(origins, directions, output=1)
            c1, w1 = time.process_time_ns(), time.perf_counter_ns()
            wall.append(w1 - w0)
            cpu_time.append(c1 - c0)
        ids = result["primID"].astype("<i4")
        t = result["tfar"].astype("<f4")
        missed = ids == -1
        t[missed] = np.inf
        ids.tofile(os.path.join(directory, f"{name}.embree.id.i32"))
        t.tofile(os.path.join(directory, f"{name}.embree.t.f32"))
        # The same rays going nowhere near the scene: what one call costs
        # around Embree's traversal (the wrapper's loop, the ray set-up, the
        # root box test), to tell apart from the traversal itself.
        away = np.full_like(origins, 1e6)
        away_wall = []
        for _ in range(runs):
            w0 = time.perf_counter_ns()
            scene.run(away, directions * 0 + np.float32(1), output=1)
            away_wall.append(time.perf_counter_ns() - w0)
        sets[name] = {
            "rays": int(len(rays)),
            "hits": int((~missed).sum()),
            "wall_ns": wall,
            "cpu_ns": cpu_time,
            "miss_all_wall_ns": away_wall,
        }
        median = sorted(wall)[len(wall) // 2]
        print(
            f"embree {name}: {len(rays) / median * 1e3:.2f} M rays/s "
            f"(median of {runs}, CPU time / wall time {sum(cpu_time) / sum(wall):.2f})"
        )
    out = {
        "embreex": version("embreex"),
        "embree": repr(device).split(":", 1)[-1].strip(),
        "numpy": np.__version__,
        "python": sys.version.split()[0],
        "build_cpu": pinned,
        "triangles": int(len(triangles)),
        "runs": runs,
        "build_ms": build_ms,
        "sets": sets,
    }
    with open(os.path.join(directory, "embree.json"), "w") as f:
        json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
