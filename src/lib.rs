//! dda-rs: Discontinuous Deformation Analysis of 2D convex polygonal rock blocks with
//! pluggable contact detection (cover-based, after Zhuang, Zheng et al. 2021, and the two
//! conventional type-based detectors).
//!
//! This facade re-exports the layers; each can also be used alone:
//! - [`geom`]: convex polygons, entrance blocks, cutting by joint sets.
//! - [`contact`]: neighbour search, the contact detectors (cover, type-1, type-2).

pub use dda_contact as contact;
pub use dda_geom as geom;
