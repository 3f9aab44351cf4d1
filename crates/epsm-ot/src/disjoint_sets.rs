//! Disjoint sets (union–find) over `0..n`, for the connected components of block graphs.

/// A partition of `0..n` into sets, merged by [`DisjointSets::union`].
///
/// Union by size and path halving; written here because its one use (the
/// components of a support graph, in `sinkhorn::bridges`) needs a dozen
/// lines, not a graph library.
#[derive(Debug, Clone)]
pub(crate) struct DisjointSets {
    parent: Vec<usize>,
    size: Vec<usize>,
}

impl DisjointSets {
    /// `n` singleton sets.
    pub fn new(n: usize) -> Self {
        Self {
            parent: (0..n).collect(),
            size: vec![1; n],
        }
    }

    /// The representative of `i`'s set.
    fn find(&mut self, mut i: usize) -> usize {
        while self.parent[i] != i {
            self.parent[i] = self.parent[self.parent[i]];
            i = self.parent[i];
        }
        i
    }

    /// Merges the sets of `a` and `b`.
    pub fn union(&mut self, a: usize, b: usize) {
        let (mut a, mut b) = (self.find(a), self.find(b));
        if a == b {
            return;
        }
        if self.size[a] < self.size[b] {
            std::mem::swap(&mut a, &mut b);
        }
        self.parent[b] = a;
        self.size[a] += self.size[b];
    }

    /// Dense labels `0..k` of the sets, in order of their smallest element, and `k`.
    pub fn labels(&mut self) -> (Vec<usize>, usize) {
        let n = self.parent.len();
        let mut label_of_root = vec![usize::MAX; n];
        let mut count = 0;
        let labels = (0..n)
            .map(|i| {
                let r = self.find(i);
                if label_of_root[r] == usize::MAX {
                    label_of_root[r] = count;
                    count += 1;
                }
                label_of_root[r]
            })
            .collect();
        (labels, count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unions_give_the_connected_components() {
        // Edges 0–3, 3–5, 1–4 over 0..7: components {0,3,5}, {1,4}, {2}, {6}.
        let mut sets = DisjointSets::new(7);
        sets.union(0, 3);
        sets.union(5, 3);
        sets.union(1, 4);
        sets.union(0, 5);
        let (labels, count) = sets.labels();
        assert_eq!(count, 4);
        assert_eq!(labels, vec![0, 1, 2, 0, 1, 0, 3]);
    }
}
