//! Why a run stops ([`SimError`]) and what was involved ([`Diagnosis`]: the blocks
//! and contacts named in summary.json's `failure`).

use crate::simulation::Simulation;
use crate::solver::SolveError;
use dda_contact::ContactState;
use serde::{Deserialize, Serialize};

/// Why a simulation cannot go on; the state stays at the last completed step.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// The time step shrank below its floor without a step converging.
    #[error("time step collapsed to {dt:.3e} s at t = {t:.6} s: {reason} (last good state kept)")]
    TimeStepCollapsed {
        /// Simulated time of the last good state.
        t: f64,
        /// The step size that failed.
        dt: f64,
        /// What kept failing.
        reason: String,
    },
    /// The global system could not be solved.
    #[error("at t = {t:.6} s: {source} (last good state kept)")]
    Solve {
        /// Simulated time of the last good state.
        t: f64,
        /// The solver's error.
        source: SolveError,
    },
    /// The solution of the global system is not finite (NaN or infinite).
    #[error(
        "at t = {t:.6} s: the solution is not finite for block `{block}` (last good state kept)"
    )]
    NonFinite {
        /// Simulated time of the last good state.
        t: f64,
        /// Id of the first block with a non-finite motion.
        block: String,
    },
    /// A block would be turned inside out by the step.
    #[error("at t = {t:.6} s: block `{block}` would be inverted (last good state kept)")]
    Inverted {
        /// Simulated time of the last good state.
        t: f64,
        /// Block id.
        block: String,
    },
    /// The step would break physics: a penetration deeper than d_tol, or energy created
    /// beyond [`crate::ENERGY_TOLERANCE`] ([`crate::RunOptions::stop_on_violation`]).
    #[error("at t = {t:.6} s: {what} (last good state kept)")]
    BrokenPhysics {
        /// Simulated time of the last good state.
        t: f64,
        /// What broke, in words.
        what: String,
        /// Ids of the blocks involved.
        blocks: Vec<String>,
    },
    /// Settling the blocks before a dynamic run failed (`analysis.settle`).
    #[error(
        "settling the blocks at t = 0 failed: {reason} (set analysis.settle = false to start \
         from the blocks as written)"
    )]
    Settle {
        /// Why the settling step failed.
        reason: String,
    },
}

/// What a failed run was doing when it stopped: which blocks and contacts were involved
/// and the step size that failed (summary.json's `failure`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Diagnosis {
    /// The error, in words.
    pub reason: String,
    /// Simulated time of the last good state, s.
    pub t: f64,
    /// The step size of the last failed attempt, s.
    pub last_dt: f64,
    /// Ids of the blocks involved (at most [`DIAGNOSIS_LIMIT`]).
    pub blocks: Vec<String>,
    /// The contacts involved (at most [`DIAGNOSIS_LIMIT`]).
    pub contacts: Vec<ContactNote>,
}

/// Most blocks and contacts a [`Diagnosis`] lists.
pub const DIAGNOSIS_LIMIT: usize = 20;

/// A contact named in a [`Diagnosis`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ContactNote {
    /// Id of the block owning the vertex.
    pub vertex_block: String,
    /// Vertex index in that block.
    pub vertex: u32,
    /// Id of the block owning the edge.
    pub edge_block: String,
    /// Edge index in that block (from vertex `edge` to `edge + 1`).
    pub edge: u32,
    /// State at the last good state: "open", "locked" or "sliding".
    pub state: String,
    /// Normal distance at the start of the failed step, m (negative: penetrating).
    pub d_n: f64,
}

impl Simulation {
    /// Records what was involved in the failure `e`: for an OCI that did not converge,
    /// the contacts still changing state and their blocks; for a step too large, the
    /// block that moved most; for an inverted or non-finite block, that block and its
    /// contacts.
    pub(crate) fn diagnose(&mut self, e: &SimError, last_dt: f64, worst: Option<usize>) {
        let index = |id: &str| self.model.blocks.iter().position(|b| b.id == id);
        let mut blocks: Vec<usize> = Vec::new();
        let mut contacts: Vec<usize> = Vec::new();
        match e {
            SimError::TimeStepCollapsed { reason, .. } if reason.contains("open-close") => {
                contacts.extend(self.scratch.flipped.iter().map(|&k| k as usize));
            }
            SimError::TimeStepCollapsed { .. } => blocks.extend(worst),
            SimError::Inverted { block, .. } | SimError::NonFinite { block, .. } => {
                blocks.extend(index(block));
            }
            SimError::BrokenPhysics { blocks: ids, .. } => {
                blocks.extend(ids.iter().filter_map(|id| index(id)));
            }
            _ => {}
        }
        if contacts.is_empty() {
            // The closed contacts of the blocks named.
            contacts.extend((0..self.state.contacts.len()).filter(|&k| {
                let c = &self.state.contacts.contacts[k];
                let key = c.key;
                c.active
                    && c.state.is_closed()
                    && blocks
                        .iter()
                        .any(|&b| b == key.vertex_block as usize || b == key.edge_block as usize)
            }));
        }
        contacts.truncate(DIAGNOSIS_LIMIT);
        for &k in &contacts {
            let key = self.state.contacts.contacts.get(k).map(|c| c.key);
            if let Some(key) = key {
                for b in [key.vertex_block as usize, key.edge_block as usize] {
                    if !blocks.contains(&b) {
                        blocks.push(b);
                    }
                }
            }
        }
        blocks.truncate(DIAGNOSIS_LIMIT);
        let id = |b: usize| self.model.blocks[b].id.clone();
        let notes = contacts
            .iter()
            .filter_map(|&k| self.state.contacts.contacts.get(k))
            .map(|c| ContactNote {
                vertex_block: id(c.key.vertex_block as usize),
                vertex: c.key.vertex,
                edge_block: id(c.key.edge_block as usize),
                edge: c.key.edge,
                state: match c.state {
                    ContactState::Open => "open",
                    ContactState::Locked => "locked",
                    ContactState::Sliding => "sliding",
                }
                .to_string(),
                d_n: c.d_n,
            })
            .collect();
        self.scratch.diagnosis = Some(Diagnosis {
            reason: e.to_string(),
            t: self.state.t,
            last_dt,
            blocks: blocks.into_iter().map(id).collect(),
            contacts: notes,
        });
    }
}
