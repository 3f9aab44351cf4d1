"""A sweep of problems x seeds x methods as Ray tasks, one optimization per
task, written as one Markdown table in the shape of docs/results.md.

Local by default (Ray starts on this machine); on a cluster, pass its
address (`--address ray://head:10001` or `auto` on a cluster node): every
task ships its problem as a pickle (the problem file's path and the
settings changed), so each worker needs the epsm wheel and the scene
files at the same paths (docs/python.md, "Sweeps on Ray").

    python examples/python/sweep_ray.py scenes/problems/mirror.toml \
        scenes/problems/shadow.toml --seeds 1 2 3 --methods epsm drot l2 \
        --out sweep.md
"""

import argparse
import pathlib
import time

import ray

import epsm

HEADER = (
    "| problem | method | seed | last θ error | best θ error | tolerance | solved | wall s |\n"
    "|---|---|---|---|---|---|---|---|"
)


# One rayon thread per task: Ray schedules one task per CPU.
@ray.remote(num_cpus=1, runtime_env={"env_vars": {"RAYON_NUM_THREADS": "1"}})
def run_one(name, problem, method, seed, iterations):
    """Runs one optimization to the end; returns its results row (a dict)."""
    settings = {"seed": seed, "method": method}
    if iterations is not None:
        settings["iterations"] = iterations
    opt = epsm.Optimization(problem.with_settings(optimizer=settings))
    start = time.perf_counter()
    while not opt.done:
        opt.step()
    best = opt.best or {}
    tolerance = problem.tolerance
    best_error = best.get("param_error")
    return {
        "problem": name,
        "method": method,
        "seed": seed,
        "last": opt.param_error,
        "best": best_error,
        "best_iteration": best.get("iteration"),
        "tolerance": tolerance,
        "solved": None if tolerance is None or best_error is None else best_error <= tolerance,
        "wall_s": time.perf_counter() - start,
    }


def sweep(problem_paths, seeds, methods, iterations=None):
    """Runs the grid as Ray tasks (Ray must be initialised); returns rows
    sorted by problem, method and seed."""
    tasks = []
    for path in problem_paths:
        path = pathlib.Path(path)
        problem = epsm.load_problem(path)
        ref = ray.put(problem)
        for method in methods:
            for seed in seeds:
                tasks.append(run_one.remote(path.stem, ref, method, seed, iterations))
    rows = ray.get(tasks)
    return sorted(rows, key=lambda r: (r["problem"], r["method"], r["seed"]))


def markdown(rows):
    """The results table (docs/results.md's columns plus the method)."""

    def num(v):
        return "—" if v is None else f"{v:.4f}"

    lines = [HEADER]
    for r in rows:
        best = num(r["best"])
        if r["best_iteration"] is not None and r["best"] is not None:
            best += f" (it. {r['best_iteration']})"
        solved = {True: "yes", False: "no", None: "—"}[r["solved"]]
        lines.append(
            f"| {r['problem']} | {r['method']} | {r['seed']} | {num(r['last'])} | {best} "
            f"| {num(r['tolerance'])} | {solved} | {r['wall_s']:.1f} |"
        )
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("problems", nargs="+", help="problem files (TOML)")
    parser.add_argument("--seeds", nargs="+", type=int, default=[1, 2, 3])
    parser.add_argument("--methods", nargs="+", default=["epsm", "drot", "l2"])
    parser.add_argument("--iterations", type=int, help="override optimizer.iterations")
    parser.add_argument("--address", help="a Ray cluster (default: start Ray locally)")
    parser.add_argument("--cpus", type=int, help="CPUs of a local Ray (default: all)")
    parser.add_argument("--out", type=pathlib.Path, help="write the table here too")
    args = parser.parse_args()
    if args.address:
        ray.init(address=args.address)
    else:
        ray.init(num_cpus=args.cpus, include_dashboard=False)
    table = markdown(sweep(args.problems, args.seeds, args.methods, args.iterations))
    print(table, end="")
    if args.out:
        args.out.write_text(table)


if __name__ == "__main__":
    main()
