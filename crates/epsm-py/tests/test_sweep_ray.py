"""The Ray sweep example on 2 local CPUs over 2 tiny problems: every cell of
the grid comes back once, from worker processes, as one results table."""

import importlib.util

import ray

from conftest import DATA, ROOT


def load_example():
    path = ROOT / "examples" / "python" / "sweep_ray.py"
    spec = importlib.util.spec_from_file_location("sweep_ray", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_sweep_runs_the_grid_on_ray_workers():
    sweep = load_example()
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        problems = [DATA / "tiny.toml", DATA / "tiny-lamp.toml"]
        rows = sweep.sweep(problems, seeds=[1, 2], methods=["epsm"], iterations=2)
    finally:
        ray.shutdown()
    cells = [(r["problem"], r["method"], r["seed"]) for r in rows]
    assert cells == [(p, "epsm", s) for p in ("tiny", "tiny-lamp") for s in (1, 2)]
    assert all(r["last"] is not None and r["wall_s"] > 0 for r in rows)
    # Seeds change the run: the two seeds of a problem end apart.
    assert rows[0]["last"] != rows[1]["last"]
    table = sweep.markdown(rows)
    lines = table.splitlines()
    assert lines[0] == sweep.HEADER.splitlines()[0]
    assert len(lines) == 2 + len(rows)
    assert lines[2].startswith("| tiny | epsm | 1 | ")
