//! dda-rs: Discontinuous Deformation Analysis of 2D convex polygonal rock blocks with
//! pluggable contact detection (cover-based, after Zhuang, Zheng et al. 2021, and the two
//! conventional type-based detectors).
//!
//! This facade re-exports the layers; each can also be used alone:
//! - [`geom`]: convex polygons, entrance blocks, cutting by joint sets.
//! - [`contact`]: neighbour search, the contact detectors (cover, type-1, type-2).
//! - [`core`]: scenes, effects, the implicit DDA engine.
//! - [`bench`](mod@bench): scene generators and the built-in scenes.
//!
//! - [`report`]: what a run writes for people (frames, plots, report.html).

pub use dda_bench as bench;
pub use dda_contact as contact;
pub use dda_core as core;
pub use dda_geom as geom;
pub use dda_report as report;
