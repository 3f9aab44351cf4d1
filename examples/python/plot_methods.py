"""Parameter error against wall-clock time for several methods on one
problem, side by side, with matplotlib (what `epsm compare` plots, from
Python).

    python examples/python/plot_methods.py scenes/problems/mirror.toml \
        --methods epsm drot l2 --out methods.png
"""

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import epsm  # noqa: E402


def run(problem, method):
    """Runs `method` to the end; returns (wall seconds, parameter error) per iteration."""
    opt = epsm.Optimization(problem, method=method)
    times, errors = [], []
    while not opt.done:
        row = opt.step()
        times.append(row["wall_s"])
        errors.append(row["param_error"])
    return times, errors


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("problem", help="a problem file with true values (TOML)")
    parser.add_argument("--methods", nargs="+", default=["epsm", "drot", "l2"])
    parser.add_argument("--out", default="methods.png")
    args = parser.parse_args()

    problem = epsm.load_problem(args.problem)
    fig, axes = plt.subplots(1, len(args.methods), figsize=(4 * len(args.methods), 3.5),
                             sharey=True, squeeze=False)
    for ax, method in zip(axes[0], args.methods):
        times, errors = run(problem, method)
        ax.semilogy(times, errors)
        ax.set_title(method)
        ax.set_xlabel("wall-clock s")
        ax.grid(True, which="both", alpha=0.3)
        if problem.tolerance is not None:
            ax.axhline(problem.tolerance, color="grey", linestyle="--", label="tolerance")
            ax.legend()
    axes[0][0].set_ylabel("parameter error (RMS)")
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"{args.problem}: {', '.join(args.methods)} -> {args.out}")


if __name__ == "__main__":
    main()
