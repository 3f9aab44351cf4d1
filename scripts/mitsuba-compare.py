#!/usr/bin/env python3
"""Side by side with Mitsuba 3: renders epsm scene files with `epsm bench render`
and with Mitsuba 3 (its LLVM backend `llvm_ad_rgb`, or with `--variant scalar_rgb` its
one-path-at-a-time CPU variant) on the same machine, and prints a Markdown table of
samples per second and of the two images' mean colours.

Usage (from the repository root, after `cargo build --release`):

    python3 -m venv /tmp/mi && /tmp/mi/bin/pip install mitsuba==3.6.4 numpy
    /tmp/mi/bin/python scripts/mitsuba-compare.py [SCENE.toml ...] \
        [--epsm target/release/epsm] [--spp 256] [--rounds 3] [--threads 1,2] \
        [--variant llvm_ad_rgb|scalar_rgb] [--pixels SEEDS]

Default scenes: every `scenes/*.toml`. Mitsuba's backend needs `libLLVM` (Debian:
`libllvm15`). Each round runs epsm's bench, then Mitsuba once per thread count
(`drjit.set_thread_count`, and the process pinned to that many CPUs, as the scalar
variant's thread pool ignores the former); the LLVM
backend's first render of a scene compiles its kernel, so every Mitsuba timing is
the best of two renders after a warm-up render. Rounds
alternate the two renderers, so compare rates within a round on a shared machine.

The scenes are translated from the TOML files rather than loaded from their
Mitsuba twins in `scenes/mitsuba/`, whose spheres and disks are Mitsuba's analytic
shapes: here both renderers intersect the same surfaces (the same triangles, or
for epsm's exact spheres, `exact = true`, Mitsuba's `sphere`). The translation covers
what the shipped scenes use and refuses the rest (mesh
files, textures, environment maps): the camera (`fov_axis = y`), `[render]`
`max_depth` (Mitsuba counts path segments: epsm's `max_depth` + 1) and `rr_depth`,
built-in shapes with the same geometry (rectangles and cubes are Mitsuba's own
meshes; epsm's icospheres and disk fans are written as PLY meshes), transforms in
epsm's order (scale, rotations in list order, translation), `diffuse`,
`dielectric` (exterior IOR 1), `conductor` and `rough_conductor` (Mitsuba's
`material = none`, so the Fresnel term is 1, times `specular_reflectance = tint`;
GGX with visible-normal sampling), `two_sided` (`twosided`), emissive objects
(`area`), point lights and a constant background (`constant`). Mitsuba's
`independent` sampler and box filter stand in for epsm's stratified samples and
box pixels: both estimate the same image, which the mean-colour columns check.

With `--pixels SEEDS` the script times nothing and checks that image pixel by pixel
instead: each renderer renders each scene SEEDS times (epsm with `--seed`, Mitsuba
with its `seed`) at `--spp`, and every 8 x 8-pixel block's mean colour is compared
as a z-score, the difference of the two renderers' seed-averaged block means over
the standard error of that difference. The standard error comes from each pixel's
seed-to-seed variance, summed over the block (pixels are independent), so it rests
on 64 · (SEEDS − 1) degrees of freedom per renderer. If the two renderers estimate
the same image, the z-scores of the blocks are close to a standard normal: mean 0,
standard deviation 1, about 0.3 % beyond ±3 and none beyond ±5. Blocks that are
constant in both renderers (background seen directly) have no noise to compare
against; the table gives their largest relative difference instead. The script
warns when a z-score exceeds 5, when their standard deviation is off 1 by more than
0.3, or when their mean is more than 8 / sqrt(count) from 0 (a shift of the whole
image). The mean of count standard normals spreads by 1 / sqrt(count); here it
spreads about twice as much (over fourteen checks of the six shipped scenes at 1024
and 4096 spp, the z mean times sqrt(count) ranged from -3.7 to +3.1, root mean
square 1.8), because skewed noise, such as a caustic's, makes a block's mean and its variance
estimate move together. Moving the caustic box's light by 2 cm in epsm's copy only
gives a z mean of -0.6 over 768 z-scores (-16.5 / sqrt(768)) at 256 spp and 4 seeds;
its sphere's IOR 1.45 instead of 1.5, a largest |z| of 22.
"""
import argparse
import json
import math
import os
import pathlib
import subprocess
import sys
import tempfile
import time
import tomllib

try:
    import drjit as dr
    import mitsuba as mi
    import numpy as np
except ImportError as e:
    sys.exit(f"{e}: this script needs `pip install mitsuba==3.6.4 numpy` (see its header)")

VARIANTS = ["llvm_ad_rgb", "scalar_rgb"]

PLY_DIR = pathlib.Path(tempfile.mkdtemp(prefix="epsm-mitsuba-"))


def icosphere(levels):
    """epsm's `sphere`: the icosahedron subdivided `levels` times (crates/epsm-scene/src/shapes.rs)."""
    t = (1.0 + 5.0**0.5) / 2.0
    corners = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
               (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    pos = [np.array(p, dtype=np.float32) / np.float32(np.linalg.norm(p)) for p in corners]
    faces = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
             [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
             [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    for _ in range(levels):
        mid = {}

        def midpoint(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = pos[a] + pos[b]
                pos.append(p / np.float32(np.linalg.norm(p)))
                mid[key] = len(pos) - 1
            return mid[key]

        nxt = []
        for a, b, c in faces:
            ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
            nxt += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        faces = nxt
    p = np.array(pos, dtype=np.float32)
    return p, p, np.array(faces, dtype=np.uint32)


def disk(segments):
    """epsm's `disk`: a fan of `segments` triangles around the centre, facing +z."""
    phi = 2.0 * np.pi * np.arange(segments) / segments
    p = np.zeros((segments + 1, 3), dtype=np.float32)
    p[1:, 0], p[1:, 1] = np.cos(phi), np.sin(phi)
    n = np.tile(np.array([0, 0, 1], dtype=np.float32), (segments + 1, 1))
    i = np.arange(segments, dtype=np.uint32)
    faces = np.stack([np.zeros_like(i), 1 + i, 1 + (i + 1) % segments], axis=1)
    return p, n, faces


def ply(name, positions, normals, faces):
    """A binary PLY file of the mesh (written directly: Mitsuba's own writer takes
    arrays of the LLVM variants' types only)."""
    path = PLY_DIR / f"{name}.ply"
    if not path.exists():
        header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(positions)}\n"
                  + "".join(f"property float {c}\n" for c in ("x", "y", "z", "nx", "ny", "nz"))
                  + f"element face {len(faces)}\nproperty list uchar uint vertex_indices\n"
                  + "end_header\n")
        vertices = np.hstack([positions, normals]).astype("<f4")
        rows = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<u4", 3)])
        rows["n"], rows["i"] = 3, faces
        path.write_bytes(header.encode() + vertices.tobytes() + rows.tobytes())
    return str(path)


def refuse(scene, what):
    sys.exit(f"{scene}: {what} is not translated to Mitsuba by this script")


def to_world(obj):
    m = mi.ScalarTransform4f().translate(obj.get("translate", [0.0, 0.0, 0.0]))
    for r in reversed(obj.get("rotate", [])):
        m = m @ mi.ScalarTransform4f().rotate(r["axis"], r["angle"])
    s = obj.get("scale", 1.0)
    return m @ mi.ScalarTransform4f().scale(s if isinstance(s, list) else [s, s, s])


def bsdf(scene, mat):
    kind = mat["type"]
    if "texture" in mat:
        refuse(scene, "a texture")
    if kind == "diffuse":
        b = {"type": "diffuse", "reflectance": {"type": "rgb", "value": mat.get("albedo", [0.5] * 3)}}
    elif kind == "dielectric":
        return {"type": "dielectric", "int_ior": mat.get("ior", 1.5), "ext_ior": 1.0}
    elif kind == "conductor":
        b = {"type": "conductor", "material": "none",
             "specular_reflectance": {"type": "rgb", "value": mat.get("tint", [1.0] * 3)}}
    elif kind == "rough_conductor":
        b = {"type": "roughconductor", "material": "none", "distribution": "ggx",
             "alpha": mat["alpha"], "sample_visible": True,
             "specular_reflectance": {"type": "rgb", "value": mat.get("tint", [1.0] * 3)}}
    else:
        refuse(scene, f"material type {kind!r}")
    return {"type": "twosided", "bsdf": b} if mat.get("two_sided", False) else b


def shape(scene, obj, materials):
    kind = obj.get("shape")
    if kind is None:
        refuse(scene, "a mesh file")
    levels = obj.get("subdivisions")
    if kind in ("rectangle", "cube"):
        d = {"type": kind}
    elif kind == "sphere" and obj.get("exact", False):
        d = {"type": "sphere"}
    elif kind == "sphere":
        levels = 3 if levels is None else levels
        d = {"type": "ply", "filename": ply(f"sphere{levels}", *icosphere(levels)), "face_normals": False}
    elif kind == "disk":
        levels = 64 if levels is None else levels
        d = {"type": "ply", "filename": ply(f"disk{levels}", *disk(levels)), "face_normals": False}
    else:
        refuse(scene, f"shape {kind!r}")
    d["to_world"] = to_world(obj)
    d["bsdf"] = bsdf(scene, materials[obj["material"]])
    if "emission" in obj:
        d["emitter"] = {"type": "area", "radiance": {"type": "rgb", "value": obj["emission"]}}
    return d


def mitsuba_scene(path, spp, max_depth):
    s = tomllib.loads(pathlib.Path(path).read_text())
    cam, render = s["camera"], s.get("render", {})
    width, height = cam["resolution"]
    d = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": max_depth + 1, "rr_depth": render.get("rr_depth", 3)},
        "sensor": {
            "type": "perspective", "fov": cam.get("fov", 40.0), "fov_axis": "y",
            "to_world": mi.ScalarTransform4f().look_at(origin=cam["origin"], target=cam["target"], up=cam.get("up", [0, 1, 0])),
            "sampler": {"type": "independent", "sample_count": spp},
            "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"}},
        },
    }
    background = s.get("background", {})
    if "envmap" in background:
        refuse(path, "an environment map")
    if "color" in background:
        d["background"] = {"type": "constant", "radiance": {"type": "rgb", "value": background["color"]}}
    for i, light in enumerate(s.get("lights", [])):
        d[f"light{i}"] = {"type": "point", "position": light["position"],
                          "intensity": {"type": "rgb", "value": light["intensity"]}}
    for i, obj in enumerate(s["objects"]):
        d[f"object{i}"] = shape(path, obj, s["materials"])
    return mi.load_dict(d), width * height * spp


def pin(cpus):
    """Restricts every thread of this process to the CPUs `cpus`."""
    for tid in os.listdir("/proc/self/task"):
        try:
            os.sched_setaffinity(int(tid), cpus)
        except ProcessLookupError:
            pass  # a thread that has ended


def mitsuba_run(scene, samples, spp, threads):
    """Best samples/s of two renders after a warm-up (kernel compilation), and the image.
    The process runs on `threads` CPUs meanwhile: the scalar variant's thread pool uses
    every core whatever `drjit.set_thread_count` says."""
    dr.set_thread_count(threads)
    cpus = os.sched_getaffinity(0)
    pin(set(sorted(cpus)[:threads]))
    times, img = [], None
    try:
        for seed in range(3):
            start = time.perf_counter()
            img = mi.render(scene, spp=spp, seed=seed)
            dr.eval(img)
            dr.sync_thread()
            times.append(time.perf_counter() - start)
    finally:
        pin(cpus)
    return samples / min(times[1:]), np.array(img, dtype=np.float64)[..., :3]


def run_epsm(binary, args):
    """epsm's standard output for `args`; exits with epsm's own error (which names the
    file and field of a bad scene) when it fails."""
    try:
        done = subprocess.run([binary, *args], capture_output=True, text=True)
    except OSError as e:
        sys.exit(f"epsm binary {binary}: {e} (build it with `cargo build --release -p epsm-cli`"
                 " or pass --epsm)")
    if done.returncode != 0:
        sys.exit(f"epsm {' '.join(args)} failed:\n{done.stderr.strip()}")
    return done.stdout


def epsm_bench(binary, path, spp, max_depth):
    """Samples/s by thread count (`bench render` runs one thread and all of them)."""
    out = run_epsm(binary, ["bench", "render", path, "--max-depth", str(max_depth),
                            "--spp", str(spp), "--repeats", "1", "--json"])
    return {run["threads"]: run["samples_per_s"] for run in json.loads(out)["runs"]}


BLOCK = 8


def block_means(img):
    """Mean colour of each BLOCK x BLOCK block of `img` (rows x columns x 3; a partial
    last row or column of blocks is left out)."""
    h, w = img.shape[0] // BLOCK * BLOCK, img.shape[1] // BLOCK * BLOCK
    return img[:h, :w].reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK, -1).mean(axis=(1, 3))


def epsm_image(binary, path, spp, seed=None):
    """epsm's render of `path` (rows x columns x RGB), with the scene's seed unless `seed`."""
    seeded = [] if seed is None else ["--seed", str(seed)]
    with tempfile.TemporaryDirectory() as tmp:
        exr = pathlib.Path(tmp) / "epsm.exr"
        run_epsm(binary, ["render", path, "--spp", str(spp), *seeded, "-o", str(exr)])
        return np.array(mi.Bitmap(str(exr)), dtype=np.float64)[..., :3]


def pixel_check(binary, path, spp, seeds):
    """z-scores of the block means of the two renderers' images (see the header), and
    the table row that summarises them."""
    text = tomllib.loads(pathlib.Path(path).read_text())
    scene, _ = mitsuba_scene(path, spp, text.get("render", {}).get("max_depth", 8))
    ours, theirs = [], []
    for seed in range(seeds):
        ours.append(epsm_image(binary, path, spp, seed))
        img = mi.render(scene, spp=spp, seed=seed)
        dr.eval(img)
        theirs.append(np.array(img, dtype=np.float64)[..., :3])
    ours, theirs = np.array(ours), np.array(theirs)
    mean_e, mean_m = block_means(ours.mean(axis=0)), block_means(theirs.mean(axis=0))
    # Variance of a block mean of the seed average: the pixels' variances summed over
    # the block, over (pixels per block)² and the seed count.
    var = (block_means(ours.var(axis=0, ddof=1)) + block_means(theirs.var(axis=0, ddof=1))) / (
        BLOCK * BLOCK * seeds)
    noisy = var > 0
    z = (mean_e - mean_m)[noisy] / np.sqrt(var[noisy])
    constant = ~noisy
    rel = np.abs(mean_e - mean_m)[constant] / np.maximum(np.abs(mean_m[constant]), 1e-30)
    worst = np.abs(z).max(initial=0.0)
    row = (f"| `{path}` | {spp} × {seeds} | {z.size} | {z.mean():+.3f} | {z.std():.3f} "
           f"| {np.sum(np.abs(z) > 3)} | {worst:.2f} | {constant.sum()} "
           f"| {rel.max(initial=0.0):.1e} |")
    if worst > 5 or abs(z.std() - 1) > 0.3 or abs(z.mean()) * math.sqrt(z.size) > 8:
        print(f"warning: {path}: the block z-scores are not those of noise (largest |z| "
              f"{worst:.2f}, mean {z.mean():+.3f}, standard deviation {z.std():.3f})",
              file=sys.stderr)
    return row


def positive(text):
    """An argument that must be a positive integer."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} is not a positive integer")
    return value


def thread_counts(text):
    """`--threads`: comma-separated counts among those epsm's bench runs (1 and all CPUs)."""
    runs = {1, os.cpu_count() or 1}
    counts = [positive(t) for t in text.split(",")]
    if not set(counts) <= runs:
        raise argparse.ArgumentTypeError(f"{text!r}: epsm's bench runs only {sorted(runs)} threads")
    return counts


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenes", nargs="*", help="epsm scene files (default: scenes/*.toml)")
    ap.add_argument("--epsm", default="target/release/epsm")
    ap.add_argument("--spp", type=positive, default=256)
    ap.add_argument("--rounds", type=positive, default=3)
    ap.add_argument("--threads", type=thread_counts, default="1,2",
                    help="thread counts, comma-separated: 1 and the CPU count, which epsm's bench runs")
    ap.add_argument("--variant", choices=VARIANTS, default=VARIANTS[0],
                    help="Mitsuba variant: its LLVM backend (many paths per vector instruction) or "
                         "its scalar CPU variant (one path at a time)")
    ap.add_argument("--pixels", type=positive, metavar="SEEDS",
                    help="time nothing; compare the images block by block over SEEDS seeds "
                         "per renderer at --spp (see the header)")
    args = ap.parse_args()
    mi.set_variant(args.variant)
    scenes = args.scenes or sorted(str(p) for p in pathlib.Path("scenes").glob("*.toml"))
    if args.pixels:
        print(f"Mitsuba variant: `{args.variant}`; {BLOCK} × {BLOCK}-pixel blocks, one z-score "
              "per block and channel (constant blocks and channels apart)\n")
        print("| scene | spp × seeds | z-scores | mean | standard deviation | beyond ±3 "
              "| largest absolute | constant blocks | their largest relative difference |")
        print("|---|---|---|---|---|---|---|---|---|")
        for path in scenes:
            print(pixel_check(args.epsm, path, args.spp, args.pixels), flush=True)
        return
    threads = args.threads
    print(f"Mitsuba variant: `{args.variant}`\n")
    print("| scene | max depth | threads | epsm samples/s | Mitsuba samples/s | epsm / Mitsuba | mean RGB epsm | mean RGB Mitsuba |")
    print("|---|---|---|---|---|---|---|---|")
    for path in scenes:
        # epsm first: it rejects a bad scene file with an error naming the field.
        ours_mean = epsm_image(args.epsm, path, args.spp).reshape(-1, 3).mean(axis=0)
        text = tomllib.loads(pathlib.Path(path).read_text())
        max_depth = text.get("render", {}).get("max_depth", 8)
        scene, samples = mitsuba_scene(path, args.spp, max_depth)
        rates = {t: ([], []) for t in threads}
        img = None
        for _ in range(args.rounds):
            ours = epsm_bench(args.epsm, path, args.spp, max_depth)
            for t in threads:
                theirs, img = mitsuba_run(scene, samples, args.spp, t)
                rates[t][0].append(ours[t])
                rates[t][1].append(theirs)
        theirs_mean = img.reshape(-1, 3).mean(axis=0)
        fmt = lambda c: " ".join(f"{x:.4f}" for x in c)  # noqa: E731
        for t in threads:
            e, m = rates[t]
            ratios = [a / b for a, b in zip(e, m)]
            print(f"| `{path}` | {max_depth} | {t} | {min(e) / 1e6:.2f}–{max(e) / 1e6:.2f} M "
                  f"| {min(m) / 1e6:.2f}–{max(m) / 1e6:.2f} M | {min(ratios):.2f}–{max(ratios):.2f} "
                  f"| {fmt(ours_mean)} | {fmt(theirs_mean)} |", flush=True)
        if not math.isclose(ours_mean.sum(), theirs_mean.sum(), rel_tol=0.05):
            print(f"warning: {path}: mean colours differ by more than 5 %", file=sys.stderr)


if __name__ == "__main__":
    main()
