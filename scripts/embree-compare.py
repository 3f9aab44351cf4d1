#!/usr/bin/env python3
"""Side by side with Embree 4: walks the rays of `epsm bench rays` (a bumpy geodesic
sphere and four smaller copies around it) through epsm's BVH and through Embree, on
the same machine and the same triangles and rays, one thread each, and prints a
Markdown table of rays per second and hit fractions.

Usage (from the repository root, after `cargo build --release`):

    python3 -m venv /tmp/emb && /tmp/emb/bin/pip install embreex numpy
    /tmp/emb/bin/python scripts/embree-compare.py [--epsm target/release/epsm] \
        [--triangles 100000] [--rays 1000000] [--rounds 3]

Each round runs `epsm bench rays --threads 1 --dump DIR` (its fastest of three runs
per measurement), then Embree on the files it wrote: `triangles.f32`, every
object's triangles in world space, and the ray sets `coherent.f32` (a camera's
pixel grid) and `incoherent.f32` (uniform origins in the scene's box, uniform
directions), walked for closest hit (`INTERSECT`) and occlusion (`OCCLUDED`).
Rounds alternate the two, so compare rates within a round on a shared machine.

Embree comes from PyPI's `embreex` (Embree 4.4 inside), which walks its rays one
by one (`rtcIntersect1` / `rtcOccluded1` in a compiled loop) on one thread; its
BVH is built over the triangles as one flat mesh, with Embree's default (medium)
build quality. epsm walks the same triangles behind its two-level structure (the
four copies are instances of the big sphere's mesh), so the comparison holds its
triangles and rays, not its acceleration layout, fixed. Embree's times are of
the walk alone: the arrays are prepared before the clock starts, and the best of
three passes counts. The product does not depend on Embree; only this script does.
"""
import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

try:
    from embreex import rtcore_scene
    from embreex.mesh_construction import TriangleMesh
except ImportError:
    sys.exit("embree-compare: needs embreex (pip install embreex numpy)")


def epsm_round(epsm, args, folder):
    """Runs epsm's benchmark with --dump; returns {(rays, query): (Mrays/s, hit fraction)}."""
    out = subprocess.run(
        [epsm, "bench", "rays", "--threads", "1", "--json", "--triangles",
         str(args.triangles), "--rays", str(args.rays), "--dump", str(folder)],
        check=True, capture_output=True, text=True).stdout
    report = json.loads(out)
    rates = {(t["rays"], t["query"]): (t["mrays_per_s"], t["hit_fraction"])
             for t in report["throughput"]}
    return report["triangles"], rates


def embree_round(folder):
    """Builds Embree's BVH over the dumped triangles and walks the dumped rays."""
    triangles = np.fromfile(folder / "triangles.f32", dtype="<f4").reshape(-1, 3, 3)
    scene = rtcore_scene.EmbreeScene()
    start = time.perf_counter()
    TriangleMesh(scene, triangles.astype(np.float32))
    # Embree builds lazily: the first query commits the scene.
    scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))
    build = time.perf_counter() - start
    rates = {}
    for name in ("coherent", "incoherent"):
        rays = np.fromfile(folder / f"{name}.f32", dtype="<f4").reshape(-1, 6)
        origins = np.ascontiguousarray(rays[:, :3])
        dirs = np.ascontiguousarray(rays[:, 3:])
        for query, embree_query in (("closest", "INTERSECT"), ("occluded", "OCCLUDED")):
            best, hits = float("inf"), 0
            for _ in range(3):
                start, cpu = time.perf_counter(), time.process_time()
                result = scene.run(origins, dirs, query=embree_query)
                wall = time.perf_counter() - start
                if time.process_time() - cpu > 1.2 * wall:
                    print(f"warning: Embree's walk used more than one thread ({name}, {query})",
                          file=sys.stderr)
                best = min(best, wall)
                hits = int(np.count_nonzero(np.asarray(result) >= 0)) if embree_query == "INTERSECT" \
                    else int(np.count_nonzero(np.asarray(result) != -1))
            rates[(name, query)] = (len(rays) / best / 1e6, hits / len(rays))
    return len(triangles), build, rates


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--epsm", default="target/release/epsm")
    parser.add_argument("--triangles", type=int, default=100000)
    parser.add_argument("--rays", type=int, default=1000000)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    print("| round | rays | query | epsm M rays/s | Embree M rays/s | Embree / epsm | hit fraction epsm / Embree |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for r in range(1, args.rounds + 1):
            triangles, ours = epsm_round(args.epsm, args, folder)
            count, build, theirs = embree_round(folder)
            for key, (rate, hits) in ours.items():
                their_rate, their_hits = theirs[key]
                print(f"| {r} | {key[0]} | {key[1]} | {rate:.2f} | {their_rate:.2f} | "
                      f"{their_rate / rate:.2f} | {hits:.4f} / {their_hits:.4f} |")
            print(f"<!-- round {r}: epsm's mesh {triangles} triangles in 5 instances, "
                  f"{count} in all; Embree build {build:.3f} s -->")


if __name__ == "__main__":
    main()
