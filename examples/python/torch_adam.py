"""θ as a PyTorch tensor, stepped by torch.optim.Adam with epsm's gradient.

epsm computes dL/dθ (the OT loss of the render against the target, through
extended path space manifolds); PyTorch owns θ and the optimizer, so the
same loop can add terms of its own (priors, other losses) to θ's gradient.

    python examples/python/torch_adam.py scenes/problems/mirror.toml --steps 40
"""

import argparse

import torch

import epsm


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("problem", help="a problem file (TOML)")
    parser.add_argument("--steps", type=int, default=40)
    parser.add_argument("--lr", type=float, default=0.05, help="Adam's step (user units)")
    args = parser.parse_args()

    problem = epsm.load_problem(args.problem)
    opt = epsm.Optimization(problem)
    theta = torch.tensor(opt.theta, dtype=torch.float64, requires_grad=True)
    adam = torch.optim.Adam([theta], lr=args.lr)
    truth = problem.true_values
    for step in range(args.steps):
        adam.zero_grad()
        # Hand θ to epsm, take its gradient back as θ's.
        opt.theta = theta.detach().tolist()
        theta.grad = torch.from_numpy(opt.gradient())
        adam.step()
        error = [t - x for t, x in zip(theta.tolist(), truth) if x is not None]
        rms = (sum(e * e for e in error) / max(len(error), 1)) ** 0.5 if error else float("nan")
        print(f"step {step:3d}  theta {[round(v, 4) for v in theta.tolist()]}  error {rms:.4f}")


if __name__ == "__main__":
    main()
