//! Time-step control: dt limited by the velocities a step starts with, cut when the
//! open-close iteration does not converge or the motion passes d_max or theta_max, grown
//! after easy steps. The factors are our choice (`docs/method.md`, section 7).

use crate::kinematics::{Vec6, point_displacement};
use crate::simulation::Simulation;
use dda_geom::DVec2;

/// Most OCI iterations of an easy step (after which dt may grow): two thirds of the bound
/// `max_oci`, rounded up (4 of 6). Our choice; Shi's formulation and the paper fix only the
/// criteria. In a large column a few of its many contacts change state in almost every
/// iteration, so a bound of half (3 of 6) held dt back as N grew. Measured with 4 against
/// 3 (counts, `docs/performance.md`): 111,460 blocks (0.1 s) 954 OCI iterations and 601
/// factorisations against 1,287 and 844; 3,472 blocks 574 and 293 against 641 and 334;
/// 10,131 blocks 691 and 380 against 725 and 361; the 826-block column over five
/// trajectories (`cargo xtask target`) 17,712 and 5,927 against 17,902 and 5,785. 5 of 6
/// gave 20 step cuts at 3,472 blocks and no gain.
pub fn easy_oci(max_oci: u32) -> u32 {
    (2 * max_oci).div_ceil(3)
}

/// Largest factor by which dt grows after one step.
pub(crate) const MAX_GROWTH: f64 = 1.25;

/// Fraction of d_max and theta_max that the next step's motion, scaled in proportion to
/// dt, may reach when dt grows after an easy step. Our choice. Until this rule dt grew by
/// 1.25 only after a step that moved at most half of d_max (0.625 of d_max predicted),
/// and a collapsing column, whose steps are limited by d_max, stayed at one dt for
/// hundreds of steps. Measured over the five trajectories of `cargo xtask target`
/// (826 blocks): steps, OCI iterations and factorisations 4,775, 18,308 and 6,173 under
/// the old rule; with this rule at 0.625, 0.7, 0.8 and 0.9 of d_max: 4,357, 17,456 and
/// 5,828; 4,198, 17,116 and 5,811; 4,032, 16,910 and 5,886; 3,889, 16,697 and 6,039
/// (more cuts, 166 against 91). The 3,472- and 10,131-block columns (0.1 s) are OCI
/// limited and took the same steps either way.
pub(crate) const GROWTH_TARGET: f64 = 0.8;

/// Factor by which dt grows after an accepted step that took `iterations` OCI iterations
/// (of at most `max_oci`) and whose largest vertex displacement and rotation were `disp`
/// and `rot`: 1 unless the step was easy ([`easy_oci`]); otherwise as far as that motion,
/// scaled in proportion to dt, stays within `GROWTH_TARGET` of `d_max` and `theta_max`,
/// between 1 and `MAX_GROWTH`.
pub fn step_growth(
    iterations: u32,
    max_oci: u32,
    disp: f64,
    rot: f64,
    d_max: f64,
    theta_max: f64,
) -> f64 {
    if iterations > easy_oci(max_oci) {
        return 1.0;
    }
    (GROWTH_TARGET * motion_room(disp, rot, d_max, theta_max)).clamp(1.0, MAX_GROWTH)
}

/// How many times a step's largest displacement `disp` and rotation `rot` fit within
/// `d_max` and `theta_max` (the smaller ratio): below 1 the step moved too far, and dt
/// scales by it either way, down after a cut and up in [`step_growth`].
pub(crate) fn motion_room(disp: f64, rot: f64, d_max: f64, theta_max: f64) -> f64 {
    (d_max / disp.max(f64::MIN_POSITIVE)).min(theta_max / rot.max(f64::MIN_POSITIVE))
}

/// A remainder to the run's end (or to an excavation's time) shorter than this many
/// steps is taken in two equal steps rather than a step and a sliver: no step before
/// the end is shorter than half the one asked for. Our choice (2026-11-28): the
/// velocities a step ends with carry the penalty springs' ringing over its length,
/// larger the shorter the step, and a run's last step is where its result is read. A
/// generated jointed mass (`g216` of `docs/method.md` section 6) at rest ended 0.3 s
/// with a step of 0.89 ms after its 2 ms ones, its kinetic energy 6.5 times that of the
/// step before (8.7e-5 J against 1.3e-5 J); it now ends with two steps of 1.45 ms, at
/// 1.3e-5 J.
pub(crate) const LANDING_SPLIT: f64 = 1.5;

/// Floor of the time step, relative to the initial step: below it the run stops.
pub(crate) const DT_FLOOR: f64 = 1e-9;

impl Simulation {
    /// Marks the blocks the rotation limit theta_max holds in this step
    /// (`Scratch::turn_limited`), after the step's detection: every block with a
    /// contact (a candidate within d_tol), a fixed point, a load or a bolt. The others
    /// turn free in flight, and the limit is of no use to them: their rotation is exact
    /// in the update, no spring's row rests on their lever arms, and d_max still bounds
    /// how far their vertices move, so that no contact is missed (docs/method.md section
    /// 7). Chips of 3 cm spinning in flight at 50 to 70 turns a second held a rubble
    /// pile's every step to 9.3e-5 s.
    pub(crate) fn mark_turn_limited(&mut self) {
        let limited = &mut self.scratch.turn_limited;
        limited.clear();
        limited.extend(
            self.state
                .blocks
                .iter()
                .map(|b| !b.fixed_points.is_empty() || !b.loads.is_empty()),
        );
        for c in &self.state.contacts.contacts {
            limited[c.key.vertex_block as usize] = true;
            limited[c.key.edge_block as usize] = true;
        }
        for b in &self.model.bolts {
            limited[b.from_block] = true;
            limited[b.to_block] = true;
        }
    }

    /// Sets each block's bound on its vertices' motion in this step
    /// (`Scratch::flight_room`), after [`Simulation::mark_turn_limited`]: d_max, but for a
    /// free block in flight (no contact, fixed point, load or bolt) whose current
    /// velocity would carry a vertex beyond d_max within the step asked for, half its gap
    /// to the nearest other block (their boxes at step start) less d_tol, where that is
    /// more. d_max bounds a step's motion so that no contact is missed: blocks closer than
    /// d_tol at step start are candidates, and no two others can meet within the step.
    /// Two blocks in flight each moving at most half the gap between them less d_tol do
    /// not meet either, nor does one moving so towards a block held to d_max (d_max is
    /// then at most that half), and the update carries a block in flight exactly (a
    /// ballistic path and its spin, docs/method.md sections 7 and 12). Our choice
    /// (2026-11-28): a block thrown clear of a mass held every step of the run to d_max
    /// over its speed.
    pub(crate) fn set_flight_room(&mut self) {
        let p = &self.model.params;
        let scratch = &mut self.scratch;
        scratch.flight_room.clear();
        scratch.flight_room.resize(scratch.shapes.len(), p.d_max);
        // The nearest block to each block in flight, from trees of the blocks' boxes at
        // step start (`Scratch::aabbs`, the detection's) built at the first such block
        // (`BoxTrees`; a scan of every block for each cost N a block in flight).
        let mut built = false;
        for (i, s) in scratch.shapes.iter().enumerate() {
            if self.free[i].is_none() || scratch.turn_limited[i] {
                continue;
            }
            let fastest = largest_vertex_motion(s, &self.state.blocks[i].velocity);
            if fastest * self.state.dt <= p.d_max {
                continue;
            }
            if !built {
                let removed = &self.removed;
                scratch.nearest.build(&scratch.aabbs, |j| !removed[j]);
                built = true;
            }
            let gap = scratch.nearest.nearest_gap(&scratch.aabbs, i);
            scratch.flight_room[i] = p.d_max.max(0.5 * (gap - p.d_tol));
        }
    }

    /// The largest step the blocks' current velocities allow: the smaller of d_max over
    /// the fastest vertex speed (strain rates included; a block in flight's bound
    /// instead of d_max, [`Simulation::set_flight_room`]) and theta_max over the fastest
    /// spin of a block the limit holds ([`Simulation::mark_turn_limited`]), infinite
    /// when nothing moves; and the block that sets it. Driven blocks count: the
    /// ground's motion is held to d_max per step as a free block's.
    pub(crate) fn velocity_room(&self) -> (f64, Option<usize>) {
        let p = &self.model.params;
        let (mut speed, mut spin) = (0.0f64, 0.0f64);
        // The block taking the largest share of the limits, and that share.
        let (mut block, mut most) = (None, 0.0f64);
        for (i, s) in self.scratch.shapes.iter().enumerate() {
            if self.free[i].is_none() && !self.model.blocks[i].driven {
                continue;
            }
            let v = &self.state.blocks[i].velocity;
            let mut fastest = largest_vertex_motion(s, v);
            // In d_max's terms: the same speed but for a block in flight, whose bound is
            // more.
            fastest *= p.d_max / self.scratch.flight_room[i];
            speed = speed.max(fastest);
            let mut share = fastest / p.d_max;
            if self.scratch.turn_limited[i] {
                spin = spin.max(v[2].abs());
                share = share.max(v[2].abs() / p.theta_max);
            }
            if share > most {
                (block, most) = (Some(i), share);
            }
        }
        ((p.d_max / speed).min(p.theta_max / spin), block)
    }

    /// The largest step `analysis.impact_steps` = N allows: for every pair of blocks in
    /// impact, a 1/N of its contact's duration pi sqrt(m / (n p)) (m the reduced mass of
    /// the two blocks, or the free block's against a fixed one, a part of a body
    /// counting as its body; n its contacts in
    /// impact, [`Simulation::in_impact`]; p the normal penalty); infinite without the
    /// key or without impacts (docs/method.md section 12). Parts of one body never
    /// strike each other: their seams are intact rock, bonded, and their vibration
    /// against each other on those bonds is no impact (counted as one, it held a jointed
    /// slope with rock bridges at steps of 7.8e-6 s once its toe was cut). A part of a
    /// body strikes with its body's mass, the parts' that remain joined to it
    /// ([`Model::bodies`](crate::Model::bodies)): they move as one (a
    /// sliver part of 1.5e-5 m^2, left by an excavation's outline on a tonne of rock,
    /// held the step at 4.6e-7 s with its own).
    pub(crate) fn impact_room(&self) -> f64 {
        let p = &self.model.params;
        let Some(n_steps) = p.impact_steps else {
            return f64::INFINITY;
        };
        let bodies = &self.bodies;
        let mut body_mass = vec![0.0; bodies.len()];
        for (i, body) in bodies.iter().enumerate() {
            if let Some(body) = *body
                && self.free[i].is_some()
            {
                body_mass[body as usize] += self.block_mass(i);
            }
        }
        let mut room = f64::INFINITY;
        for pc in &self.state.contacts.pairs {
            let (a, b) = (bodies[pc.pair.a as usize], bodies[pc.pair.b as usize]);
            if a.is_some() && a == b {
                continue;
            }
            let Some((_, speed)) = self.impact_speed(pc.pair) else {
                continue;
            };
            let Some(m) = self.reduced_mass(pc.pair, |i| {
                bodies[i].map_or_else(|| self.block_mass(i), |body| body_mass[body as usize])
            }) else {
                continue;
            };
            let in_impact = self.state.contacts.contacts[pc.start as usize..pc.end as usize]
                .iter()
                .filter(|c| self.in_impact(c, speed))
                .count() as u32;
            if in_impact > 0 {
                let duration =
                    std::f64::consts::PI * (m / (f64::from(in_impact) * p.normal_penalty)).sqrt();
                room = room.min(duration / f64::from(n_steps));
            }
        }
        room
    }

    /// The reduced mass m of `pair`'s blocks (the free block's against a fixed one) and
    /// the speed past which their contacts are in impact, 2 g sqrt(m / p): twice the
    /// speed at which a contact set down unloaded rings under the weight it carries, so
    /// that resting contacts are not in impact (0 without gravity: every contact moving
    /// along its normal is). None if neither block is free.
    pub(crate) fn impact_speed(&self, pair: dda_contact::NeighbourPair) -> Option<(f64, f64)> {
        let p = &self.model.params;
        let g = p.gravity.map_or(0.0, |g| g.length());
        let m = self.reduced_mass(pair, |i| self.block_mass(i))?;
        Some((m, 2.0 * g * (m / p.normal_penalty).sqrt()))
    }

    /// The reduced mass of `pair`'s blocks, each of mass `mass` (the free block's
    /// against a fixed one); None if neither block is free.
    fn reduced_mass(
        &self,
        pair: dda_contact::NeighbourPair,
        mass: impl Fn(usize) -> f64,
    ) -> Option<f64> {
        let of = |i: u32| self.free[i as usize].map(|_| mass(i as usize));
        match (of(pair.a), of(pair.b)) {
            (Some(ma), Some(mb)) => Some(ma * mb / (ma + mb)),
            (Some(m), None) | (None, Some(m)) => Some(m),
            (None, None) => None,
        }
    }

    /// Whether contact `c` is in impact at the step's start: active, and its vertex
    /// approaching the edge, or leaving it while the contact is closed, faster than
    /// `speed` ([`Simulation::impact_speed`]), by the blocks' velocities.
    pub(crate) fn in_impact(&self, c: &dda_contact::Contact, speed: f64) -> bool {
        if !c.active {
            return false;
        }
        let k = c.key;
        let (vs, es) = (
            &self.scratch.shapes[k.vertex_block as usize],
            &self.scratch.shapes[k.edge_block as usize],
        );
        let at = vs.vertices[k.vertex as usize];
        let t = es.tangents[k.edge as usize];
        let normal = DVec2::new(t.y, -t.x);
        let velocity = |i: usize, shape: &dda_contact::BlockShape| {
            point_displacement(at, shape.centroid, &self.state.blocks[i].velocity)
        };
        let v_n = (velocity(k.vertex_block as usize, vs) - velocity(k.edge_block as usize, es))
            .dot(normal);
        v_n < -speed || (c.state.is_closed() && v_n > speed)
    }

    /// Largest vertex displacement (first order; a block in flight's in d_max's terms,
    /// scaled by d_max over its own bound, [`Simulation::set_flight_room`]) and largest
    /// |rotation| of a block the rotation limit holds ([`Simulation::mark_turn_limited`])
    /// of the trial solution, driven blocks included, and the block nearest its limits.
    pub(crate) fn largest_motion(&self) -> (f64, f64, Option<usize>) {
        let (mut disp, mut rot) = (0.0f64, 0.0f64);
        let (mut worst, mut worst_ratio) = (None, 0.0);
        let p = &self.model.params;
        for (i, s) in self.scratch.shapes.iter().enumerate() {
            if self.free[i].is_none() && !self.model.blocks[i].driven {
                continue;
            }
            let d = &self.scratch.d[i];
            let turn = if self.scratch.turn_limited[i] {
                d[2].abs()
            } else {
                0.0
            };
            rot = rot.max(turn);
            let mut block_disp = largest_vertex_motion(s, d);
            // In d_max's terms (`Simulation::set_flight_room`).
            block_disp *= p.d_max / self.scratch.flight_room[i];
            disp = disp.max(block_disp);
            let ratio = (block_disp / p.d_max).max(turn / p.theta_max);
            if ratio > worst_ratio {
                (worst, worst_ratio) = (Some(i), ratio);
            }
        }
        (disp, rot, worst)
    }
}

/// The largest motion of a vertex of block `s` under `d` (a velocity, or a step's
/// motion; strain included).
fn largest_vertex_motion(s: &dda_contact::BlockShape, d: &Vec6) -> f64 {
    s.vertices
        .iter()
        .map(|&x| point_displacement(x, s.centroid, d).length())
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::{GROWTH_TARGET, MAX_GROWTH, easy_oci, step_growth};

    /// An easy step's bound lies within the OCI bound, never falls as that bound grows,
    /// and is 4 of the paper's 6 (two thirds, rounded up).
    #[test]
    fn the_easy_bound_lies_within_the_oci_bound() {
        for m in 1..=100 {
            let e = easy_oci(m);
            assert!((1..=m).contains(&e), "max_oci {m}: {e}");
            assert!(m == 1 || e >= easy_oci(m - 1), "max_oci {m}: {e}");
        }
        assert_eq!(easy_oci(6), 4);
    }

    /// dt grows only after an easy step, by at most `MAX_GROWTH`, and never so far that
    /// the step's motion scaled with dt passes `GROWTH_TARGET` of d_max or theta_max;
    /// below that it grows as far as either allows.
    #[test]
    fn dt_grows_only_within_the_motion_bounds() {
        let (d_max, theta_max) = (0.01, 0.02);
        assert_eq!(step_growth(5, 6, 0.0, 0.0, d_max, theta_max), 1.0);
        assert_eq!(step_growth(4, 6, 0.0, 0.0, d_max, theta_max), MAX_GROWTH);
        for i in 0..=40 {
            for j in 0..=40 {
                let (disp, rot) = (d_max * i as f64 / 40.0, theta_max * j as f64 / 40.0);
                let g = step_growth(4, 6, disp, rot, d_max, theta_max);
                assert!((1.0..=MAX_GROWTH).contains(&g), "{disp} {rot}: {g}");
                let reach = (g * disp / d_max).max(g * rot / theta_max);
                if g > 1.0 {
                    assert!(
                        reach <= GROWTH_TARGET * (1.0 + 1e-15),
                        "{disp} {rot}: {reach}"
                    );
                }
                if g < MAX_GROWTH {
                    // Held back: the motion already reaches the target or beyond.
                    assert!(
                        reach >= GROWTH_TARGET * (1.0 - 1e-15),
                        "{disp} {rot}: {reach}"
                    );
                }
            }
        }
    }
}
