//! Ground motion (docs/scene-format.md, "Seismic input"; docs/method.md section 11).
//!
//! A `[seismic]` record gives the ground's acceleration at sample times; between samples
//! it is held linear, before the first sample and after the last it is zero. The
//! ground's velocity and displacement are its exact integrals from rest at t = 0 (a
//! quadratic and a cubic on each interval), so a step of any size moves the driven
//! blocks by exactly the record's displacement over it, whatever the record's sampling.
//!
//! The driven blocks have no unknowns: in a step from t to t + dt each moves by the
//! ground's displacement `u(t + dt) - u(t)`. A contact row couples a free block to a
//! driven one through a known motion, so that motion is folded into the row's value
//! (`Row::driven`, see `springs`) and the free blocks respond through their contacts.
//! The ground does work on the free blocks through those contacts; the physics guard
//! counts it as supplied energy (`Simulation::ground_work`).

use crate::assembly::StepRule;
use crate::limits;
use crate::simulation::Simulation;
use dda_geom::DVec2;

/// A validated ground motion: the record's samples with the velocity and displacement
/// integrated to each, and the blocks that follow it.
#[derive(Clone, Debug, PartialEq)]
pub struct GroundMotion {
    /// Sample times, s, increasing from 0 or later.
    t: Vec<f64>,
    /// Acceleration at each sample (scaled), m/s^2.
    a: Vec<DVec2>,
    /// Velocity at each sample, m/s.
    v: Vec<DVec2>,
    /// Displacement at each sample, m.
    u: Vec<DVec2>,
    /// The blocks that follow the ground (scene indices, increasing).
    pub blocks: Vec<usize>,
}

impl GroundMotion {
    /// The ground motion of `samples` (rows `[t, ax, ay]` that passed [`check_samples`])
    /// multiplied by `scale`, followed by `blocks`.
    pub fn new(samples: &[[f64; 3]], scale: f64, blocks: Vec<usize>) -> Self {
        let n = samples.len();
        let (mut t, mut a) = (Vec::with_capacity(n), Vec::with_capacity(n));
        for s in samples {
            t.push(s[0]);
            a.push(scale * DVec2::new(s[1], s[2]));
        }
        let (mut v, mut u) = (vec![DVec2::ZERO; n], vec![DVec2::ZERO; n]);
        for k in 1..n {
            let h = t[k] - t[k - 1];
            v[k] = v[k - 1] + 0.5 * h * (a[k - 1] + a[k]);
            u[k] = u[k - 1] + h * v[k - 1] + h * h * (a[k - 1] / 3.0 + a[k] / 6.0);
        }
        GroundMotion { t, a, v, u, blocks }
    }

    /// The ground's displacement and velocity at time `t`.
    pub fn at(&self, t: f64) -> (DVec2, DVec2) {
        // The last sample at or before t.
        let k = self.t.partition_point(|&s| s <= t);
        if k == 0 {
            // Before the first sample: at rest.
            return (DVec2::ZERO, DVec2::ZERO);
        }
        let k = k - 1;
        let tau = t - self.t[k];
        let (a0, v0, u0) = (self.a[k], self.v[k], self.u[k]);
        if k + 1 == self.t.len() {
            // After the last sample the acceleration is zero.
            return (u0 + tau * v0, v0);
        }
        let slope = (self.a[k + 1] - a0) / (self.t[k + 1] - self.t[k]);
        let v = v0 + tau * a0 + 0.5 * tau * tau * slope;
        let u = u0 + tau * v0 + 0.5 * tau * tau * a0 + tau * tau * tau / 6.0 * slope;
        (u, v)
    }

    /// The ground's velocity after the record ends, and the largest speed it reaches
    /// at a sample before: a record that is not baseline-corrected leaves the ground
    /// moving on.
    pub fn end_and_peak_velocity(&self) -> (DVec2, f64) {
        let end = self.v.last().copied().unwrap_or(DVec2::ZERO);
        (end, self.v.iter().map(|v| v.length()).fold(0.0, f64::max))
    }

    /// The ground's displacement from `t0` to `t1`.
    pub fn displacement(&self, t0: f64, t1: f64) -> DVec2 {
        self.at(t1).0 - self.at(t0).0
    }
}

/// Checks a record's samples `[t, ax, ay]`: at least one, every value finite, times
/// from 0 on and strictly increasing, accelerations within [`limits::GRAVITY`]. The
/// error gives the index of the first bad sample and what is wrong with it.
pub fn check_samples(samples: &[[f64; 3]]) -> Result<(), LineError> {
    if samples.is_empty() {
        return Err((0, "the record has no samples".into()));
    }
    if samples.len() as f64 > limits::MAX_RECORD_SAMPLES {
        return Err((
            0,
            format!(
                "the record has {} samples, more than {:e}",
                samples.len(),
                limits::MAX_RECORD_SAMPLES
            ),
        ));
    }
    for (i, s) in samples.iter().enumerate() {
        if !limits::RECORD_TIME.contains(s[0]) {
            return Err((i, format!("time: {}", limits::RECORD_TIME.message(s[0]))));
        }
        if i > 0 && s[0] <= samples[i - 1][0] {
            return Err((
                i,
                format!(
                    "times must increase: {} s follows {} s",
                    s[0],
                    samples[i - 1][0]
                ),
            ));
        }
        for (c, name) in [(1, "ax"), (2, "ay")] {
            if !limits::GRAVITY.contains(s[c]) {
                return Err((i, format!("{name}: {}", limits::GRAVITY.message(s[c]))));
            }
        }
    }
    Ok(())
}

/// A fault at a line (1-based) or sample (0-based) of a record, and what it is.
pub type LineError = (usize, String);

/// Reads a record file's text: comma-separated `t, ax, ay` rows, a header line first
/// (a first line whose cells are all numbers is taken as data), blank lines and lines
/// starting with `#` skipped. The error gives the 1-based line and what is wrong; the
/// values are checked by [`check_samples`] (its index mapped to the line by the second
/// vector returned).
pub fn read_record(text: &str) -> Result<(Vec<[f64; 3]>, Vec<usize>), LineError> {
    let (mut samples, mut lines) = (Vec::new(), Vec::new());
    let mut first = true;
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let numbers: Vec<Option<f64>> = cells.iter().map(|c| c.parse::<f64>().ok()).collect();
        if std::mem::take(&mut first) && numbers.iter().any(Option::is_none) {
            // The header.
            continue;
        }
        if cells.len() != 3 {
            // A spreadsheet in a language that writes decimal commas separates its
            // cells by semicolons.
            let hint = if line.contains(';') {
                "; the line has semicolons: write the record with decimal points and cells \
                 separated by commas"
            } else {
                ""
            };
            return Err((
                i + 1,
                format!(
                    "{} cells, expected 3 (t, ax, ay separated by commas){hint}",
                    cells.len()
                ),
            ));
        }
        let mut row = [0.0; 3];
        for (c, (x, name)) in numbers.iter().zip(["t", "ax", "ay"]).enumerate() {
            row[c] = x.ok_or_else(|| {
                (
                    i + 1,
                    format!("column {name}: `{}` is not a number", cells[c]),
                )
            })?;
        }
        samples.push(row);
        lines.push(i + 1);
        if samples.len() as f64 > limits::MAX_RECORD_SAMPLES {
            return Err((
                i + 1,
                format!("more than {:e} samples", limits::MAX_RECORD_SAMPLES),
            ));
        }
    }
    Ok((samples, lines))
}

impl Simulation {
    /// The driven blocks' motion over the first half and over the whole of a step of
    /// `dt` from now; None without ground motion.
    pub(crate) fn ground_step(&self, dt: f64) -> Option<(DVec2, DVec2)> {
        let g = self.model.ground.as_ref()?;
        let t = self.state.t;
        Some((g.displacement(t, t + 0.5 * dt), g.displacement(t, t + dt)))
    }

    /// The work the ground does on the free blocks in the trial step, through the
    /// springs and friction forces of contacts with driven blocks, `e` being a row's
    /// driven part (the driven block's motion along it): a spring of penalty p takes
    /// p q e from the ground, q its value at the end of the step; a friction force f
    /// takes -f e. The physics guard adds it to the energy supplied.
    ///
    /// The force is the end of the step's because that is the force the scheme applies:
    /// constant acceleration from end-of-step forces makes a free block's kinetic energy
    /// gain p q c . D exactly, and then the spring's energy, its gain from the blocks and
    /// this work balance to -p (q - q0)^2 / 2, never positive, as for springs between
    /// free blocks. The mid-step force would leave p e (q - q0) / 2 unaccounted, of
    /// either sign: on tests/scenes/quake.toml it read as 2.3% of the reference energy
    /// created at t = 0.053 s, and stopped the run. Under the average-acceleration rule
    /// the force is the step's mean, and so is the work's.
    pub(crate) fn ground_work(&self) -> f64 {
        if self.model.ground.is_none() {
            return 0.0;
        }
        // Under the average-acceleration rule a step's force is the mean of its start's
        // and its end's (docs/method.md section 12), and so is the ground's.
        let average = self.step_rule() == StepRule::Average;
        let mut work = 0.0;
        let driven = |b: u32| self.model.blocks[b as usize].driven;
        for s in &self.scratch.springs {
            // Only a spring with a driven block has a driven part (and a row worth making).
            let key = self.state.contacts.contacts[s.contact as usize].key;
            if !(driven(key.vertex_block) || driven(key.edge_block)) {
                continue;
            }
            let row = self.spring_row(s);
            if row.driven != 0.0 {
                let mut q = row.eval(&self.scratch.d);
                // The dashpot's force, p beta / dt (q - q_ref), on the change of q over the
                // step from where the blocks touched (no dashpot under the
                // average-acceleration rule).
                let dashpot = s.viscous * (q - crate::assembly::dashpot_base(&row));
                if average {
                    q = 0.5 * (q + row.g0 - row.driven);
                }
                work += s.penalty * (q + dashpot) * row.driven;
            }
        }
        for (_, f, row) in &self.scratch.forces {
            work -= f * row.driven;
        }
        work
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The integrals are exact for a record linear between samples: a constant
    /// acceleration gives u = a t^2 / 2, a ramp a = k t gives u = k t^3 / 6, at sample
    /// times and between, and after the record the ground keeps its last velocity.
    #[test]
    fn integration_is_exact_for_piecewise_linear_records() {
        let constant = GroundMotion::new(&[[0.0, 2.0, -1.0], [1.0, 2.0, -1.0]], 1.0, vec![]);
        for t in [0.0, 0.25, 0.5, 1.0] {
            let (u, v) = constant.at(t);
            assert!((u - DVec2::new(t * t, -0.5 * t * t)).length() < 1e-15);
            assert!((v - DVec2::new(2.0 * t, -t)).length() < 1e-15);
        }
        // After the end: velocity (2, -1) kept, displacement grows linearly.
        let (u, v) = constant.at(3.0);
        assert!((v - DVec2::new(2.0, -1.0)).length() < 1e-15);
        assert!((u - DVec2::new(1.0 + 2.0 * 2.0, -0.5 - 2.0)).length() < 1e-14);
        let ramp = GroundMotion::new(
            &[[0.0, 0.0, 0.0], [0.5, 1.5, 0.0], [2.0, 6.0, 0.0]],
            1.0,
            vec![],
        );
        for t in [0.1, 0.5, 0.9, 1.7, 2.0] {
            let (u, v) = ramp.at(t);
            assert!((u.x - 3.0 * t * t * t / 6.0).abs() < 1e-14, "{t}: {u}");
            assert!((v.x - 1.5 * t * t).abs() < 1e-14, "{t}: {v}");
        }
        // Scale multiplies; a record starting later leaves the ground at rest until then.
        let late = GroundMotion::new(&[[1.0, 1.0, 0.0], [2.0, 1.0, 0.0]], 3.0, vec![]);
        assert_eq!(late.at(0.5), (DVec2::ZERO, DVec2::ZERO));
        assert!((late.at(2.0).0.x - 1.5).abs() < 1e-15);
    }

    /// A record is read line by line: the header skipped, every bad line reported by
    /// its number.
    #[test]
    fn records_report_their_bad_lines() {
        let (s, lines) = read_record("t,ax,ay\n0,0,0\n\n# note\n0.1, 1.5, -2\n").unwrap();
        assert_eq!(s, vec![[0.0, 0.0, 0.0], [0.1, 1.5, -2.0]]);
        assert_eq!(lines, vec![2, 5]);
        // No header: the first line is data.
        assert_eq!(read_record("0,1,2\n").unwrap().0, vec![[0.0, 1.0, 2.0]]);
        let err = read_record("t,ax,ay\n0,0,0\n0.1,x,0\n").unwrap_err();
        assert_eq!(err.0, 3);
        assert!(err.1.contains("ax") && err.1.contains("`x`"), "{}", err.1);
        assert_eq!(read_record("t,ax,ay\n0,0\n").unwrap_err().0, 2);
        // A spreadsheet's record with decimal commas and semicolons: told so.
        let err = read_record("t;ax;ay\n0,00;0,0;0,0\n").unwrap_err();
        assert_eq!(err.0, 2);
        assert!(err.1.contains("semicolons"), "{}", err.1);
        let (s, _) = read_record("t,ax,ay\n0,0,0\n0.2,0,0\n0.1,0,0\n").unwrap();
        assert_eq!(check_samples(&s).unwrap_err().0, 2);
        assert!(check_samples(&[[0.0, f64::NAN, 0.0]]).is_err());
        assert!(check_samples(&[[-1.0, 0.0, 0.0]]).is_err());
        assert!(check_samples(&[]).is_err());
    }
}
