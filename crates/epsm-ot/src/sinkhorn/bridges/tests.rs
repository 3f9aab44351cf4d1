//! Lumped-problem tests: Newton across weak bridges, the grounded Laplacian
//! solve, and several components joined in both directions.

use super::*;

fn lumped(log_flows: Vec<Vec<f64>>, a: &[f64], b: &[f64]) -> Lumped {
    let k = a.len();
    Lumped {
        components: k,
        src: (0..k).collect(),
        dst: (0..k).collect(),
        log_flows,
        log_a: a.iter().map(|m| m.ln()).collect(),
        log_b: b.iter().map(|m| m.ln()).collect(),
    }
}

/// Row and column L1 errors of the lumped plan for shifts `u, v`.
fn marginal_errors(l: &Lumped, s: &Solved) -> (f64, f64) {
    let k = l.components;
    let p = |a: usize, b: usize| (l.log_flows[a][b] + s.u[a] + s.v[b]).exp();
    let row: f64 = (0..k)
        .map(|a| ((0..k).map(|b| p(a, b)).sum::<f64>() - l.log_a[a].exp()).abs())
        .sum();
    let col: f64 = (0..k)
        .map(|b| ((0..k).map(|a| p(a, b)).sum::<f64>() - l.log_b[b].exp()).abs())
        .sum();
    (row, col)
}

#[test]
fn newton_moves_an_imbalance_across_a_bridge_of_mass_e_minus_80() {
    // Seed 4's lumped problem at n = 16384: 0.1 % of the mass must cross a bridge
    // carrying e^−80 (the Anderson-accelerated scaling did not converge in 10 000 updates).
    let l = lumped(
        vec![vec![-0.6346, -80.03], vec![f64::NEG_INFINITY, -2.107]],
        &[(-0.21238f64).exp(), (-1.65368f64).exp()],
        &[(-0.21382f64).exp(), (-1.64763f64).exp()],
    );
    let s = l.solve().unwrap_or_else(|| panic!("did not converge"));
    assert!(s.steps <= 5, "{} Newton steps", s.steps);
    let (row, col) = marginal_errors(&l, &s);
    assert!(row <= SCALING_TOLERANCE && col <= 1e-12, "{row} {col}");
    // One-way flow: the bridge carries the whole imbalance A_0 − B_0.
    let bridge = (l.log_flows[0][1] + s.u[0] + s.v[1]).exp();
    let imbalance = l.log_a[0].exp() - l.log_b[0].exp();
    assert!(
        (bridge - imbalance).abs() <= SCALING_TOLERANCE,
        "{bridge} {imbalance}"
    );
}

#[test]
fn the_grounded_laplacian_solve_keeps_weights_far_below_rounding() {
    // Nodes 0 and 1 joined by weight 1, node 0 grounded by e^−60 only: the system is
    // [[1 + e^−60, −1], [−1, 1]] x = [0, r], whose solution x = (r e^60, r e^60 + r)
    // needs the e^−60 that the sum 1 + e^−60 rounds away.
    let tiny = (-60.0f64).exp();
    let r = 1e-3;
    let x = grounded_laplacian_solve(
        vec![vec![0.0, 1.0], vec![1.0, 0.0]],
        vec![tiny, 0.0],
        vec![0.0, r],
    )
    .unwrap_or_else(|| panic!("singular"));
    let exact = [r / tiny, r / tiny + r];
    assert_eq!(x.len(), exact.len(), "{x:?}");
    for (got, want) in x.iter().zip(exact) {
        assert!((got / want - 1.0).abs() < 1e-12, "{x:?} against {exact:?}");
    }
    // A node without any path to the ground is singular.
    assert!(grounded_laplacian_solve(vec![vec![0.0]], vec![0.0], vec![1.0]).is_none());
}

#[test]
fn newton_solves_three_components_joined_in_both_directions() {
    // From 4096 points, seed 1, `jump_radii` 1.75: component 0's excess (2.5 % of
    // the mass) must reach component 2 through a bridge of e^−53, while 1 and 2 are
    // joined by e^−14 one way and e^−50 the other.
    let l = Lumped {
        components: 3,
        src: vec![0, 1, 2],
        dst: vec![0, 1, 2],
        log_flows: vec![
            vec![-0.5066, -88.389, -53.397],
            vec![-68.606, -2.8891, -13.756],
            vec![-86.963, -50.247, -3.1586],
        ],
        log_a: vec![-0.173958, -2.474222, -2.584425],
        log_b: vec![-0.203741, -2.465564, -2.308953],
    };
    let s = l.solve().unwrap_or_else(|| panic!("did not converge"));
    assert!(s.steps <= 20, "{} Newton steps", s.steps);
    let (row, col) = marginal_errors(&l, &s);
    assert!(row <= SCALING_TOLERANCE && col <= 1e-12, "{row} {col}");
}

#[test]
fn newton_solves_a_chain_of_components_and_a_target_only_component() {
    // 0 → 1 → 2 by weak one-way bridges; component 2 holds only targets.
    let ninf = f64::NEG_INFINITY;
    let l = lumped(
        vec![
            vec![-0.5, -40.0, ninf],
            vec![ninf, -1.2, -60.0],
            vec![ninf, ninf, ninf],
        ],
        &[0.6, 0.4, 0.0],
        &[0.5, 0.4, 0.1],
    );
    let s = l.solve().unwrap_or_else(|| panic!("did not converge"));
    assert!(s.steps <= 20, "{} Newton steps", s.steps);
    let (row, col) = marginal_errors(&l, &s);
    assert!(row <= SCALING_TOLERANCE && col <= 1e-12, "{row} {col}");
}
