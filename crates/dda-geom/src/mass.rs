//! Rock masses: a simple outline (convex or not) cut by joints, persistent or not, into
//! pieces of rock. The detectors take convex blocks, so a piece that is not convex (an
//! outline's re-entrant corner, a joint that ends inside the rock) is carried as convex
//! parts glued along the faces where the rock is intact.
//!
//! The cutting, in [`cut_mass`]:
//! 1. the outline is split into convex parts (ear clipping, then Hertel-Mehlhorn: a
//!    diagonal is removed wherever the two parts beside it make a convex one);
//! 2. each joint splits every part its trace crosses, along its whole line through that
//!    part;
//! 3. where a trace ends inside the rock, the parts whose face runs through its end are
//!    split across the joint there, so that every shared face is either all joint or all
//!    intact rock;
//! 4. parts sharing a face of intact rock (a diagonal, a bridge between traces, a cut
//!    across a trace's end) are glued, and glued parts whose union is convex are merged;
//! 5. the pieces are the groups of glued parts; pieces below the sliver area are dropped.
//!
//! Every step is deterministic: the same outline and joints give the same pieces in the
//! same order.

use crate::cut::{Line, labelled_piece, split_ring};
use crate::error::{JointSetError, PolygonError};
use crate::polygon::{ConvexPolygon, DEFAULT_REL_TOL};
use crate::{Aabb, Groups, JointSet};
use glam::DVec2;

fn cross(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// A simple polygon, counter-clockwise, convex or not: the outline of a rock mass. One
/// that exists has at least three vertices, all finite, no two consecutive ones closer
/// than [`DEFAULT_REL_TOL`] of its size, none on the line through its neighbours, and no
/// edge touching or crossing another.
#[derive(Clone, Debug, PartialEq)]
pub struct Outline {
    vertices: Vec<DVec2>,
}

impl Outline {
    /// Validates `vertices` strictly: clockwise order, repeated or collinear vertices and
    /// crossing or touching edges are errors naming the vertex or edges, not repaired.
    pub fn new(vertices: Vec<DVec2>) -> Result<Self, PolygonError> {
        let n = vertices.len();
        if n < 3 {
            return Err(PolygonError::TooFewVertices { count: n });
        }
        if let Some(i) = vertices.iter().position(|v| !v.is_finite()) {
            return Err(PolygonError::NonFinite { vertex: i });
        }
        let eps = DEFAULT_REL_TOL * Aabb::from_points(&vertices).size().length();
        for i in 0..n {
            let j = (i + 1) % n;
            if vertices[i].distance(vertices[j]) <= eps {
                let (vertex, of) = if j == 0 { (i, 0) } else { (j, i) };
                return Err(PolygonError::DuplicateVertex { vertex, of });
            }
        }
        for i in 0..n {
            for j in (i + 2)..n {
                if vertices[i].distance(vertices[j]) <= eps {
                    return Err(PolygonError::DuplicateVertex { vertex: j, of: i });
                }
            }
        }
        for i in 0..n {
            let (p, v, q) = (
                vertices[(i + n - 1) % n],
                vertices[i],
                vertices[(i + 1) % n],
            );
            let chord = q - p;
            if cross(v - p, chord).abs() <= eps * chord.length() {
                return Err(PolygonError::CollinearVertex { vertex: i });
            }
        }
        // Edges that cross, or a vertex touching an edge it does not end.
        for a in 0..n {
            let (p0, p1) = (vertices[a], vertices[(a + 1) % n]);
            for b in (a + 1)..n {
                if b == a + 1 || (a == 0 && b == n - 1) {
                    continue;
                }
                let (q0, q1) = (vertices[b], vertices[(b + 1) % n]);
                if segments_meet(p0, p1, q0, q1, eps) {
                    return Err(PolygonError::SelfIntersecting {
                        edge_a: a,
                        edge_b: b,
                    });
                }
            }
        }
        let outline = Outline { vertices };
        if outline.twice_area() <= 0.0 {
            return Err(PolygonError::Clockwise);
        }
        Ok(outline)
    }

    /// The vertices, counter-clockwise.
    pub fn vertices(&self) -> &[DVec2] {
        &self.vertices
    }

    fn twice_area(&self) -> f64 {
        let o = self.vertices[0];
        let n = self.vertices.len();
        (0..n)
            .map(|i| cross(self.vertices[i] - o, self.vertices[(i + 1) % n] - o))
            .sum()
    }

    /// Enclosed area.
    pub fn area(&self) -> f64 {
        0.5 * self.twice_area()
    }

    /// Bounding box.
    pub fn aabb(&self) -> Aabb {
        Aabb::from_points(&self.vertices)
    }

    /// The vertex at which the outline turns clockwise (a re-entrant corner), if any.
    pub fn reflex_vertex(&self) -> Option<usize> {
        let v = &self.vertices;
        let n = v.len();
        (0..n).find(|&i| cross(v[i] - v[(i + n - 1) % n], v[(i + 1) % n] - v[i]) < 0.0)
    }

    /// Whether `p` lies inside (boundary excluded up to rounding), by the crossing number.
    pub fn contains(&self, p: DVec2) -> bool {
        let v = &self.vertices;
        let n = v.len();
        let mut inside = false;
        for i in 0..n {
            let (a, b) = (v[i], v[(i + 1) % n]);
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if p.x < x {
                    inside = !inside;
                }
            }
        }
        inside
    }

    /// The outline split into convex parts, as lists of vertex indices (counter-clockwise):
    /// ear clipping into triangles, then every diagonal removed whose two sides make a
    /// convex part (Hertel-Mehlhorn: at most four times the fewest parts possible).
    pub fn convex_parts(&self) -> Vec<Vec<usize>> {
        let v = &self.vertices;
        let n = v.len();
        if self.reflex_vertex().is_none() {
            return vec![(0..n).collect()];
        }
        let triangles = ear_clip(v);
        // Merge across diagonals, in the order the triangles were cut.
        let mut parts: Vec<Option<Vec<usize>>> = triangles.into_iter().map(Some).collect();
        let mut merged = true;
        while merged {
            merged = false;
            for a in 0..parts.len() {
                for b in (a + 1)..parts.len() {
                    let (Some(pa), Some(pb)) = (&parts[a], &parts[b]) else {
                        continue;
                    };
                    if let Some(union) = merge_convex(v, pa, pb) {
                        parts[a] = Some(union);
                        parts[b] = None;
                        merged = true;
                    }
                }
            }
        }
        parts.into_iter().flatten().collect()
    }
}

/// Whether the closed segments p0-p1 and q0-q1 cross or come within `eps` of each other.
fn segments_meet(p0: DVec2, p1: DVec2, q0: DVec2, q1: DVec2, eps: f64) -> bool {
    let d1 = cross(p1 - p0, q0 - p0);
    let d2 = cross(p1 - p0, q1 - p0);
    let d3 = cross(q1 - q0, p0 - q0);
    let d4 = cross(q1 - q0, p1 - q0);
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    point_segment_distance(q0, p0, p1) <= eps
        || point_segment_distance(q1, p0, p1) <= eps
        || point_segment_distance(p0, q0, q1) <= eps
        || point_segment_distance(p1, q0, q1) <= eps
}

fn point_segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    p.distance(a + t * ab)
}

/// Triangles of a simple counter-clockwise polygon by ear clipping, as index triples.
fn ear_clip(v: &[DVec2]) -> Vec<Vec<usize>> {
    let mut ring: Vec<usize> = (0..v.len()).collect();
    let mut out = Vec::with_capacity(v.len() - 2);
    let convex = |ring: &[usize], k: usize| {
        let m = ring.len();
        let (a, b, c) = (v[ring[(k + m - 1) % m]], v[ring[k]], v[ring[(k + 1) % m]]);
        cross(b - a, c - b) > 0.0
    };
    let mut k = 0;
    let mut misses = 0;
    while ring.len() > 3 {
        let m = ring.len();
        let (ia, ib, ic) = (ring[(k + m - 1) % m], ring[k % m], ring[(k + 1) % m]);
        let is_ear = convex(&ring, k % m)
            && ring.iter().all(|&j| {
                if j == ia || j == ib || j == ic {
                    return true;
                }
                !in_triangle(v[j], v[ia], v[ib], v[ic])
            });
        if is_ear || misses > m {
            // An outline that validated always has an ear; `misses` only guards rounding.
            out.push(vec![ia, ib, ic]);
            ring.remove(k % m);
            misses = 0;
            k %= ring.len();
        } else {
            k = (k + 1) % m;
            misses += 1;
        }
    }
    out.push(ring);
    out
}

/// Whether `p` lies in the closed triangle a, b, c (counter-clockwise).
fn in_triangle(p: DVec2, a: DVec2, b: DVec2, c: DVec2) -> bool {
    cross(b - a, p - a) >= 0.0 && cross(c - b, p - b) >= 0.0 && cross(a - c, p - c) >= 0.0
}

/// The union of two convex index polygons that share an edge (a diagonal), if it is
/// convex at both ends of that edge.
fn merge_convex(v: &[DVec2], a: &[usize], b: &[usize]) -> Option<Vec<usize>> {
    let (na, nb) = (a.len(), b.len());
    for i in 0..na {
        let (p, q) = (a[i], a[(i + 1) % na]);
        let Some(j) = (0..nb).find(|&j| b[j] == q && b[(j + 1) % nb] == p) else {
            continue;
        };
        // a: ... p q ...; b: ... q p ...: the union walks a from q round to p, then b
        // from p round to q.
        let mut ring = Vec::with_capacity(na + nb - 2);
        for k in 0..na {
            ring.push(a[(i + 1 + k) % na]);
        }
        for k in 1..nb - 1 {
            ring.push(b[(j + 1 + k) % nb]);
        }
        let m = ring.len();
        let ok = (0..m).all(|k| {
            let (x, y, z) = (v[ring[(k + m - 1) % m]], v[ring[k]], v[ring[(k + 1) % m]]);
            cross(y - x, z - y) > 0.0
        });
        return ok.then_some(ring);
    }
    None
}

/// A joint of a rock mass: a line and, unless it is persistent, the stretches of it that
/// are open joint (its traces); between them the rock is intact (rock bridges).
#[derive(Clone, Debug, PartialEq)]
pub struct Joint {
    /// The joint's line.
    pub line: Line,
    /// The joint set it belongs to (an index the caller gives).
    pub set: usize,
    /// `None`: the joint crosses everything (persistent). Otherwise its traces as
    /// intervals `[t0, t1]` (ascending, disjoint) of the position `t = x . d` along the
    /// line, `d = (normal.y, -normal.x)`.
    pub traces: Option<Vec<[f64; 2]>>,
}

impl Joint {
    /// The line's direction d, along which trace positions are measured.
    pub fn direction(&self) -> DVec2 {
        self.line.direction()
    }

    /// Whether the stretch `[t0, t1]` of the line overlaps a trace by more than `eps`.
    fn trace_overlaps(&self, t0: f64, t1: f64, eps: f64) -> bool {
        match &self.traces {
            None => t1 - t0 > eps,
            Some(tr) => tr.iter().any(|&[a, b]| b.min(t1) - a.max(t0) > eps),
        }
    }

    /// Whether the point at `t` lies on a trace.
    fn on_trace(&self, t: f64) -> bool {
        match &self.traces {
            None => true,
            Some(tr) => tr.iter().any(|&[a, b]| a <= t && t <= b),
        }
    }
}

/// A joint set with its statistics: spacing varying about its mean (coefficient of
/// variation `spacing_cv`, uniform), each joint's dip within `dip_spread_deg` of the
/// mean (uniform), and joints that are not persistent: traces of `trace_length` with rock
/// bridges of `bridge` between them, starting at a random point along each joint. All
/// drawn from `seed`, so the same family gives the same joints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointFamily {
    /// Mean dip, spacing and the offset of one joint.
    pub set: JointSet,
    /// Coefficient of variation of the spacing, 0 to 0.5 (0: regular).
    pub spacing_cv: f64,
    /// Largest deviation of a joint's dip from the mean, degrees (0: parallel).
    pub dip_spread_deg: f64,
    /// Trace length and bridge length, m (`None`: persistent).
    pub trace: Option<(f64, f64)>,
    /// The point from which the traces' random start is measured along each joint (the
    /// origin; a point the set is placed through, so that the traces move with it).
    pub trace_origin: DVec2,
    /// Seed of the draws.
    pub seed: u64,
}

impl JointFamily {
    /// A regular family of persistent, parallel joints.
    pub fn regular(set: JointSet) -> Self {
        JointFamily {
            set,
            spacing_cv: 0.0,
            dip_spread_deg: 0.0,
            trace: None,
            trace_origin: DVec2::ZERO,
            seed: 0,
        }
    }

    /// The family's joints that may cross `bounds`, in ascending position along the
    /// normal, tagged with `set`. A regular family's are the lines `offset + k spacing`.
    /// At most `max` joints and `max` traces are made (an error beyond: a spacing or a
    /// trace length in the wrong unit).
    pub fn joints(
        &self,
        set: usize,
        bounds: &Aabb,
        max: usize,
    ) -> Result<Vec<Joint>, JointSetError> {
        let s = &self.set;
        if !(s.dip_deg.is_finite() && s.offset.is_finite()) {
            return Err(JointSetError::NonFinite { set });
        }
        if !(s.spacing.is_finite() && s.spacing > 0.0) {
            return Err(JointSetError::Spacing {
                set,
                spacing: s.spacing,
            });
        }
        let normal = s.normal();
        let corners = [
            bounds.min,
            bounds.max,
            DVec2::new(bounds.min.x, bounds.max.y),
            DVec2::new(bounds.max.x, bounds.min.y),
        ];
        let along = |n: DVec2| {
            corners
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), c| {
                    (lo.min(n.dot(*c)), hi.max(n.dot(*c)))
                })
        };
        let (mut lo, mut hi) = along(normal);
        let spread = self.dip_spread_deg.to_radians();
        // A joint turned by up to `spread` about the box's centre line may cross the box
        // from a little further out.
        let margin = bounds.size().length() * spread.sin();
        lo -= margin;
        hi += margin;
        if (hi - lo) / s.spacing > max as f64 * (1.0 + 2.0 * self.spacing_cv) + 2.0 {
            return Err(JointSetError::TooMany { set, max });
        }
        let mut rng = SplitMix64(self.seed);
        let gap = |rng: &mut SplitMix64| {
            s.spacing * (1.0 + 3f64.sqrt() * self.spacing_cv * rng.symmetric())
        };
        let mut positions = Vec::new();
        if self.spacing_cv == 0.0 {
            let first = ((lo - s.offset) / s.spacing).ceil() as i64;
            let last = ((hi - s.offset) / s.spacing).floor() as i64;
            positions.extend((first..=last).map(|k| s.offset + k as f64 * s.spacing));
        } else {
            let mut p = s.offset;
            while p <= hi {
                if p >= lo {
                    positions.push(p);
                }
                p += gap(&mut rng);
            }
            let mut p = s.offset - gap(&mut rng);
            let mut down = Vec::new();
            while p >= lo {
                if p <= hi {
                    down.push(p);
                }
                p -= gap(&mut rng);
            }
            down.reverse();
            down.extend(positions);
            positions = down;
        }
        if positions.len() > max {
            return Err(JointSetError::TooMany { set, max });
        }
        let centre = 0.5 * (bounds.min + bounds.max);
        let mut out = Vec::with_capacity(positions.len());
        let mut traces_made = 0usize;
        for p in positions {
            let line = if spread > 0.0 {
                let turn = spread * rng.symmetric();
                let through = centre + (p - normal.dot(centre)) * normal;
                let n = DVec2::from_angle(turn).rotate(normal);
                Line {
                    normal: n,
                    offset: n.dot(through),
                }
            } else {
                Line { normal, offset: p }
            };
            let traces = self.trace.map(|(length, bridge)| {
                let d = line.direction();
                let (t_lo, t_hi) = along(d);
                let period = length + bridge;
                let phase = d.dot(self.trace_origin) + period * 0.5 * (1.0 + rng.symmetric());
                let first = ((t_lo - phase - length) / period).floor();
                let last = ((t_hi - phase) / period).ceil();
                let count = (last - first + 1.0).max(0.0);
                if !count.is_finite() || traces_made as f64 + count > max as f64 {
                    return Err(JointSetError::TooMany { set, max });
                }
                let (first, last) = (first as i64, last as i64);
                traces_made += count as usize;
                Ok((first..=last)
                    .map(|k| {
                        let a = phase + k as f64 * period;
                        [a, a + length]
                    })
                    .collect())
            });
            let traces = traces.transpose()?;
            out.push(Joint { line, set, traces });
        }
        Ok(out)
    }
}

/// SplitMix64: a small, fixed generator, so that a scene's joints never change with a
/// dependency's version.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [-1, 1).
    fn symmetric(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

/// What an edge of a part lies on: the outline, a joint's line (by index), a diagonal
/// of the outline's convex split, or a cut across a trace's end.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Face {
    Outline,
    Joint(usize),
    Diagonal,
    Tip,
}

/// One piece of rock: convex parts glued along intact rock (one part if the piece is
/// convex), and for each part's edge the joint set of the trace it lies on, if any.
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    /// The convex parts.
    pub parts: Vec<ConvexPolygon>,
    /// For each part, for each edge (from vertex i to i + 1): the set of the joint trace
    /// it lies on.
    pub edge_sets: Vec<Vec<Option<usize>>>,
}

impl Piece {
    /// Area of the piece.
    pub fn area(&self) -> f64 {
        self.parts.iter().map(ConvexPolygon::area).sum()
    }
}

/// The pieces a rock mass was cut into, and the slivers dropped.
#[derive(Clone, Debug, PartialEq)]
pub struct MassCutting {
    /// The pieces, in a deterministic order.
    pub pieces: Vec<Piece>,
    /// How many pieces were below the sliver area and dropped.
    pub dropped: usize,
    /// Their total area.
    pub dropped_area: f64,
}

/// A part during the cutting: its polygon and what each edge lies on.
struct Cell {
    poly: ConvexPolygon,
    faces: Vec<Face>,
}

/// Cuts `outline` by `joints` into pieces (see the module docs); pieces with area below
/// `min_area` are dropped and counted. Every part is convex and counter-clockwise, the
/// parts tile the outline, and parts of different pieces meet only along joint traces.
pub fn cut_mass(
    outline: &Outline,
    joints: &[Joint],
    min_area: f64,
) -> Result<MassCutting, JointSetError> {
    if !(min_area.is_finite() && min_area >= 0.0) {
        return Err(JointSetError::MinArea { min_area });
    }
    let v = outline.vertices();
    let size = outline.aabb().size().length();
    let eps = DEFAULT_REL_TOL * size;
    let mut cells = Vec::new();
    for part in outline.convex_parts() {
        let pts: Vec<DVec2> = part.iter().map(|&i| v[i]).collect();
        let m = part.len();
        let faces = (0..m)
            .map(|k| {
                let (a, b) = (part[k], part[(k + 1) % m]);
                if b == (a + 1) % v.len() {
                    Face::Outline
                } else {
                    Face::Diagonal
                }
            })
            .collect();
        let piece = labelled_piece(pts, faces, eps)
            .map_err(|error| JointSetError::Piece { set: 0, error })?;
        if let Some((poly, faces)) = piece {
            cells.push(Cell { poly, faces });
        }
    }
    // 2. Each joint splits the parts its trace crosses.
    for (index, joint) in joints.iter().enumerate() {
        let line = &joint.line;
        if !(line.normal.is_finite() && line.offset.is_finite()) {
            return Err(JointSetError::NonFinite { set: joint.set });
        }
        let mut next = Vec::with_capacity(cells.len() + 8);
        for cell in cells.drain(..) {
            let (lo, hi) = cell.poly.extent(line.normal);
            let crosses = lo < line.offset
                && hi > line.offset
                && (joint.traces.is_none()
                    || chord(&cell.poly, line)
                        .is_some_and(|(t0, t1)| joint.trace_overlaps(t0, t1, eps)));
            if !crosses {
                next.push(cell);
                continue;
            }
            split_cell(cell, line, Face::Joint(index), eps, &mut next).map_err(|error| {
                JointSetError::Piece {
                    set: joint.set,
                    error,
                }
            })?;
        }
        cells = next;
    }
    // 3. Cuts across the joint at each trace end lying within a part's face, part by
    // part (each part is split at the first such end, and its pieces looked at again).
    let tips: Vec<Vec<f64>> = joints
        .iter()
        .map(|j| {
            let mut t: Vec<f64> = j
                .traces
                .iter()
                .flatten()
                .flat_map(|&[a, b]| [a, b])
                .collect();
            t.sort_by(f64::total_cmp);
            t
        })
        .collect();
    let mut stack: Vec<Cell> = cells.drain(..).rev().collect();
    while let Some(cell) = stack.pop() {
        let Some((j, t)) = first_tip_inside(&cell, joints, &tips, eps) else {
            cells.push(cell);
            continue;
        };
        let across = Line {
            normal: joints[j].direction(),
            offset: t,
        };
        let mut pieces = Vec::with_capacity(2);
        let copy = Cell {
            poly: cell.poly.clone(),
            faces: cell.faces.clone(),
        };
        split_cell(cell, &across, Face::Tip, eps, &mut pieces).map_err(|error| {
            JointSetError::Piece {
                set: joints[j].set,
                error,
            }
        })?;
        if pieces.len() < 2 {
            // Rounding left no second piece: the end is at a corner after all.
            cells.push(copy);
            continue;
        }
        stack.extend(pieces.into_iter().rev());
    }
    // 4. Glue across intact faces; merge glued parts whose union is convex.
    let mut glue = glued_pairs(&cells, joints, eps);
    loop {
        let mut merged_any = false;
        let mut alive = vec![true; cells.len()];
        let mut replaced: Vec<Option<Cell>> = (0..cells.len()).map(|_| None).collect();
        for &(a, b, ea, eb) in &glue {
            if !(alive[a] && alive[b]) {
                continue;
            }
            if let Some(union) = merge_cells(&cells[a], ea, &cells[b], eb, joints, eps) {
                alive[a] = false;
                alive[b] = false;
                replaced[a] = Some(union);
                merged_any = true;
            }
        }
        if !merged_any {
            break;
        }
        let old = std::mem::take(&mut cells);
        for (k, c) in old.into_iter().enumerate() {
            if let Some(u) = replaced[k].take() {
                cells.push(u);
            } else if alive[k] {
                cells.push(c);
            }
        }
        glue = glued_pairs(&cells, joints, eps);
    }
    // 5. Pieces: groups of glued parts, in the order of their first part.
    let mut root = Groups::new(cells.len());
    for &(a, b, _, _) in &glue {
        root.join(a, b);
    }
    let mut groups: Vec<Vec<usize>> = Vec::new();
    let mut group_of = vec![usize::MAX; cells.len()];
    for k in 0..cells.len() {
        let r = root.of(k);
        if group_of[r] == usize::MAX {
            group_of[r] = groups.len();
            groups.push(Vec::new());
        }
        groups[group_of[r]].push(k);
    }
    let mut out = MassCutting {
        pieces: Vec::with_capacity(groups.len()),
        dropped: 0,
        dropped_area: 0.0,
    };
    for g in groups {
        let piece = Piece {
            parts: g.iter().map(|&k| cells[k].poly.clone()).collect(),
            edge_sets: g
                .iter()
                .map(|&k| edge_sets(&cells[k], joints, eps))
                .collect(),
        };
        let area = piece.area();
        if area < min_area {
            out.dropped += 1;
            out.dropped_area += area;
        } else {
            out.pieces.push(piece);
        }
    }
    Ok(out)
}

/// Splits `cell` by `line`, the new edges labelled `face`, pushing the sides with area.
fn split_cell(
    cell: Cell,
    line: &Line,
    face: Face,
    eps: f64,
    out: &mut Vec<Cell>,
) -> Result<(), PolygonError> {
    let (sides, has_below, has_above) = split_ring(cell.poly.vertices(), &cell.faces, line, face);
    for ((pts, faces), present) in sides.into_iter().zip([has_below, has_above]) {
        if !present {
            continue;
        }
        if let Some((poly, faces)) = labelled_piece(pts, faces, eps)? {
            out.push(Cell { poly, faces });
        }
    }
    Ok(())
}

/// The positions `t = x . d` where `line` enters and leaves the convex polygon, if it
/// crosses it.
fn chord(poly: &ConvexPolygon, line: &Line) -> Option<(f64, f64)> {
    let d = line.direction();
    let v = poly.vertices();
    let n = v.len();
    let mut ts = Vec::with_capacity(2);
    for i in 0..n {
        let (a, b) = (v[i], v[(i + 1) % n]);
        let (sa, sb) = (
            line.normal.dot(a) - line.offset,
            line.normal.dot(b) - line.offset,
        );
        if (sa <= 0.0 && sb > 0.0) || (sa > 0.0 && sb <= 0.0) {
            let x = a + (b - a) * (sa / (sa - sb));
            ts.push(d.dot(x));
        }
    }
    (ts.len() >= 2).then(|| {
        let lo = ts.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = ts.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (lo, hi)
    })
}

/// The first trace end (joint, position along it) lying inside (more than `eps` from
/// either end of) an edge of `cell` made by that joint.
fn first_tip_inside(
    cell: &Cell,
    joints: &[Joint],
    tips: &[Vec<f64>],
    eps: f64,
) -> Option<(usize, f64)> {
    let v = cell.poly.vertices();
    let n = v.len();
    (0..n).find_map(|i| {
        let Face::Joint(j) = cell.faces[i] else {
            return None;
        };
        let d = joints[j].direction();
        let (ta, tb) = (d.dot(v[i]), d.dot(v[(i + 1) % n]));
        let (lo, hi) = (ta.min(tb) + eps, ta.max(tb) - eps);
        let t = &tips[j];
        let k = t.partition_point(|&x| x <= lo);
        t.get(k).copied().filter(|&x| x < hi).map(|x| (j, x))
    })
}

/// The joint whose trace the segment a-b lies on, if any: along the line of the edge's
/// label if that is a joint, else any joint's line (a diagonal may run along a joint).
fn trace_under(face: Face, a: DVec2, b: DVec2, joints: &[Joint], eps: f64) -> Option<usize> {
    let m = 0.5 * (a + b);
    let on = |j: &Joint| {
        (j.line.normal.dot(a) - j.line.offset).abs() <= eps
            && (j.line.normal.dot(b) - j.line.offset).abs() <= eps
            && j.on_trace(j.direction().dot(m))
    };
    match face {
        // Made by the split along joint k: on its line by construction.
        Face::Joint(k) => joints[k]
            .on_trace(joints[k].direction().dot(m))
            .then_some(k),
        Face::Diagonal | Face::Outline => joints.iter().position(on),
        Face::Tip => None,
    }
}

/// Each edge's joint set, where it lies on a trace.
fn edge_sets(cell: &Cell, joints: &[Joint], eps: f64) -> Vec<Option<usize>> {
    let v = cell.poly.vertices();
    let n = v.len();
    (0..n)
        .map(|i| {
            trace_under(cell.faces[i], v[i], v[(i + 1) % n], joints, eps).map(|k| joints[k].set)
        })
        .collect()
}

/// The pairs of cells sharing a stretch of intact rock: (cell a, cell b, a's edge, b's
/// edge), a < b, in ascending order. Only cells whose boxes are within `eps` of each
/// other on both axes ([`near_boxes`]) can share one.
fn glued_pairs(cells: &[Cell], joints: &[Joint], eps: f64) -> Vec<(usize, usize, usize, usize)> {
    let boxes: Vec<Aabb> = cells.iter().map(|c| c.poly.aabb()).collect();
    let mut out: Vec<_> = near_boxes(&boxes, eps)
        .into_iter()
        .filter_map(|(a, b)| {
            shared_intact(&cells[a], &cells[b], joints, eps).map(|(ea, eb)| (a, b, ea, eb))
        })
        .collect();
    out.sort_unstable();
    out
}

/// Boxes spanning more grid cells than this on either axis are paired with every box
/// directly rather than entered in the grid ([`near_boxes`]).
const GRID_SPAN: usize = 8;

/// The pairs (a, b), a < b, ascending, of boxes within `eps` of each other along x and
/// along y: with the boxes ordered by their left sides (ties by index), a pair whose
/// later box starts no more than `eps` right of the earlier one's right side, and whose
/// y ranges are no more than `eps` apart. The same pairs, by the same comparisons, as a
/// sweep along x, which costs N^1.5 over a square mass (every box against the column of
/// boxes beside it): the boxes grown by `eps` are entered in a grid of cells about their
/// mean size, each pair is proposed once, by the first cell the two share, and decided
/// by the sweep's own test.
fn near_boxes(boxes: &[Aabb], eps: f64) -> Vec<(usize, usize)> {
    let n = boxes.len();
    let before = |a: usize, b: usize| {
        boxes[a]
            .min
            .x
            .total_cmp(&boxes[b].min.x)
            .then(a.cmp(&b))
            .is_lt()
    };
    // The sweep's test, the earlier box of the two first.
    let near = |a: usize, b: usize| {
        let (a, b) = if before(a, b) { (a, b) } else { (b, a) };
        let (p, q) = (&boxes[a], &boxes[b]);
        !(q.min.x > p.max.x + eps || q.min.y > p.max.y + eps || p.min.y > q.max.y + eps)
    };
    let grown: Vec<Aabb> = boxes.iter().map(|b| b.expanded(eps)).collect();
    let mut out = Vec::new();
    let Some(all) = grown.iter().copied().reduce(|a, b| a.union(&b)) else {
        return out;
    };
    let mean = grown
        .iter()
        .map(|b| b.size().x.max(b.size().y))
        .sum::<f64>()
        / n as f64;
    let size = all.size();
    // Cells about the boxes' mean size, at most some 4 N of them.
    let mut cell = mean.max(f64::MIN_POSITIVE);
    while (size.x / cell + 1.0) * (size.y / cell + 1.0) > 4.0 * n as f64 + 16.0 {
        cell *= 2.0;
    }
    if !(cell.is_finite() && size.x.is_finite() && size.y.is_finite()) {
        // Nothing to index by: every pair by the test.
        for a in 0..n {
            out.extend((a + 1..n).filter(|&b| near(a, b)).map(|b| (a, b)));
        }
        return out;
    }
    let nx = (size.x / cell) as usize + 1;
    let ny = (size.y / cell) as usize + 1;
    let index = |v: f64, lo: f64, count: usize| (((v - lo) / cell) as usize).min(count - 1);
    let range = |b: &Aabb| {
        (
            index(b.min.x, all.min.x, nx),
            index(b.max.x, all.min.x, nx),
            index(b.min.y, all.min.y, ny),
            index(b.max.y, all.min.y, ny),
        )
    };
    let ranges: Vec<_> = grown.iter().map(range).collect();
    let is_large = |i: usize| {
        let (x0, x1, y0, y1) = ranges[i];
        x1 - x0 >= GRID_SPAN || y1 - y0 >= GRID_SPAN
    };
    // Each box not large in the cells it spans, by cell (row-major), then by box.
    let mut entered: Vec<(usize, u32)> = Vec::new();
    for i in (0..n).filter(|&i| !is_large(i)) {
        let (x0, x1, y0, y1) = ranges[i];
        for y in y0..=y1 {
            entered.extend((x0..=x1).map(|x| (y * nx + x, i as u32)));
        }
    }
    entered.sort_unstable();
    for here in entered.chunk_by(|a, b| a.0 == b.0) {
        let (x, y) = (here[0].0 % nx, here[0].0 / nx);
        for (k, &(_, a)) in here.iter().enumerate() {
            for &(_, b) in &here[k + 1..] {
                let (a, b) = (a as usize, b as usize);
                // Proposed by the first cell the two share only.
                let (ra, rb) = (ranges[a], ranges[b]);
                if (ra.0.max(rb.0), ra.2.max(rb.2)) == (x, y) && near(a, b) {
                    out.push((a.min(b), a.max(b)));
                }
            }
        }
    }
    // A large box against every other box, a pair of large ones once.
    for a in (0..n).filter(|&a| is_large(a)) {
        for b in (0..n).filter(|&b| b != a && (!is_large(b) || b > a)) {
            if near(a, b) {
                out.push((a.min(b), a.max(b)));
            }
        }
    }
    out.sort_unstable();
    out
}

/// The first pair of edges (one of each cell) that run along each other over more than
/// `eps` on intact rock (not on a joint trace), if any.
fn shared_intact(a: &Cell, b: &Cell, joints: &[Joint], eps: f64) -> Option<(usize, usize)> {
    let (va, vb) = (a.poly.vertices(), b.poly.vertices());
    let (na, nb) = (va.len(), vb.len());
    for i in 0..na {
        let (p0, p1) = (va[i], va[(i + 1) % na]);
        let dir = (p1 - p0).normalize();
        for j in 0..nb {
            let (q0, q1) = (vb[j], vb[(j + 1) % nb]);
            // Anti-parallel and on one line.
            if cross(dir, q0 - p0).abs() > eps || cross(dir, q1 - p0).abs() > eps {
                continue;
            }
            if dir.dot(q1 - q0) >= 0.0 {
                continue;
            }
            let (s0, s1) = (0.0f64, dir.dot(p1 - p0));
            let (r0, r1) = (dir.dot(q1 - p0), dir.dot(q0 - p0));
            let (lo, hi) = (s0.max(r0), s1.min(r1));
            if hi - lo <= eps {
                continue;
            }
            let (x0, x1) = (p0 + lo * dir, p0 + hi * dir);
            let on_joint = trace_under(a.faces[i], x0, x1, joints, eps).is_some()
                || trace_under(b.faces[j], x0, x1, joints, eps).is_some();
            if !on_joint {
                return Some((i, j));
            }
        }
    }
    None
}

/// The union of two glued cells sharing the whole of edge `ea` of `a` and `eb` of `b`, if
/// it is convex; collinear vertices at the ends are removed only between edges of the
/// trace status (so that no edge becomes part joint, part intact rock).
fn merge_cells(
    a: &Cell,
    ea: usize,
    b: &Cell,
    eb: usize,
    joints: &[Joint],
    eps: f64,
) -> Option<Cell> {
    let (va, vb) = (a.poly.vertices(), b.poly.vertices());
    let (na, nb) = (va.len(), vb.len());
    let (p0, p1) = (va[ea], va[(ea + 1) % na]);
    let (q0, q1) = (vb[eb], vb[(eb + 1) % nb]);
    if p0.distance(q1) > eps || p1.distance(q0) > eps {
        return None;
    }
    // a from p1 round to p0, then b from q1 (= p0) round to q0 (= p1), exclusive.
    let mut pts = Vec::with_capacity(na + nb - 2);
    let mut faces = Vec::with_capacity(na + nb - 2);
    for k in 0..na - 1 {
        let i = (ea + 1 + k) % na;
        pts.push(va[i]);
        faces.push(a.faces[i]);
    }
    for k in 0..nb - 1 {
        let j = (eb + 1 + k) % nb;
        pts.push(vb[j]);
        faces.push(b.faces[j]);
    }
    // The joins are at p0 (index na - 1) and p1 (index 0).
    let m = pts.len();
    let mut drop = Vec::new();
    for &k in &[na - 1, 0] {
        let (x, y, z) = (pts[(k + m - 1) % m], pts[k], pts[(k + 1) % m]);
        let turn = cross(y - x, z - y);
        let straight = turn.abs() <= eps * (z - x).length();
        if straight {
            let w = (k + m - 1) % m;
            let on = |e: usize, p: DVec2, q: DVec2| trace_under(faces[e], p, q, joints, eps);
            if on(w, x, y) != on(k, y, z) {
                return None;
            }
            // One edge of two kinds of face (the outline, a diagonal, ...) both off every
            // trace, or both on one: the joint search by geometry finds what it lies on.
            if faces[w] != faces[k] {
                faces[w] = match on(w, x, y) {
                    Some(j) => Face::Joint(j),
                    None => Face::Diagonal,
                };
            }
            drop.push(k);
        } else if turn < 0.0 {
            return None;
        }
    }
    drop.sort_unstable();
    for &k in drop.iter().rev() {
        pts.remove(k);
        faces.remove(k);
    }
    let (poly, faces) = labelled_piece(pts, faces, eps).ok()??;
    Some(Cell { poly, faces })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The pairs a sweep along x finds, as `glued_pairs` found them before the grid.
    fn swept(boxes: &[Aabb], eps: f64) -> Vec<(usize, usize)> {
        let mut order: Vec<usize> = (0..boxes.len()).collect();
        order.sort_by(|&a, &b| boxes[a].min.x.total_cmp(&boxes[b].min.x).then(a.cmp(&b)));
        let mut out = Vec::new();
        for (k, &a) in order.iter().enumerate() {
            for &b in &order[k + 1..] {
                if boxes[b].min.x > boxes[a].max.x + eps {
                    break;
                }
                if boxes[b].min.y > boxes[a].max.y + eps || boxes[a].min.y > boxes[b].max.y + eps {
                    continue;
                }
                out.push((a.min(b), a.max(b)));
            }
        }
        out.sort_unstable();
        out
    }

    proptest! {
        #![proptest_config(crate::test_support::config(256))]
        /// The grid pairs the boxes the sweep pairs: cells of a cut (boxes on a grid of
        /// 1/8, touching, apart by eps to the bit, overlapping), a few far larger (a
        /// big piece, in no grid cell) and a few far away.
        #[test]
        fn the_grid_pairs_the_boxes_the_sweep_pairs(
            v in prop::collection::vec(
                (
                    prop_oneof![8 => 0.0..10.0f64, 1 => -1e3..1e3f64],
                    prop_oneof![8 => 0.0..10.0f64, 1 => -1e3..1e3f64],
                    prop_oneof![8 => 0.0..1.5f64, 1 => 0.0..60.0f64],
                    prop_oneof![8 => 0.0..1.5f64, 1 => 0.0..60.0f64],
                ),
                0..150,
            ),
            eps in prop_oneof![Just(0.0), Just(0.125), 0.0..0.3f64],
            far in any::<bool>(),
        ) {
            let s = |x: f64| (x * 8.0).round() / 8.0;
            // Without boxes far away, the grid's cells stay small and the large boxes
            // are paired outside it.
            let near_by = |x: f64| if far { x } else { x.clamp(0.0, 10.0) };
            let boxes: Vec<Aabb> = v
                .iter()
                .map(|&(x, y, w, h)| {
                    let min = DVec2::new(s(near_by(x)), s(near_by(y)));
                    Aabb { min, max: min + DVec2::new(s(w), s(h)) }
                })
                .collect();
            prop_assert_eq!(near_boxes(&boxes, eps), swept(&boxes, eps));
        }
    }

    fn outline(c: &[[f64; 2]]) -> Outline {
        Outline::new(c.iter().map(|&p| DVec2::from(p)).collect()).expect("valid outline")
    }

    fn horizontal(y: f64, traces: Option<Vec<[f64; 2]>>) -> Joint {
        // normal (0, 1): direction (1, 0), so t = x.
        Joint {
            line: Line {
                normal: DVec2::Y,
                offset: y,
            },
            set: 0,
            traces,
        }
    }

    #[test]
    fn an_l_shaped_outline_is_one_piece_of_two_glued_parts() {
        let l = outline(&[
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, 2.0],
            [0.0, 2.0],
        ]);
        assert_eq!(l.reflex_vertex(), Some(3));
        let cut = cut_mass(&l, &[], 0.0).expect("cut");
        assert_eq!(cut.pieces.len(), 1);
        assert_eq!(cut.pieces[0].parts.len(), 2);
        assert!((cut.pieces[0].area() - 3.0).abs() < 1e-12);
        // A persistent joint along the re-entrant corner's edge splits it in two pieces.
        let cut = cut_mass(&l, &[horizontal(1.0, None)], 0.0).expect("cut");
        assert_eq!(cut.pieces.len(), 2);
        let mut areas: Vec<f64> = cut.pieces.iter().map(Piece::area).collect();
        areas.sort_by(f64::total_cmp);
        assert!((areas[0] - 1.0).abs() < 1e-12 && (areas[1] - 2.0).abs() < 1e-12);
        // Each piece's face on the joint is tagged with its set.
        for p in &cut.pieces {
            assert!(p.edge_sets.iter().flatten().any(|s| *s == Some(0)));
        }
    }

    #[test]
    fn a_joint_ending_inside_the_rock_leaves_one_piece() {
        let sq = outline(&[[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]]);
        // A trace from x = -1 to x = 1 along y = 1: it ends in the middle of the square.
        let cut = cut_mass(&sq, &[horizontal(1.0, Some(vec![[-1.0, 1.0]]))], 0.0).expect("cut");
        assert_eq!(cut.pieces.len(), 1);
        let p = &cut.pieces[0];
        assert!((p.area() - 4.0).abs() < 1e-12);
        // The two quarters beside the trace, and the right half merged across the bridge.
        assert_eq!(p.parts.len(), 3);
        let tagged: usize = p.edge_sets.iter().flatten().filter(|s| s.is_some()).count();
        assert_eq!(tagged, 2, "the trace's two faces, one on each side");
        // The same trace across the whole square cuts it in two.
        let cut = cut_mass(&sq, &[horizontal(1.0, Some(vec![[-1.0, 3.0]]))], 0.0).expect("cut");
        assert_eq!(cut.pieces.len(), 2);
        assert!(cut.pieces.iter().all(|p| p.parts.len() == 1));
    }

    #[test]
    fn a_regular_family_is_the_lines_of_its_spacing() {
        let fam = JointFamily::regular(JointSet {
            dip_deg: 0.0,
            spacing: 1.0,
            offset: 0.5,
        });
        let bounds = Aabb::from_points(&[DVec2::ZERO, DVec2::new(3.0, 3.0)]);
        let js = fam.joints(0, &bounds, 100).expect("joints");
        let offsets: Vec<f64> = js.iter().map(|j| j.line.offset).collect();
        assert_eq!(offsets, vec![0.5, 1.5, 2.5]);
        assert!(fam.joints(0, &bounds, 2).is_err());
        // Statistical draws repeat with the seed and vary with it.
        let stat = JointFamily {
            spacing_cv: 0.3,
            dip_spread_deg: 5.0,
            trace: Some((1.0, 0.5)),
            seed: 7,
            ..fam
        };
        let a = stat.joints(0, &bounds, 100).expect("joints");
        assert_eq!(a, stat.joints(0, &bounds, 100).expect("joints"));
        assert_ne!(
            a,
            JointFamily { seed: 8, ..stat }
                .joints(0, &bounds, 100)
                .expect("joints")
        );
        for j in &a {
            let tr = j.traces.as_ref().expect("traces");
            for w in tr.windows(2) {
                assert!((w[1][0] - w[0][1] - 0.5).abs() < 1e-12, "bridges of 0.5");
            }
        }
    }

    #[test]
    fn bad_outlines_name_the_vertex_or_edges() {
        let o = |c: &[[f64; 2]]| Outline::new(c.iter().map(|&p| DVec2::from(p)).collect());
        assert_eq!(
            o(&[[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]]),
            Err(PolygonError::Clockwise)
        );
        assert_eq!(
            o(&[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [1.0, 1.0]]),
            Err(PolygonError::CollinearVertex { vertex: 1 })
        );
        assert!(matches!(
            o(&[[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]]),
            Err(PolygonError::SelfIntersecting { .. })
        ));
    }
}
