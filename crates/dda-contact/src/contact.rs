//! The contact data structure (paper fig. 12): block -> neighbour pairs -> contact list ->
//! contact {vertex, edge, activity, state, locked point, ...}.
//!
//! Every contact, vertex-edge or edge-vertex alike, is stored as "vertex of one block
//! against edge of another", so its [`ContactKey`] names it the same way from step to step
//! and from either side of the pair; that is how states are inherited.

use crate::neighbour::NeighbourPair;
use serde::{Deserialize, Serialize};

/// The identity of a contact: vertex `vertex` of block `vertex_block` against edge `edge`
/// (from vertex `edge` to `edge + 1`) of block `edge_block`. Stable across steps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct ContactKey {
    /// Block owning the vertex.
    pub vertex_block: u32,
    /// Vertex index in that block.
    pub vertex: u32,
    /// Block owning the edge.
    pub edge_block: u32,
    /// Edge index in that block.
    pub edge: u32,
}

impl ContactKey {
    /// The neighbour pair the contact belongs to.
    #[inline]
    pub fn pair(&self) -> NeighbourPair {
        NeighbourPair::new(self.vertex_block, self.edge_block)
    }
}

/// Mechanical state of a contact (paper section 2.3; Shi 1988).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum ContactState {
    /// No spring.
    #[default]
    Open,
    /// Closed, no relative sliding: normal and shear springs.
    Locked,
    /// Closed, sliding: normal spring plus friction force.
    Sliding,
}

impl ContactState {
    /// Whether the contact transmits force (locked or sliding).
    #[inline]
    pub fn is_closed(self) -> bool {
        self != ContactState::Open
    }
}

/// One candidate contact of a step.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Contact {
    /// Which vertex against which edge.
    pub key: ContactKey,
    /// Perpendicular distance d_n at step start (paper eq. 7), positive outside.
    pub d_n: f64,
    /// Projection ratio r at step start (paper eq. 8).
    pub r: f64,
    /// Whether the contact may carry springs this step (eq. 11 or trajectory tracking).
    pub active: bool,
    /// Open, locked or sliding.
    pub state: ContactState,
    /// Where on the edge the vertex is locked, as a ratio along it (the shear spring's
    /// anchor); set by the engine when the contact locks.
    pub locked_r: f64,
    /// Direction of sliding along the edge (+1 towards `edge + 1`, -1 back, 0 unknown),
    /// kept by the engine for the friction force.
    pub slide_dir: f64,
    /// Whether cohesion and tensile strength still hold (lost for good once broken).
    pub bonded: bool,
    /// Compressive normal force of the last solve, N (positive pushing the blocks apart),
    /// kept by the engine for the friction of a sliding contact.
    pub normal_force: f64,
    /// Whether the contact stands for two vertices meeting (a vertex-vertex contact of a
    /// conventional detector, resolved to one entrance edge): it carries a normal spring
    /// only, with no shear spring, friction, cohesion or tension, as in Shi's code (two
    /// corners have no contact length, and the entrance edge chosen is only one of two).
    #[serde(default)]
    pub vertex_vertex: bool,
}

impl Contact {
    /// A fresh contact at step start: open if d_n >= 0, else locked at its projection.
    pub fn new(key: ContactKey, d_n: f64, r: f64, active: bool) -> Self {
        let state = if d_n >= 0.0 {
            ContactState::Open
        } else {
            ContactState::Locked
        };
        Contact {
            key,
            d_n,
            r,
            active,
            state,
            locked_r: r,
            slide_dir: 0.0,
            bonded: false,
            normal_force: 0.0,
            vertex_vertex: false,
        }
    }
}

/// The contacts of one neighbour pair: a range of [`ContactSet::contacts`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct PairContacts {
    /// The pair.
    pub pair: NeighbourPair,
    /// First contact of the pair.
    pub start: u32,
    /// One past its last contact.
    pub end: u32,
    /// Whether the pair overlapped deeper than d_tol at step start with a closed contact
    /// kept from the last step (the cover detector's deep rule, `cover::deep_covers`):
    /// its spring then follows the deepest face during open-close iteration.
    pub deep: bool,
}

/// All candidate contacts of a step, grouped by neighbour pair; pairs sorted, contacts of
/// a pair sorted by key. Deterministic whatever the thread count.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ContactSet {
    /// Pairs with at least one candidate, sorted.
    pub pairs: Vec<PairContacts>,
    /// The candidates, pair by pair.
    pub contacts: Vec<Contact>,
}

impl ContactSet {
    /// Empties the set, keeping its buffers.
    pub fn clear(&mut self) {
        self.pairs.clear();
        self.contacts.clear();
    }

    /// Number of candidate contacts.
    pub fn len(&self) -> usize {
        self.contacts.len()
    }

    /// Whether there are no candidates.
    pub fn is_empty(&self) -> bool {
        self.contacts.is_empty()
    }

    /// The candidates of pair entry `k`.
    pub fn of_pair(&self, k: usize) -> &[Contact] {
        let p = &self.pairs[k];
        &self.contacts[p.start as usize..p.end as usize]
    }

    /// The contact with `key`, if it is a candidate.
    pub fn find(&self, key: &ContactKey) -> Option<&Contact> {
        self.with_pair(key.pair()).iter().find(|c| c.key == *key)
    }

    /// The candidates of a neighbour pair (sorted by key; empty if it has none).
    pub fn with_pair(&self, pair: NeighbourPair) -> &[Contact] {
        match self.pairs.binary_search_by(|p| p.pair.cmp(&pair)) {
            Ok(k) => self.of_pair(k),
            Err(_) => &[],
        }
    }

    /// Active contacts.
    pub fn active(&self) -> impl Iterator<Item = &Contact> {
        self.contacts.iter().filter(|c| c.active)
    }

    /// Number of active and closed contacts.
    pub fn closed_count(&self) -> usize {
        self.active().filter(|c| c.state.is_closed()).count()
    }
}
