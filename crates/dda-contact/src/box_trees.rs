//! Trees of bounding boxes over the blocks, for two questions a scan of every block
//! answers in time N each:
//! - the nearest other box to a box ([`BoxTrees::nearest_gap`]), asked once a step for
//!   each block in flight (a scan cost N times the blocks in flight a step: a rockfall of
//!   thousands of blocks spent more time there than in the rest of its steps);
//! - the boxes holding a point ([`BoxTrees::containing`]), asked for each measured point
//!   and bolt end of a scene.
//!
//! The answers are exact: the smallest [`Aabb::gap`] over every other box in the trees,
//! the same number a scan of them all would give, whatever their order; every box that
//! holds the point.
//!
//! The boxes are split by size into classes a factor [`CLASS_RATIO`] apart, one tree
//! each: a box far larger than its neighbours (a fixed floor under a rockfall, a wall
//! beside a mass) would otherwise widen every node it falls in, along a whole branch of
//! the tree, and the queries near it would visit most of that branch.

use dda_geom::{Aabb, DVec2};

/// Boxes in a leaf at most.
const LEAF: usize = 4;

/// The ratio of sizes (a box's longer side) from one class to the next.
pub const CLASS_RATIO: f64 = 8.0;

/// Classes at most; boxes larger still join the last.
const CLASSES: usize = 32;

/// A node of a tree: the box holding its boxes, and either two children or a run of
/// `order`.
#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    /// Children `first` and `first + 1` when `count` is 0, else the first of `count`
    /// entries of `order`.
    first: u32,
    count: u32,
}

/// Trees of bounding boxes, one a size class, for nearest-box and point queries
/// ([`BoxTrees::nearest_gap`], [`BoxTrees::containing`]). Their buffers are kept from
/// one build to the next.
#[derive(Clone, Debug, Default)]
pub struct BoxTrees {
    /// Every tree's nodes; a parent's children are two consecutive nodes.
    nodes: Vec<Node>,
    /// The root node of each class's tree.
    roots: Vec<u32>,
    /// Box indices, by class, each leaf's a contiguous run.
    order: Vec<u32>,
    /// The centres of the boxes, by index, while building.
    centres: Vec<[f64; 2]>,
    /// The size class of each box, by index, while building.
    class: Vec<u8>,
    /// The nodes still to visit in a query, with the least gap a box in them can have.
    stack: Vec<(f64, u32)>,
}

impl BoxTrees {
    /// No trees.
    pub fn new() -> Self {
        Self::default()
    }

    /// Builds the trees over the boxes `i` of `boxes` for which `include(i)`. Median
    /// splits along the longer side of each node's box, ties broken by index, so the
    /// same boxes give the same trees.
    pub fn build(&mut self, boxes: &[Aabb], include: impl Fn(usize) -> bool) {
        self.nodes.clear();
        self.roots.clear();
        self.order.clear();
        self.order
            .extend((0..boxes.len()).filter(|&i| include(i)).map(|i| i as u32));
        self.centres.clear();
        self.centres.extend(boxes.iter().map(|b| {
            let c = (b.min + b.max) * 0.5;
            [c.x, c.y]
        }));
        let side = |b: &Aabb| {
            let s = b.size();
            s.x.max(s.y)
        };
        let smallest = self
            .order
            .iter()
            .map(|&i| side(&boxes[i as usize]))
            .filter(|s| *s > 0.0 && s.is_finite())
            .fold(f64::INFINITY, f64::min);
        self.class.clear();
        self.class.extend(boxes.iter().map(|b| {
            let ratio = side(b) / smallest;
            if ratio > 1.0 && ratio.is_finite() {
                (ratio.log2() / CLASS_RATIO.log2()).min((CLASSES - 1) as f64) as u8
            } else {
                0
            }
        }));
        let class = &self.class;
        self.order.sort_unstable_by_key(|&i| (class[i as usize], i));
        let mut todo = Vec::new();
        let mut start = 0;
        while start < self.order.len() {
            let c = class[self.order[start] as usize];
            let len = self.order[start..]
                .iter()
                .take_while(|&&i| class[i as usize] == c)
                .count();
            self.roots.push(self.nodes.len() as u32);
            todo.push(self.nodes.len());
            self.nodes.push(Node {
                bounds: bounds_of(boxes, &self.order[start..start + len]),
                first: start as u32,
                count: len as u32,
            });
            start += len;
        }
        while let Some(k) = todo.pop() {
            let Node {
                bounds,
                first,
                count,
            } = self.nodes[k];
            let (first, count) = (first as usize, count as usize);
            if count <= LEAF {
                continue;
            }
            let size = bounds.size();
            let axis = usize::from(size.y > size.x);
            let run = &mut self.order[first..first + count];
            let half = count / 2;
            let centres = &self.centres;
            run.select_nth_unstable_by(half, |&a, &b| {
                centres[a as usize][axis]
                    .total_cmp(&centres[b as usize][axis])
                    .then(a.cmp(&b))
            });
            let left = self.nodes.len();
            for (start, len) in [(first, half), (first + half, count - half)] {
                self.nodes.push(Node {
                    bounds: bounds_of(boxes, &self.order[start..start + len]),
                    first: start as u32,
                    count: len as u32,
                });
            }
            self.nodes[k] = Node {
                bounds,
                first: left as u32,
                count: 0,
            };
            todo.push(left);
            todo.push(left + 1);
        }
    }

    /// The smallest [`Aabb::gap`] between `boxes[i]` and the other boxes of the trees
    /// (`boxes` as built), infinite if there is none. A node is passed over where the
    /// larger of its [`Aabb::axis_gaps`] to the box is already no less than the nearest
    /// found: every box inside it is at least that far along that axis, and so at least
    /// that far, which keeps the answer exact.
    pub fn nearest_gap(&mut self, boxes: &[Aabb], i: usize) -> f64 {
        let own = boxes[i];
        let bound = |node: &Node| {
            let d = own.axis_gaps(&node.bounds);
            d.x.max(d.y)
        };
        let mut best = f64::INFINITY;
        self.stack.clear();
        // The roots, the nearest last, to be visited first.
        self.stack.extend(
            self.roots
                .iter()
                .map(|&r| (bound(&self.nodes[r as usize]), r)),
        );
        self.stack
            .sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(b.1.cmp(&a.1)));
        while let Some((lower, k)) = self.stack.pop() {
            if lower >= best {
                continue;
            }
            let node = self.nodes[k as usize];
            if node.count > 0 {
                let (first, count) = (node.first as usize, node.count as usize);
                for &j in &self.order[first..first + count] {
                    // The gap (`Aabb::gap`, d's length) is at least the larger axis
                    // gap: no nearer where that is not.
                    let d = own.axis_gaps(&boxes[j as usize]);
                    if j as usize != i && d.x.max(d.y) < best {
                        best = best.min(d.x.hypot(d.y));
                    }
                }
                continue;
            }
            let (a, b) = (node.first, node.first + 1);
            let (la, lb) = (
                bound(&self.nodes[a as usize]),
                bound(&self.nodes[b as usize]),
            );
            // The nearer child is visited first (pushed last).
            if la <= lb {
                self.stack.push((lb, b));
                self.stack.push((la, a));
            } else {
                self.stack.push((la, a));
                self.stack.push((lb, b));
            }
        }
        best
    }

    /// The indices of the boxes of the trees (`boxes` as built) that hold `p`, their
    /// boundary included, in `out` (cleared first), in increasing order.
    pub fn containing(&mut self, boxes: &[Aabb], p: DVec2, out: &mut Vec<u32>) {
        out.clear();
        self.stack.clear();
        self.stack.extend(self.roots.iter().map(|&r| (0.0, r)));
        while let Some((_, k)) = self.stack.pop() {
            let node = self.nodes[k as usize];
            if !node.bounds.contains(p) {
                continue;
            }
            if node.count > 0 {
                let (first, count) = (node.first as usize, node.count as usize);
                out.extend(
                    (self.order[first..first + count].iter())
                        .filter(|&&j| boxes[j as usize].contains(p)),
                );
            } else {
                self.stack.push((0.0, node.first));
                self.stack.push((0.0, node.first + 1));
            }
        }
        out.sort_unstable();
    }
}

/// The box holding the boxes `run` of `boxes` (an inverted empty box for none).
fn bounds_of(boxes: &[Aabb], run: &[u32]) -> Aabb {
    run.iter()
        .map(|&j| boxes[j as usize])
        .reduce(|a, b| a.union(&b))
        .unwrap_or_else(|| Aabb::from_points(&[]))
}

#[cfg(test)]
mod tests {
    use super::BoxTrees;
    use dda_geom::{Aabb, DVec2};
    use proptest::prelude::*;

    /// The nearest gap by a scan of every other included box, as the engine took it
    /// before the tree.
    fn scan(boxes: &[Aabb], include: &[bool], i: usize) -> f64 {
        boxes
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != i && include[j])
            .map(|(_, b)| boxes[i].gap(b))
            .fold(f64::INFINITY, f64::min)
    }

    fn boxes_strategy() -> impl Strategy<Value = Vec<(Aabb, bool)>> {
        // A cluster of small boxes, some touching or overlapping, a few far away (debris
        // thrown clear of a mass), a few a hundred times larger (floors and walls, in
        // other size classes), some left out of the trees.
        let b = (
            prop_oneof![3 => -5.0..5.0f64, 1 => -1e4..1e4f64],
            prop_oneof![3 => -5.0..5.0f64, 1 => -1e4..1e4f64],
            prop_oneof![4 => 0.0..2.0f64, 1 => 0.0..200.0f64],
            prop_oneof![4 => 0.0..2.0f64, 1 => 0.0..200.0f64],
            prop::bool::weighted(0.9),
        );
        prop::collection::vec(b, 1..120).prop_map(|v| {
            v.into_iter()
                .map(|(x, y, w, h, inc)| {
                    // Snapped to a grid of 1/8 so that boxes touch and tie exactly.
                    let s = |v: f64| (v * 8.0).round() / 8.0;
                    let min = DVec2::new(s(x), s(y));
                    (
                        Aabb {
                            min,
                            max: min + DVec2::new(s(w), s(h)),
                        },
                        inc,
                    )
                })
                .collect()
        })
    }

    proptest! {
        #![proptest_config(dda_geom::test_support::config(256))]
        /// Every box's nearest gap is the scan's, to the bit, whether or not the box is
        /// itself in the tree.
        #[test]
        fn the_tree_finds_the_scan_s_nearest_gap(v in boxes_strategy()) {
            let boxes: Vec<Aabb> = v.iter().map(|p| p.0).collect();
            let include: Vec<bool> = v.iter().map(|p| p.1).collect();
            let mut tree = BoxTrees::new();
            tree.build(&boxes, |j| include[j]);
            for i in 0..boxes.len() {
                let want = scan(&boxes, &include, i);
                let got = tree.nearest_gap(&boxes, i);
                prop_assert_eq!(got.to_bits(), want.to_bits(), "box {}", i);
            }
        }
    }

    proptest! {
        #![proptest_config(dda_geom::test_support::config(256))]
        /// The boxes holding a point are those a scan finds, in increasing order: for
        /// the corners and centres of the boxes (on their boundaries, and inside) and
        /// points between them.
        #[test]
        fn the_trees_find_the_boxes_holding_a_point(
            v in boxes_strategy(),
            extra in prop::collection::vec((-10.0..10.0f64, -10.0..10.0f64), 0..20),
        ) {
            let boxes: Vec<Aabb> = v.iter().map(|p| p.0).collect();
            let include: Vec<bool> = v.iter().map(|p| p.1).collect();
            let mut tree = BoxTrees::new();
            tree.build(&boxes, |j| include[j]);
            let points = (boxes.iter())
                .flat_map(|b| [b.min, b.max, (b.min + b.max) * 0.5])
                .chain(extra.iter().map(|&(x, y)| DVec2::new(x, y)));
            let mut got = Vec::new();
            for p in points {
                tree.containing(&boxes, p, &mut got);
                let want: Vec<u32> = (0..boxes.len())
                    .filter(|&j| include[j] && boxes[j].contains(p))
                    .map(|j| j as u32)
                    .collect();
                prop_assert_eq!(&got, &want, "point {:?}", p);
            }
        }
    }

    /// With no other box the gap is infinite, as a scan's fold gives.
    #[test]
    fn a_box_alone_has_no_nearest() {
        let b = Aabb {
            min: DVec2::ZERO,
            max: DVec2::ONE,
        };
        let mut tree = BoxTrees::new();
        tree.build(&[b], |_| true);
        assert_eq!(tree.nearest_gap(&[b], 0), f64::INFINITY);
        tree.build(&[b, b], |j| j == 0);
        assert_eq!(tree.nearest_gap(&[b, b], 1), 0.0);
        assert_eq!(tree.nearest_gap(&[b, b], 0), f64::INFINITY);
    }
}
