//! Neighbour (broad-phase) search: block pairs whose bounding boxes, grown so that boxes
//! within d_tol of each other overlap, by sort-and-sweep along the scene's longer axis.

use dda_geom::Aabb;
use serde::{Deserialize, Serialize};

/// Two blocks that may be in contact this step, `a < b`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct NeighbourPair {
    /// The lower block index.
    pub a: u32,
    /// The higher block index.
    pub b: u32,
}

impl NeighbourPair {
    /// The pair of blocks `i` and `j` in either order (`i != j`).
    #[inline]
    pub fn new(i: u32, j: u32) -> Self {
        if i < j {
            NeighbourPair { a: i, b: j }
        } else {
            NeighbourPair { a: j, b: i }
        }
    }
}

/// All pairs of boxes no farther apart than `gap` (each box is grown by gap / 2), sorted.
/// Sort-and-sweep along the longer axis of the scene: O(N log N + K) for K pairs.
/// `out` is cleared first, so its buffer can be reused from step to step.
pub fn neighbour_pairs(boxes: &[Aabb], gap: f64, out: &mut Vec<NeighbourPair>) {
    out.clear();
    if boxes.len() < 2 {
        return;
    }
    let half = 0.5 * gap.max(0.0);
    let scene = boxes.iter().skip(1).fold(boxes[0], |s, b| s.union(b));
    let size = scene.size();
    let axis = usize::from(size.y > size.x);
    let lo = |b: &Aabb| if axis == 0 { b.min.x } else { b.min.y } - half;
    let hi = |b: &Aabb| if axis == 0 { b.max.x } else { b.max.y } + half;
    let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
    order.sort_unstable_by(|&i, &j| {
        lo(&boxes[i as usize])
            .total_cmp(&lo(&boxes[j as usize]))
            .then(i.cmp(&j))
    });
    for (k, &i) in order.iter().enumerate() {
        let bi = boxes[i as usize].expanded(half);
        let end = hi(&boxes[i as usize]);
        for &j in &order[k + 1..] {
            let bj = &boxes[j as usize];
            if lo(bj) > end {
                break;
            }
            if bi.overlaps(&bj.expanded(half)) {
                out.push(NeighbourPair::new(i, j));
            }
        }
    }
    out.sort_unstable();
}

#[cfg(test)]
mod tests {
    use super::*;
    use dda_geom::DVec2;

    #[test]
    fn touching_and_gap() {
        let b = |x: f64| Aabb {
            min: DVec2::new(x, 0.0),
            max: DVec2::new(x + 1.0, 1.0),
        };
        let boxes = [b(0.0), b(1.05), b(3.0)];
        let mut out = Vec::new();
        neighbour_pairs(&boxes, 0.1, &mut out);
        assert_eq!(out, vec![NeighbourPair::new(0, 1)]);
        neighbour_pairs(&boxes, 0.01, &mut out);
        assert!(out.is_empty());
    }
}
