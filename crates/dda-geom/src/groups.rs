//! Groups of indices joined pair by pair (disjoint sets, union-find).

/// Disjoint groups of the indices `0..n`, joined pair by pair. Each group is named by
/// its smallest member, so the same pairs joined in any order give the same names.
#[derive(Clone, Debug)]
pub struct Groups {
    root: Vec<usize>,
}

impl Groups {
    /// `n` indices, each in a group of its own.
    pub fn new(n: usize) -> Self {
        Groups {
            root: (0..n).collect(),
        }
    }

    /// Joins the groups of `a` and `b`.
    pub fn join(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.of(a), self.of(b));
        self.root[ra.max(rb)] = ra.min(rb);
    }

    /// The group of `i`: its smallest member.
    pub fn of(&mut self, mut i: usize) -> usize {
        while self.root[i] != i {
            // Path halving: every other link skips to its grandparent.
            self.root[i] = self.root[self.root[i]];
            i = self.root[i];
        }
        i
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Groups are named by their smallest member whatever the order of the joins, and
    /// indices never joined stay alone.
    #[test]
    fn groups_are_named_by_their_smallest_member() {
        for pairs in [[(4, 2), (2, 0), (5, 3)], [(5, 3), (0, 2), (2, 4)]] {
            let mut g = Groups::new(7);
            for (a, b) in pairs {
                g.join(a, b);
            }
            let names: Vec<usize> = (0..7).map(|i| g.of(i)).collect();
            assert_eq!(names, [0, 1, 0, 3, 0, 3, 6]);
        }
    }
}
