//! ε-scaling forward auction on the sparse candidate graph: fast price discovery.
//!
//! Bertsekas' auction in minimisation form: every unassigned row `i` bids for
//! the column `j₁` minimising `c_ij + q_j`, raising its price `q_j₁` by the gap
//! to the second-best column plus ε, and evicting the previous owner. At the
//! end of a phase every row holds a column within ε of its best (ε-complementary
//! slackness); ε then shrinks by `factor` and all rows bid again from the
//! current prices. The prices (as column potentials `v = −q`) warm-start the
//! exact shortest-augmenting-path finish, whose searches then stay tiny.

const NONE: u32 = u32::MAX;

/// Runs the auction from prices `q` (updated in place); returns the final row → column
/// assignment, or `None` if the bid budget ran out (e.g. the graph has no perfect matching).
pub(crate) fn run(
    edges: &[Vec<(u32, f64)>],
    q: &mut [f64],
    eps_start: f64,
    eps_end: f64,
    factor: f64,
) -> Option<Vec<u32>> {
    let n = edges.len();
    let budget = 200 * n + 10_000;
    let mut eps = eps_start.max(eps_end);
    let mut owner = vec![NONE; n];
    let mut col_of = vec![NONE; n];
    loop {
        owner.fill(NONE);
        col_of.fill(NONE);
        let mut queue: Vec<u32> = (0..n as u32).rev().collect();
        let mut bids = 0usize;
        while let Some(i) = queue.pop() {
            bids += 1;
            if bids > budget {
                return None;
            }
            let (mut j1, mut r1, mut r2) = (NONE, f64::INFINITY, f64::INFINITY);
            for &(j, c) in &edges[i as usize] {
                let r = c + q[j as usize];
                if r < r1 {
                    (j1, r2, r1) = (j, r1, r);
                } else if r < r2 {
                    r2 = r;
                }
            }
            if j1 == NONE {
                return None;
            }
            let gap = if r2.is_finite() { r2 - r1 } else { 1.0 };
            q[j1 as usize] += gap + eps;
            let previous = owner[j1 as usize];
            if previous != NONE {
                col_of[previous as usize] = NONE;
                queue.push(previous);
            }
            owner[j1 as usize] = i;
            col_of[i as usize] = j1;
        }
        if eps <= eps_end {
            return Some(col_of);
        }
        eps = (eps * factor).max(eps_end);
    }
}
