//! Contact layer of dda-rs: neighbour search, the contact data structure, and the
//! pluggable [`ContactDetector`] with three implementations: the cover-based detector of
//! Zhuang, Zheng et al. (2021), [`CoverDetector`], and two conventional type-based
//! detectors, [`TerritoryDetector::type1`] and [`TerritoryDetector::type2`].
//!
//! One step of detection: block shapes ([`BlockShape`]) -> neighbour pairs
//! ([`neighbour_pairs`], AABBs grown by d_tol) -> per pair, the detector's candidate
//! contacts with their initial activity -> states inherited from the previous step
//! ([`detect`]). During open-close iteration the engine asks which inactive candidates
//! the trial displacements make active (trajectory tracking, paper eq. 12-13): [`track`],
//! or a [`TrackList`] made once per step, which finds the same for less work.
//! The mechanics (springs, Mohr-Coulomb) belong to the engine, not here.

mod box_trees;
mod contact;
mod cover;
mod detector;
mod neighbour;
mod shape;
mod territory;
pub mod tracking;

#[cfg(test)]
mod test_util;

pub use self::box_trees::BoxTrees;
pub use self::contact::{Contact, ContactKey, ContactSet, ContactState, PairContacts};
pub use self::cover::CoverDetector;
pub use self::detector::{
    ContactDetector, DETECTOR_NAMES, DetectionParams, TrackList, UnknownDetector, detect,
    detector_by_name, track,
};
pub use self::neighbour::{NeighbourPair, NeighbourSearch, neighbour_pairs};
pub use self::shape::BlockShape;
pub use self::territory::{Territory, TerritoryDetector};
