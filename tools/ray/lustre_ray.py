#!/usr/bin/env python3
"""Photon tracing and frame rendering for Lustre on Ray (https://www.ray.io).

Photon batches are independent given a light and a range of photon indices
(Stürzlinger & Bastos 1997, section 2.1), so `lustre trace --batch I/N` traces
the I-th of N batches of one run deterministically and `lustre merge` joins
the N files into the file of the whole run, byte for byte. This driver submits
the batches as Ray tasks, gathers the files and merges them; it can also render
a list of frames as tasks, each reading the same photon file
(`lustre render --photons-file`).

    python tools/ray/lustre_ray.py trace glosbox --photons 10000000 --batches 16 --out photons.lph
    python tools/ray/lustre_ray.py frames frames.json

`--address` joins a running Ray cluster (`ray start --head` on one machine,
`ray start --address=HEAD:6379` on the others); without it a local Ray
instance with `--workers` CPUs is started and stopped. On a cluster, the
`lustre` binary (`--lustre`) and the working directory (`--workdir`, where
the batch files and frames are written) must be at the same paths on every
node, for example on a shared file system.

`frames.json` lists the frames, each the arguments of one `lustre render`
after `render`:

    [["glosbox", "--photons-file", "photons.lph", "--out", "f0.exr"],
     ["glosbox", "--photons-file", "photons.lph", "--size", "320x240", "--out", "f1.exr"]]

Exit status 0 when every task and the merge succeeded; otherwise 1, with the
failing task's command and output on stderr, and no merged file.
"""

import argparse
import json
import logging
import os
import shutil
import subprocess
import sys
import tempfile
import time


def parse_args(argv):
    parser = argparse.ArgumentParser(
        prog="lustre_ray.py",
        description="Trace photon batches and render frames of Lustre as Ray tasks.",
    )
    parser.add_argument(
        "--lustre",
        default=None,
        help="the lustre binary (default: target/release/lustre, else target/debug/lustre, "
        "beside this script's repository)",
    )
    parser.add_argument(
        "--address",
        default=None,
        help="address of a running Ray cluster (default: start a local instance)",
    )
    parser.add_argument(
        "--workers",
        type=int,
        default=os.cpu_count() or 1,
        help="CPUs of the local Ray instance: tasks that run at once (default: all cores)",
    )
    parser.add_argument(
        "--threads-per-task",
        type=int,
        default=None,
        help="photon-tracing threads of each task (default: cores / workers, at least 1)",
    )
    parser.add_argument(
        "--workdir",
        default=None,
        help="directory of the batch files (default: a temporary directory beside --out)",
    )
    sub = parser.add_subparsers(dest="command", required=True)

    trace = sub.add_parser("trace", help="trace a run's photons in batches and merge them")
    trace.add_argument("scene", help="a built-in scene or an OBJ file, as `lustre trace` takes")
    trace.add_argument("--photons", type=int, default=1_000_000, help="photons of the whole run")
    trace.add_argument("--batches", type=int, required=True, help="number of batches N")
    trace.add_argument("--out", required=True, help="the merged photon file")
    trace.add_argument("--seed", type=int, default=None, help="passed to `lustre trace`")
    trace.add_argument("--emission", default=None, help="passed to `lustre trace`")
    trace.add_argument("--area-lights", default=None, help="passed to `lustre trace`")
    trace.add_argument("--keep-batches", action="store_true", help="keep the batch files")

    frames = sub.add_parser("frames", help="render the frames listed in a JSON file")
    frames.add_argument("list", help="JSON list of `lustre render` argument lists")

    args = parser.parse_args(argv)
    if args.workers < 1:
        parser.error("--workers must be at least 1")
    if args.command == "trace":
        if args.batches < 1:
            parser.error("--batches must be at least 1")
        if args.photons < 1:
            parser.error("--photons must be at least 1")
    if args.threads_per_task is None:
        args.threads_per_task = max(1, (os.cpu_count() or 1) // args.workers)
    if args.threads_per_task < 1:
        parser.error("--threads-per-task must be at least 1")
    return args


def find_lustre(given):
    """The lustre binary as an absolute path, or an error naming what was tried."""
    if given:
        candidates = [given]
    else:
        root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
        candidates = [
            os.path.join(root, "target", "release", "lustre"),
            os.path.join(root, "target", "debug", "lustre"),
        ]
    for c in candidates:
        if os.path.isfile(c) and os.access(c, os.X_OK):
            return os.path.abspath(c)
    sys.exit(
        "lustre_ray.py: no lustre binary at "
        + " or ".join(candidates)
        + "; build it with `cargo build --release` or pass --lustre"
    )


# The driver's working directory: tasks resolve relative paths from it.
CWD = os.getcwd()


def run_lustre(lustre, arguments, threads):
    """Runs lustre with `arguments` in the driver's directory; returns (seconds, exit status, output)."""
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
    start = time.monotonic()
    done = subprocess.run(
        [lustre] + arguments,
        env=env,
        cwd=CWD,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    return time.monotonic() - start, done.returncode, done.stdout + done.stderr


def fail(what, arguments, output):
    sys.stderr.write(f"lustre_ray.py: {what}: lustre {' '.join(arguments)}\n{output}\n")
    sys.exit(1)


def trace(args, ray, lustre):
    out = os.path.abspath(args.out)
    workdir = args.workdir or tempfile.mkdtemp(prefix=".lustre-ray-", dir=os.path.dirname(out))
    os.makedirs(workdir, exist_ok=True)
    options = []
    for flag, value in (
        ("--seed", args.seed),
        ("--emission", args.emission),
        ("--area-lights", args.area_lights),
    ):
        if value is not None:
            options += [flag, str(value)]

    @ray.remote(num_cpus=1)
    def batch(index):
        path = os.path.join(workdir, f"batch-{index:05d}-of-{args.batches}.lph")
        arguments = ["trace", args.scene, "--photons", str(args.photons)]
        arguments += ["--batch", f"{index}/{args.batches}", "--out", path] + options
        seconds, status, output = run_lustre(lustre, arguments, args.threads_per_task)
        return index, path, arguments, seconds, status, output

    start = time.monotonic()
    try:
        results = ray.get([batch.remote(i) for i in range(args.batches)])
        traced = time.monotonic() - start
        for index, path, arguments, seconds, status, output in results:
            if status != 0:
                fail(f"batch {index}/{args.batches} failed", arguments, output)
        parts = [path for _, path, *_ in sorted(results)]
        arguments = ["merge"] + parts + ["--out", out]
        merge_seconds, status, output = run_lustre(lustre, arguments, 1)
        if status != 0:
            fail("the merge failed", arguments, output)
    finally:
        if not args.keep_batches and args.workdir is None:
            shutil.rmtree(workdir, ignore_errors=True)
    task_seconds = [r[3] for r in results]
    report = {
        "command": "trace",
        "scene": args.scene,
        "photons": args.photons,
        "batches": args.batches,
        "workers": args.workers,
        "threads_per_task": args.threads_per_task,
        "trace_seconds": round(traced, 3),
        "photons_per_second": round(args.photons / traced, 1),
        "task_seconds_median": round(sorted(task_seconds)[len(task_seconds) // 2], 3),
        "merge_seconds": round(merge_seconds, 3),
        "out": out,
    }
    print(json.dumps(report))


def frames(args, ray, lustre):
    try:
        with open(args.list) as f:
            jobs = json.load(f)
    except (OSError, ValueError) as e:
        sys.exit(f"lustre_ray.py: cannot read the frame list {args.list}: {e}")
    if not isinstance(jobs, list) or not all(
        isinstance(j, list) and all(isinstance(a, str) for a in j) for j in jobs
    ):
        sys.exit(f"lustre_ray.py: {args.list}: expected a JSON list of lists of strings")

    @ray.remote(num_cpus=1)
    def frame(index, arguments):
        seconds, status, output = run_lustre(lustre, ["render"] + arguments, args.threads_per_task)
        return index, arguments, seconds, status, output

    start = time.monotonic()
    results = ray.get([frame.remote(i, j) for i, j in enumerate(jobs)])
    for index, arguments, seconds, status, output in results:
        if status != 0:
            fail(f"frame {index} failed", ["render"] + arguments, output)
    print(
        json.dumps(
            {
                "command": "frames",
                "frames": len(jobs),
                "workers": args.workers,
                "seconds": round(time.monotonic() - start, 3),
                "frame_seconds": [round(r[2], 3) for r in results],
            }
        )
    )


def main(argv):
    args = parse_args(argv)
    lustre = find_lustre(args.lustre)
    try:
        import ray
    except ImportError:
        sys.exit(
            "lustre_ray.py: the `ray` package is missing; `cargo xtask ray --install-only` "
            "creates .ray-venv with it (run this script with .ray-venv/bin/python)"
        )
    os.environ.setdefault("RAY_AUTH_MODE", "disabled")
    if args.address:
        ray.init(address=args.address, log_to_driver=False, logging_level=logging.WARNING)
    else:
        ray.init(
            num_cpus=args.workers,
            include_dashboard=False,
            log_to_driver=False,
            logging_level=logging.WARNING,
        )
    try:
        if args.command == "trace":
            trace(args, ray, lustre)
        else:
            frames(args, ray, lustre)
    finally:
        ray.shutdown()


if __name__ == "__main__":
    main(sys.argv[1:])
