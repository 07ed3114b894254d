//! Contact springs as linear constraint rows (docs/method.md).
//!
//! Every spring of the engine measures one quantity that is, to first order, linear in the
//! unknowns of at most two blocks: q(D) = g0 + c_a . D_a + c_b . D_b. A spring of
//! stiffness p on q adds the energy p q^2 / 2, that is K_xy += p c_x c_y^T and
//! F_x -= p g0 c_x; a force f along q adds F_x += f c_x. The normal spring, the shear
//! spring, the friction force and the fixed-point springs are all this one mechanism.
//!
//! **Where a contact row is linearised** (our choice; Shi takes the gradient at step
//! start). g0 is the value at step start (the normal row divides it by the edge's length
//! at the half step, see [`normal_row`]); the coefficients c are the gradient at
//! the step's predicted midpoint: both blocks moved by half their motion at their current
//! velocities, V dt / 2 ([`HalfStep`]). Then c . D equals q(D) - q(0) up to terms of third
//! order when the step moves as predicted (the midpoint rule is exact for quadratics), so
//! the force's work over the step matches the change of the spring's energy. With the
//! step-start gradient it misses the second-order part of the gap, q'' D D / 2 (a block
//! turning by theta moves a point at radius rho by theta^2 rho / 2 more than the first
//! order says); the force times that is work no motion paid for. It made a block spinning
//! in contact at theta_max per step gain up to 8% of its energy in `tests/physics/hard_pairs.rs`,
//! which the midpoint rows remove.

use crate::kinematics::{Vec6, along, dot, t_rows};
use dda_contact::{BlockShape, Contact};
use dda_geom::{DVec2, Motion};

/// A block's predicted motion over the first half of a step, V dt / 2 with exact
/// rotation: where the step's contact rows are linearised (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HalfStep {
    /// None for a block at rest: its points stay where they are, bit for bit.
    motion: Option<Motion>,
    centroid: DVec2,
    /// A driven block's motion over the whole step, known before it (`seismic`): rows
    /// fold it into their value.
    pub(crate) driven: Option<DVec2>,
}

impl HalfStep {
    /// The half step of a block with reference point `centroid` moving at `velocity`
    /// over a step of `dt`.
    pub fn new(centroid: DVec2, velocity: &Vec6, dt: f64) -> Self {
        if velocity.iter().all(|&v| v == 0.0) {
            return HalfStep::at_rest(centroid);
        }
        let d = velocity.map(|v| 0.5 * dt * v);
        HalfStep {
            motion: Some(Motion::new(centroid, &d)),
            centroid: centroid + DVec2::new(d[0], d[1]),
            driven: None,
        }
    }

    /// A block driven by the ground: translated by `half` at the half step and by
    /// `step` over the whole step.
    pub fn driven(centroid: DVec2, half: DVec2, step: DVec2) -> Self {
        let d = [half.x, half.y, 0.0, 0.0, 0.0, 0.0];
        HalfStep {
            motion: Some(Motion::new(centroid, &d)),
            centroid: centroid + half,
            driven: Some(step),
        }
    }

    /// A block that does not move (fixed, at rest, or in a static analysis).
    pub fn at_rest(centroid: DVec2) -> Self {
        HalfStep {
            motion: None,
            centroid,
            driven: None,
        }
    }

    /// Where point `p` of the block is at the half step.
    #[inline]
    pub fn apply(&self, p: DVec2) -> DVec2 {
        self.motion.map_or(p, |m| m.apply(p))
    }
}

/// A linear measure over the unknowns of (up to) two blocks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    /// Value at D = 0 (at step start).
    pub g0: f64,
    /// The two blocks (scene indices): the vertex's and the edge's.
    pub blocks: [u32; 2],
    /// Coefficients over each block's unknowns.
    pub c: [Vec6; 2],
    /// The part of `g0` that is a driven block's known motion over the step (its
    /// coefficients times that motion, then zeroed): 0 unless a block is driven.
    pub driven: f64,
}

impl Row {
    /// The measure for block motions `d` (indexed by scene block).
    #[inline]
    pub fn eval(&self, d: &[Vec6]) -> f64 {
        self.g0
            + dot(&self.c[0], &d[self.blocks[0] as usize], 6)
            + dot(&self.c[1], &d[self.blocks[1] as usize], 6)
    }
}

/// The points of a contact at step start: vertex P1 of the vertex block, edge P2 -> P3 of
/// the edge block.
#[inline]
pub fn contact_points(c: &Contact, shapes: &[BlockShape]) -> (DVec2, DVec2, DVec2) {
    let k = c.key;
    let vs = &shapes[k.vertex_block as usize];
    let es = &shapes[k.edge_block as usize];
    (
        vs.vertices[k.vertex as usize],
        es.vertices[k.edge as usize],
        es.vertices[es.next(k.edge as usize)],
    )
}

/// The contact's step-start points `p` (vertex, edge start, edge end) moved to the half
/// step (`half`, by block), with the vertex block's and edge block's reference points.
#[inline]
fn points_at(c: &Contact, p: (DVec2, DVec2, DVec2), half: &[HalfStep]) -> ([DVec2; 3], [DVec2; 2]) {
    let (p1, p2, p3) = p;
    let (hv, he) = (
        &half[c.key.vertex_block as usize],
        &half[c.key.edge_block as usize],
    );
    (
        [hv.apply(p1), he.apply(p2), he.apply(p3)],
        [hv.centroid, he.centroid],
    )
}

/// The normal distance of a vertex-edge contact after the step, to first order:
/// d = (S0 + H^T D_i + G^T D_j) / l with S0 = `det[[1,x1,y1],[1,x3,y3],[1,x2,y2]]`
/// (docs/method.md section 4; S0 / l is the paper's d_n, eq. 7), H, G and l taken at the
/// half step `half` (see the module docs). S0 is the step start's; l at the half step
/// equals l at step start for a rigid motion, and differs by the edge's strain over half a
/// step for a straining block. Its translational parts are equal and opposite, so the
/// spring conserves momentum.
pub fn normal_row(c: &Contact, shapes: &[BlockShape], half: &[HalfStep]) -> Row {
    let start = contact_points(c, shapes);
    let (p1, p2, p3) = start;
    let s0 = (p3.x - p1.x) * (p2.y - p1.y) - (p2.x - p1.x) * (p3.y - p1.y);
    let ([p1, p2, p3], [ci, cj]) = points_at(c, start, half);
    let l = (p3 - p2).length();
    let ti = t_rows(p1, ci);
    let (t2, t3) = (t_rows(p2, cj), t_rows(p3, cj));
    let h = [p3.y - p2.y, p2.x - p3.x];
    let g2 = [p1.y - p3.y, p3.x - p1.x];
    let g3 = [p2.y - p1.y, p1.x - p2.x];
    let inv = 1.0 / l;
    let e: Vec6 = std::array::from_fn(|m| inv * (h[0] * ti[0][m] + h[1] * ti[1][m]));
    let g: Vec6 = std::array::from_fn(|m| {
        inv * (g2[0] * t2[0][m] + g2[1] * t2[1][m] + g3[0] * t3[0][m] + g3[1] * t3[1][m])
    });
    fold_driven(
        Row {
            g0: s0 * inv,
            blocks: [c.key.vertex_block, c.key.edge_block],
            c: [e, g],
            driven: 0.0,
        },
        half,
    )
}

/// Folds the known motion of a driven block of `row` into its value (see `seismic`):
/// q = g0 + c_a . D_a + c_b . D_b with D_b known is g0 + c_b . D_b + c_a . D_a.
#[inline]
fn fold_driven(mut row: Row, half: &[HalfStep]) -> Row {
    for (b, c) in row.blocks.iter().zip(row.c.iter_mut()) {
        if let Some(u) = half[*b as usize].driven {
            let e = c[0] * u.x + c[1] * u.y;
            row.g0 += e;
            row.driven += e;
            *c = [0.0; 6];
        }
    }
    row
}

/// The tangential displacement of the vertex relative to the point at ratio `anchor`
/// along the edge (a material point of the edge block), measured along the edge's unit
/// tangent: the shear spring's and the friction force's row. Its value is taken at step
/// start, its gradient at the half step `half`, as the normal row's.
pub fn shear_row(c: &Contact, shapes: &[BlockShape], half: &[HalfStep], anchor: f64) -> Row {
    let start = contact_points(c, shapes);
    let (p1, p2, p3) = start;
    let t = (p3 - p2).normalize();
    let g0 = (p1 - (p2 + anchor * (p3 - p2))).dot(t);
    let ([p1, p2, p3], [ci, cj]) = points_at(c, start, half);
    let t = (p3 - p2).normalize();
    let p0 = p2 + anchor * (p3 - p2);
    let mut cb = along(t, p0, cj);
    for v in cb.iter_mut() {
        *v = -*v;
    }
    fold_driven(
        Row {
            g0,
            blocks: [c.key.vertex_block, c.key.edge_block],
            c: [along(t, p1, ci), cb],
            driven: 0.0,
        },
        half,
    )
}

/// The length a contact's cohesion and tensile strength act over: half the overlap of
/// the edge its vertex lies against and the face of the vertex's block that runs along
/// that edge (the one of the vertex's two edges within `sin_e`, sin theta_e, of
/// parallel to it), so that the two ends of a face-to-face contact share the faces'
/// overlap, as Shi's code takes it (`proj` in ntdda); 0 for a corner against an edge,
/// with no face along it. Taking half the edge itself (until 2026-11-27) gave a block
/// bonded to a long bed the strength of the bed's length: a 1 m block on an 11 m bed
/// held 11 times its joint's strength.
pub fn contact_length(c: &Contact, shapes: &[BlockShape], sin_e: f64) -> f64 {
    let (edge, e) = (&shapes[c.key.edge_block as usize], c.key.edge as usize);
    let (p0, t, len) = (edge.vertices[e], edge.tangents[e], edge.lengths[e]);
    let block = &shapes[c.key.vertex_block as usize];
    let (n, v) = (block.vertices.len(), c.key.vertex as usize);
    let x = block.vertices[v];
    // The vertex's two edges, as the segment from it to its neighbour.
    let face = [block.vertices[(v + n - 1) % n], block.vertices[(v + 1) % n]]
        .into_iter()
        .filter(|q| {
            let d = *q - x;
            t.perp_dot(d).abs() <= sin_e * d.length()
        })
        .min_by(|a, b| {
            let turn = |q: &DVec2| t.perp_dot((*q - x).normalize_or_zero()).abs();
            turn(a).total_cmp(&turn(b))
        });
    let Some(q) = face else {
        return 0.0;
    };
    let (sx, sq) = ((x - p0).dot(t), (q - p0).dot(t));
    let overlap = sx.max(sq).min(len) - sx.min(sq).max(0.0);
    0.5 * overlap.max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use dda_contact::ContactKey;
    use dda_geom::{ConvexPolygon, displace_point};

    fn square(x: f64, y: f64) -> ConvexPolygon {
        ConvexPolygon::from_coords(&[[x, y], [x + 1.0, y], [x + 1.0, y + 1.0], [x, y + 1.0]])
            .unwrap()
    }

    /// Square A's corner 0 at (0.2, 1.01), 0.01 above square B's top edge (edge 2,
    /// (1, 1) -> (0, 1)): the squares, their shapes and the contact.
    fn corner_over_edge() -> (ConvexPolygon, ConvexPolygon, [BlockShape; 2], Contact) {
        let a = square(0.2, 1.01);
        let b = square(0.0, 0.0);
        let shapes = [BlockShape::new(&a), BlockShape::new(&b)];
        let key = ContactKey {
            vertex_block: 0,
            vertex: 0,
            edge_block: 1,
            edge: 2,
        };
        (a, b, shapes, Contact::new(key, 0.01, 0.8, true))
    }

    /// A face-to-face contact's cohesion length is half the faces' overlap: square A
    /// (x from 0.2 to 1.2) over square B (0 to 1) overlaps it by 0.8 m, so 0.4 m at each
    /// end; a corner of a diamond against the same edge has no face along it, and 0.
    #[test]
    fn a_contact_length_is_half_the_faces_overlap() {
        let (_, _, shapes, c) = corner_over_edge();
        let sin_e = 4f64.to_radians().sin();
        assert!((contact_length(&c, &shapes, sin_e) - 0.4).abs() < 1e-12);
        let diamond =
            ConvexPolygon::from_coords(&[[0.5, 1.01], [1.0, 1.51], [0.5, 2.01], [0.0, 1.51]])
                .unwrap();
        let shapes = [BlockShape::new(&diamond), shapes[1].clone()];
        assert_eq!(contact_length(&c, &shapes, sin_e), 0.0);
    }

    /// Linearised at step start (blocks at rest), the normal row's value equals d_n at
    /// D = 0 and is the first-order expansion of S0 / l with l held at its step-start
    /// value (docs/method.md): against the exact S0 after a motion of size h, divided by
    /// the step-start l, the error is O(h^2).
    #[test]
    fn normal_row_is_the_linearised_distance() {
        let (a, b, shapes, c) = corner_over_edge();
        let rest = [a.centroid(), b.centroid()].map(HalfStep::at_rest);
        let row = normal_row(&c, &shapes, &rest);
        assert!((row.g0 - 0.01).abs() < 1e-15);
        for h in [1e-3, 1e-4] {
            let d = [
                [0.3 * h, -0.7 * h, 0.5 * h, 0.1 * h, -0.2 * h, 0.3 * h],
                [-0.1 * h, 0.2 * h, -0.4 * h, 0.2 * h, 0.1 * h, -0.1 * h],
            ];
            let p1 = displace_point(a.vertex(0), a.centroid(), &d[0]);
            let p2 = displace_point(b.vertex(2), b.centroid(), &d[1]);
            let p3 = displace_point(b.vertex(3), b.centroid(), &d[1]);
            // Exact S0 after the motion over the step-start length.
            let l0 = (b.vertex(3) - b.vertex(2)).length();
            let exact = dda_geom::normal_distance(p1, p2, p3) * (p3 - p2).length() / l0;
            let err = (row.eval(&d) - exact).abs();
            assert!(err < 10.0 * h * h, "h = {h}: error {err}");
        }
        // Translational parts equal and opposite.
        assert!((row.c[0][0] + row.c[1][0]).abs() < 1e-15);
        assert!((row.c[0][1] + row.c[1][1]).abs() < 1e-15);
    }

    /// The normal distance after a step of exactly the predicted motion D = V dt, with the
    /// rotation exact, against the row: linearised at step start the error is of second
    /// order in the motion, at the half step of third order (the midpoint rule is exact
    /// for quadratics). Measured by the order of convergence as the motion shrinks tenfold:
    /// the error must shrink at least 10^2.5 times at the half step (10^3 for a cubic term;
    /// the margin covers the fourth-order remainder), and the step-start error at most
    /// 10^2.5 times (it is quadratic), so that this test fails if the half step is not
    /// used.
    #[test]
    fn rows_at_the_half_step_are_exact_to_second_order() {
        let (a, b, shapes, c) = corner_over_edge();
        // A spin-dominated motion of both blocks (rigid: strains play no part here).
        let v = [
            [0.3, -0.7, 2.0, 0.0, 0.0, 0.0],
            [-0.1, 0.2, -1.5, 0.0, 0.0, 0.0],
        ];
        let error = |h: f64, at_half: bool| {
            let half: Vec<HalfStep> = (0..2)
                .map(|i| {
                    let centre = shapes[i].centroid;
                    if at_half {
                        HalfStep::new(centre, &v[i], h)
                    } else {
                        HalfStep::at_rest(centre)
                    }
                })
                .collect();
            let row = normal_row(&c, &shapes, &half);
            let d = v.map(|vi| vi.map(|x| x * h));
            let p1 = displace_point(a.vertex(0), a.centroid(), &d[0]);
            let p2 = displace_point(b.vertex(2), b.centroid(), &d[1]);
            let p3 = displace_point(b.vertex(3), b.centroid(), &d[1]);
            (row.eval(&d) - dda_geom::normal_distance(p1, p2, p3)).abs()
        };
        let shrink = |at_half: bool| error(1e-2, at_half) / error(1e-3, at_half);
        assert!(
            shrink(true) > 10f64.powf(2.5),
            "half step: {}",
            shrink(true)
        );
        assert!(
            shrink(false) < 10f64.powf(2.5),
            "step start: {}",
            shrink(false)
        );
    }
}
