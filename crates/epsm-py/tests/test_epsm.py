"""The Python module against the CLI and the core: renders bit for bit,
gradients against finite differences, matching, errors, a short
optimization, checkpoints and pickling."""

import pickle

import numpy as np
import pytest

import epsm
from conftest import DATA, ROOT, cli_value

TINY_BOX = ROOT / "tests" / "data" / "tiny-box.toml"


def test_render_equals_the_cli_exr_bit_for_bit(epsm_cli, tmp_path):
    out = tmp_path / "cli.exr"
    epsm_cli("render", TINY_BOX, "--spp", 4, "--seed", 9, "-o", out)
    cli = epsm.read_image(out)
    scene = epsm.load_scene(TINY_BOX)
    image = scene.render(spp=4, seed=9)
    assert image.dtype == np.float32 and image.shape == (32, 32, 3)
    assert image.max() > 0.0
    assert image.tobytes() == cli.tobytes()
    # Another seed is another image: the comparison can fail.
    assert scene.render(spp=4, seed=10).tobytes() != cli.tobytes()


def test_set_moves_the_scene_and_get_reads_it_back():
    scene = epsm.load_scene(TINY_BOX)
    before = scene.render(spp=2, seed=1)
    assert scene.get("box.translate.x") == 0.0
    scene.set("box.translate.x", 0.4)
    assert scene.get("box.translate.x") == 0.4
    assert not np.array_equal(before, scene.render(spp=2, seed=1))
    with pytest.raises(epsm.EpsmError) as e:
        scene.set("box.translate.w", 1.0)
    assert e.value.field == "box.translate.w"


def test_gradient_matches_central_differences():
    # L2 on the box's red albedo: the loss at θ ± h uses the same random
    # streams (the iteration does not advance), so the difference is smooth.
    scene = epsm.load_scene(DATA / "albedo.toml")
    problem = epsm.Problem(
        scene,
        [{"key": "box.albedo.r", "initial": 0.5, "true": 0.8, "lr": 0.05}],
        target={"spp": 64},
        loss={"kind": "l2", "match_resolution": [24, 24]},
        optimizer={"method": "l2", "iterations": 4},
        render={"spp_grad": 64, "spp_primal": 4},
    )
    opt = epsm.Optimization(problem)
    grad = opt.gradient()[0]
    h = 0.02
    losses = []
    for theta in (0.5 + h, 0.5 - h):
        opt.theta = [theta]
        losses.append(opt.loss())
    fd = (losses[0] - losses[1]) / (2 * h)
    assert grad < 0.0, "raising the albedo towards the target lowers the loss"
    assert abs(grad - fd) < 0.02 * abs(fd), (grad, fd)


def test_match_equals_the_rust_result(epsm_cli, tmp_path):
    scene = epsm.load_scene(TINY_BOX)
    a = scene.render(spp=2, seed=1)
    scene.set("box.translate.x", 0.3)
    b = scene.render(spp=2, seed=2)
    epsm.write_image(tmp_path / "a.exr", a)
    epsm.write_image(tmp_path / "b.exr", b)
    for solver in ("exact", "sinkhorn"):
        m = epsm.match(a, b, solver=solver, lam=0.5, blur=0.05)
        out = epsm_cli(
            "match", tmp_path / "a.exr", tmp_path / "b.exr", "--solver", solver,
            "--lambda", 0.5, "--blur", 0.05, "--resolution", 32, 32,
        )
        assert m["loss"] == float(cli_value(out, "loss")), solver
        assert m["loss"] > 0.0
        assert m["grad_points"].shape == (32, 32, 5)
        assert m["grad_xy"].shape == (32, 32, 2)
        # Every gradient is 2 (P - T) / n toward the point's target.
        n = 32 * 32
        pull = m["targets"] + 0.5 * n * m["grad_points"]
        assert np.allclose(pull[..., 3] / 0.5, (np.arange(32)[None, :] + 0.5) / 32, atol=1e-4)
    exact = epsm.match(a, b)
    assert np.array_equal(np.sort(exact["assignment"]), np.arange(n))
    assert epsm.match(a, a)["loss"] == 0.0


def test_a_malformed_problem_raises_with_the_field_named(tmp_path):
    bad = tmp_path / "bad.toml"
    text = (DATA / "tiny.toml").read_text().replace('kind = "ot_exact"', 'kind = "ot_fast"')
    bad.write_text(text.replace("../../../../tests", str(ROOT / "tests")))
    with pytest.raises(epsm.EpsmError) as e:
        epsm.load_problem(bad)
    assert e.value.field == "loss.kind"
    assert e.value.file == str(bad)
    assert e.value.line == 10
    assert "unknown loss `ot_fast`" in e.value.message
    assert str(e.value).startswith(f"{bad}:10: loss.kind:")


def test_three_steps_move_theta_toward_the_truth():
    opt = epsm.Optimization(epsm.load_problem(DATA / "tiny.toml"))
    rows = [opt.step() for _ in range(3)]
    assert [r["iteration"] for r in rows] == [0, 1, 2]
    assert rows[0]["theta"] == [0.5]
    assert all(r["loss"] > 0.0 and r["paths"][0] > 0 for r in rows)
    assert opt.done
    assert abs(opt.theta[0]) < 0.5
    with pytest.raises(epsm.EpsmError):
        opt.step()


def test_checkpoint_round_trip_continues_exactly(tmp_path):
    problem = epsm.load_problem(DATA / "tiny.toml")
    straight = epsm.Optimization(problem)
    straight.step()
    path = tmp_path / "run.json"
    straight.checkpoint(path)
    resumed = epsm.Optimization.restore(path)
    assert resumed.iteration == 1 and resumed.theta == straight.theta
    assert resumed.rows == straight.rows
    a, b = straight.step(), resumed.step()
    assert a["theta"] == b["theta"] and a["loss"] == b["loss"]
    assert straight.theta == resumed.theta
    path.write_text(path.read_text().replace('"iteration": 1', '"iteration": 7', 1))
    with pytest.raises(epsm.EpsmError) as e:
        epsm.Optimization.restore(path)
    assert str(path) in str(e.value)


def test_scenes_and_problems_pickle():
    scene = epsm.load_scene(TINY_BOX)
    scene.set("box.translate.x", 0.25)
    copy = pickle.loads(pickle.dumps(scene))
    assert copy.get("box.translate.x") == 0.25
    assert copy.render(spp=1, seed=3).tobytes() == scene.render(spp=1, seed=3).tobytes()
    target = epsm.load_scene(TINY_BOX).render(spp=4, seed=1)
    built = epsm.Problem(scene, ["box.translate.x"], target=target, optimizer={"iterations": 2})
    again = pickle.loads(pickle.dumps(built))
    assert again.keys == ["box.translate.x"] and again.text == built.text
    assert again.target.tobytes() == target.tobytes()
    filed = pickle.loads(pickle.dumps(epsm.load_problem(DATA / "tiny.toml")))
    assert filed.true_values == [0.0]


def test_motion_field_moves_the_box_right():
    scene = epsm.load_scene(TINY_BOX)
    field, counts = epsm.motion_field(scene, "box.translate.x", spp=2)
    assert field.shape == (32, 32, 2)
    moving = np.linalg.norm(field, axis=2) > 0
    assert 0 < moving.sum() < 32 * 32
    # Seen from above and in front, +x moves the box right on the film.
    assert np.mean(field[moving][:, 0] > 0) > 0.9
    assert counts["primary"] > 0
