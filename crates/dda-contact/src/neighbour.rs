//! Neighbour (broad-phase) search: block pairs whose bounding boxes, grown so that boxes
//! within d_tol of each other overlap, by sort-and-sweep along the axis where the boxes'
//! intervals overlap least; optionally swept with a skin and reused while the boxes stay
//! within it (a Verlet list).

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
/// Sort-and-sweep along the axis where the boxes' intervals overlap least: O(N log N + K)
/// for K pairs, plus the tests of pairs that overlap on that axis only.
/// `out` is cleared first, so its buffer can be reused from step to step; a
/// [`NeighbourSearch`] also keeps its sort order and scratch from call to call.
pub fn neighbour_pairs(boxes: &[Aabb], gap: f64, out: &mut Vec<NeighbourPair>) {
    NeighbourSearch::default().find(boxes, gap, out);
}

/// Sort-and-sweep neighbour search that keeps its box order and buffers between calls:
/// blocks move little in a step, so the order of the last call is nearly sorted and
/// re-sorts in about linear time (the stable sort finds the runs), and nothing is
/// allocated once the buffers have grown. Gives exactly [`neighbour_pairs`]' result.
///
/// With a skin ([`NeighbourSearch::with_skin`]) it sweeps for the gap plus twice the skin
/// and keeps those pairs (a Verlet list): while no box edge has moved by more than the
/// skin since, every pair within the gap is among them, and a call only filters them by
/// the same box test the sweep applies. The result is the same either way; only the
/// number of sweeps differs.
#[derive(Clone, Debug, Default)]
pub struct NeighbourSearch {
    /// Box indices in the order of the last sweep.
    order: Vec<u32>,
    /// The axis of the last sweep (0: x, 1: y).
    axis: usize,
    /// Pairs found by the sweep, then per lower block the start of its pairs.
    found: Vec<NeighbourPair>,
    start: Vec<u32>,
    /// How far a box edge may move before the kept pairs are swept anew (0: every call).
    skin: f64,
    /// The boxes and the gap of the last sweep with a skin, and the pairs it found.
    built: Vec<Aabb>,
    built_gap: f64,
    kept: Vec<NeighbourPair>,
    /// Sweeps made (with a skin: the calls that could not reuse the kept pairs).
    sweeps: u64,
}

impl NeighbourSearch {
    /// An empty search that sweeps at every call.
    pub fn new() -> Self {
        Self::default()
    }

    /// An empty search that keeps the pairs within the gap plus twice `skin` and reuses
    /// them while no box edge has moved by more than `skin` (a non-positive or non-finite
    /// skin sweeps at every call).
    pub fn with_skin(skin: f64) -> Self {
        NeighbourSearch {
            skin: if skin.is_finite() { skin.max(0.0) } else { 0.0 },
            ..Self::default()
        }
    }

    /// How many sweeps the calls so far have made.
    pub fn sweeps(&self) -> u64 {
        self.sweeps
    }

    /// Whether the kept pairs hold every pair of `boxes` within `gap`: same boxes and
    /// gap, and no box edge moved by more than the skin (less a margin far above
    /// rounding) since the sweep that found them.
    fn kept_hold(&self, boxes: &[Aabb], gap: f64) -> bool {
        let limit = 0.999 * self.skin;
        let near = |a: f64, b: f64| (a - b).abs() <= limit;
        self.built.len() == boxes.len()
            && self.built_gap == gap
            && self.built.iter().zip(boxes).all(|(o, b)| {
                near(o.min.x, b.min.x)
                    && near(o.min.y, b.min.y)
                    && near(o.max.x, b.max.x)
                    && near(o.max.y, b.max.y)
            })
    }

    /// The axis to sweep along (0: x, 1: y): the one along which a box's grown interval
    /// overlaps the fewest others on average, estimated as the sum of the intervals'
    /// lengths over the spread of the boxes' centres. The spread of the scene's bounding
    /// box would mislead: one long fixed base (the jointed columns' is five times the
    /// column's width) makes a tall column look wide, and sweeping it along x tested 2 to
    /// 2.6 times as many pairs as along y. The axis of the last call is kept unless the
    /// other is clearly better, so that the kept order stays nearly sorted.
    fn sweep_axis(&mut self, boxes: &[Aabb], gap: f64) -> usize {
        let density = |axis: usize| {
            let (mut length, mut lo, mut hi) = (0.0, f64::INFINITY, f64::NEG_INFINITY);
            for b in boxes {
                let (a, z) = if axis == 0 {
                    (b.min.x, b.max.x)
                } else {
                    (b.min.y, b.max.y)
                };
                length += z - a + gap;
                lo = f64::min(lo, 0.5 * (a + z));
                hi = f64::max(hi, 0.5 * (a + z));
            }
            length / (hi - lo)
        };
        let (dx, dy) = (density(0), density(1));
        let better = |d: f64, other: f64| d < 0.8 * other || (other.is_nan() && !d.is_nan());
        self.axis = match self.axis {
            0 if better(dy, dx) => 1,
            1 if better(dx, dy) => 0,
            kept => kept,
        };
        self.axis
    }

    /// All pairs of `boxes` no farther apart than `gap`, sorted, into `out` (cleared).
    pub fn find(&mut self, boxes: &[Aabb], gap: f64, out: &mut Vec<NeighbourPair>) {
        out.clear();
        if self.skin == 0.0 {
            self.sweep(boxes, gap, out);
            return;
        }
        if !self.kept_hold(boxes, gap) {
            let mut kept = std::mem::take(&mut self.kept);
            self.sweep(boxes, gap.max(0.0) + 2.0 * self.skin, &mut kept);
            self.kept = kept;
            self.built.clear();
            self.built.extend_from_slice(boxes);
            self.built_gap = gap;
        }
        // The sweep's own test: grown boxes that overlap (the kept pairs are sorted).
        let half = 0.5 * gap.max(0.0);
        out.extend(self.kept.iter().filter(|p| {
            boxes[p.a as usize]
                .expanded(half)
                .overlaps(&boxes[p.b as usize].expanded(half))
        }));
    }

    /// All pairs of `boxes` no farther apart than `gap`, sorted, into `out` (cleared), by
    /// sort-and-sweep.
    fn sweep(&mut self, boxes: &[Aabb], gap: f64, out: &mut Vec<NeighbourPair>) {
        out.clear();
        self.sweeps += 1;
        if boxes.len() < 2 {
            return;
        }
        let half = 0.5 * gap.max(0.0);
        let axis = self.sweep_axis(boxes, gap);
        let lo = |b: &Aabb| if axis == 0 { b.min.x } else { b.min.y } - half;
        let hi = |b: &Aabb| if axis == 0 { b.max.x } else { b.max.y } + half;
        let n = boxes.len();
        if self.order.len() != n {
            self.order.clear();
            self.order.extend(0..n as u32);
        }
        // Ties broken by index: the order is a total one, whatever the previous order.
        self.order.sort_by(|&i, &j| {
            lo(&boxes[i as usize])
                .total_cmp(&lo(&boxes[j as usize]))
                .then(i.cmp(&j))
        });
        self.found.clear();
        for (k, &i) in self.order.iter().enumerate() {
            let bi = boxes[i as usize].expanded(half);
            let end = hi(&boxes[i as usize]);
            for &j in &self.order[k + 1..] {
                let bj = &boxes[j as usize];
                if lo(bj) > end {
                    break;
                }
                if bi.overlaps(&bj.expanded(half)) {
                    self.found.push(NeighbourPair::new(i, j));
                }
            }
        }
        // Counting sort by the lower block, then each block's few pairs by the higher.
        self.start.clear();
        self.start.resize(n + 1, 0);
        for p in &self.found {
            self.start[p.a as usize + 1] += 1;
        }
        for a in 0..n {
            self.start[a + 1] += self.start[a];
        }
        out.resize(self.found.len(), NeighbourPair { a: 0, b: 0 });
        for p in &self.found {
            let slot = &mut self.start[p.a as usize];
            out[*slot as usize] = *p;
            *slot += 1;
        }
        // `start[a]` is now the end of block a's pairs, the start of block a + 1's.
        let mut begin = 0;
        for a in 0..n {
            let end = self.start[a] as usize;
            out[begin..end].sort_unstable();
            begin = end;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dda_geom::DVec2;

    /// A reproducible stream of numbers uniform in [0, 1) (a 64-bit LCG).
    fn uniform(seed: u64) -> impl FnMut() -> f64 {
        let mut rng = seed;
        move || {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (rng >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// 300 boxes of 0.1 to 0.7 by 0.1 to 0.7 scattered over 10 x 4.
    fn random_boxes(next: &mut impl FnMut() -> f64) -> Vec<Aabb> {
        (0..300)
            .map(|_| {
                let c = DVec2::new(10.0 * next(), 4.0 * next());
                let h = DVec2::new(0.05 + 0.3 * next(), 0.05 + 0.3 * next());
                Aabb {
                    min: c - h,
                    max: c + h,
                }
            })
            .collect()
    }

    /// The search that keeps its order gives the plain search's pairs as boxes move.
    #[test]
    fn kept_order_matches_a_fresh_search() {
        let mut next = uniform(12345);
        let mut boxes = random_boxes(&mut next);
        let mut search = NeighbourSearch::new();
        let (mut kept, mut fresh) = (Vec::new(), Vec::new());
        for _ in 0..20 {
            search.find(&boxes, 0.02, &mut kept);
            // The reference: every pair checked, no sweep.
            fresh.clear();
            for i in 0..boxes.len() {
                for j in i + 1..boxes.len() {
                    if boxes[i].expanded(0.01).overlaps(&boxes[j].expanded(0.01)) {
                        fresh.push(NeighbourPair::new(i as u32, j as u32));
                    }
                }
            }
            assert_eq!(kept, fresh);
            assert!(!kept.is_empty());
            for b in boxes.iter_mut() {
                let d = DVec2::new(0.2 * next() - 0.1, 0.2 * next() - 0.1);
                b.min += d;
                b.max += d;
            }
        }
    }

    /// With a skin the search gives every pair within the gap, as a fresh search does,
    /// while sweeping only after some box has moved farther than the skin since the last
    /// sweep, or the gap has changed.
    #[test]
    fn a_skin_reuses_pairs_until_a_box_moves_past_it() {
        let mut next = uniform(777);
        let mut boxes = random_boxes(&mut next);
        let (skin, rounds) = (0.05, 40u64);
        let mut search = NeighbourSearch::with_skin(skin);
        let mut out = Vec::new();
        for round in 0..rounds {
            // Every tenth round one box jumps by four skins, and the last rounds use a
            // larger gap: both must sweep anew.
            let gap = if round < 35 { 0.02 } else { 0.03 };
            search.find(&boxes, gap, &mut out);
            assert_eq!(out, brute_force(&boxes, gap), "round {round}");
            assert!(!out.is_empty());
            for b in boxes.iter_mut() {
                let d = DVec2::new(0.01 * next() - 0.005, 0.01 * next() - 0.005);
                b.min += d;
                b.max += d;
            }
            if round % 10 == 9 {
                let k = (next() * 300.0) as usize;
                boxes[k].min.x += 4.0 * skin;
                boxes[k].max.x += 4.0 * skin;
            }
        }
        // At least the first call, the calls after the jumps (the 11th, 21st and 31st)
        // and the first with the new gap.
        assert!(search.sweeps() >= 5, "{} sweeps", search.sweeps());
        assert!(search.sweeps() < rounds / 2, "{} sweeps", search.sweeps());
    }

    /// Every pair of boxes within `gap`, by checking all of them.
    fn brute_force(boxes: &[Aabb], gap: f64) -> Vec<NeighbourPair> {
        let mut out = Vec::new();
        for i in 0..boxes.len() {
            for j in i + 1..boxes.len() {
                if boxes[i]
                    .expanded(0.5 * gap)
                    .overlaps(&boxes[j].expanded(0.5 * gap))
                {
                    out.push(NeighbourPair::new(i as u32, j as u32));
                }
            }
        }
        out
    }

    /// A tall column of unit boxes on a base five times as wide as the column: the base
    /// makes the scene wider than tall, but the sweep goes along y, where the column's
    /// boxes overlap fewer others; laid out as a wide row, the same boxes are swept along
    /// x. The pairs are the same either way.
    #[test]
    fn sweeps_along_the_axis_where_intervals_overlap_least() {
        let unit = |x: f64, y: f64| Aabb {
            min: DVec2::new(x, y),
            max: DVec2::new(x + 1.0, y + 1.0),
        };
        let base = Aabb {
            min: DVec2::new(-20.0, -1.0),
            max: DVec2::new(30.0, 0.0),
        };
        let column: Vec<Aabb> = std::iter::once(base)
            .chain((0..200).map(|k| unit((k % 10) as f64 * 1.01, (k / 10) as f64 * 1.01)))
            .collect();
        let row: Vec<Aabb> = (0..200)
            .map(|k| unit((k / 10) as f64 * 1.01, (k % 10) as f64 * 1.01))
            .collect();
        let mut search = NeighbourSearch::new();
        let mut out = Vec::new();
        for (boxes, axis) in [(&row, 0), (&column, 1), (&row, 0)] {
            search.find(boxes, 0.02, &mut out);
            assert_eq!(search.axis, axis);
            assert_eq!(out, brute_force(boxes, 0.02));
            assert!(!out.is_empty());
        }
    }

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
