//! Per-block geometry cached for detection: vertices, unit edge directions, edge lengths,
//! centroid and bounding box, refreshed in place when blocks move.

use dda_geom::{Aabb, ConvexPolygon, DVec2};

/// A block's geometry as the detectors read it. Vertices run counter-clockwise; edge `i`
/// goes from vertex `i` to vertex `i + 1` with unit direction `tangents[i]`, outward
/// normal (t.y, -t.x) and length `lengths[i]`.
#[derive(Clone, Debug, PartialEq)]
pub struct BlockShape {
    /// Vertices, counter-clockwise.
    pub vertices: Vec<DVec2>,
    /// Unit direction of each edge.
    pub tangents: Vec<DVec2>,
    /// Length of each edge.
    pub lengths: Vec<f64>,
    /// Centroid: the reference point of the block's displacement function.
    pub centroid: DVec2,
    /// Bounding box.
    pub aabb: Aabb,
}

impl BlockShape {
    /// Caches the geometry of `poly`.
    pub fn new(poly: &ConvexPolygon) -> Self {
        let mut s = BlockShape {
            vertices: Vec::new(),
            tangents: Vec::new(),
            lengths: Vec::new(),
            centroid: DVec2::ZERO,
            aabb: poly.aabb(),
        };
        s.set(poly);
        s
    }

    /// The vertices (index, point) inside `other`'s box expanded by `tol`: the only ones
    /// that can be within `tol` of its edges, so the vertex-edge loops start from them.
    #[inline]
    pub fn vertices_near<'a>(
        &'a self,
        other: &BlockShape,
        tol: f64,
    ) -> impl Iterator<Item = (usize, DVec2)> + 'a {
        let reach = other.aabb.expanded(tol);
        self.vertices
            .iter()
            .copied()
            .enumerate()
            .filter(move |(_, a)| reach.contains(*a))
    }

    /// Refreshes the cache from `poly` (same vertex count or not), reusing the buffers.
    pub fn set(&mut self, poly: &ConvexPolygon) {
        let v = poly.vertices();
        let n = v.len();
        self.vertices.clear();
        self.vertices.extend_from_slice(v);
        self.tangents.clear();
        self.lengths.clear();
        for i in 0..n {
            let d = v[if i + 1 == n { 0 } else { i + 1 }] - v[i];
            let l = d.length();
            self.tangents.push(d / l);
            self.lengths.push(l);
        }
        self.centroid = poly.centroid();
        self.aabb = poly.aabb();
    }

    /// Number of vertices.
    #[inline]
    #[allow(clippy::len_without_is_empty)] // a block always has vertices
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    /// Index of the vertex after `i`.
    #[inline]
    pub fn next(&self, i: usize) -> usize {
        if i + 1 == self.vertices.len() {
            0
        } else {
            i + 1
        }
    }

    /// Index of the vertex before `i`.
    #[inline]
    pub fn prev(&self, i: usize) -> usize {
        if i == 0 {
            self.vertices.len() - 1
        } else {
            i - 1
        }
    }

    /// Outward unit normal of edge `i`.
    #[inline]
    pub fn normal(&self, i: usize) -> DVec2 {
        let t = self.tangents[i];
        DVec2::new(t.y, -t.x)
    }

    /// Unit vectors along the two edges at vertex `i`, pointing away from it: towards the
    /// previous vertex and towards the next (the e of the entrance filter, paper eq. 5-6).
    #[inline]
    pub fn vertex_edges(&self, i: usize) -> (DVec2, DVec2) {
        (-self.tangents[self.prev(i)], self.tangents[i])
    }
}
