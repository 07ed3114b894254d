//! Geometry layer of dda-rs: convex polygons, the paper's vertex-edge measures, entrance
//! blocks and cutting of regions by joint sets.
//!
//! Everything here is `f64` and free of I/O. A [`ConvexPolygon`] that exists is valid
//! (counter-clockwise, convex, no degenerate edge), so code that receives one never checks
//! it again. The entrance block E(A,B) = B - A + a0 of the cover-based contact detection
//! (Zhuang, Zheng et al. 2021, section 2.1) is built in O(n + m) by merging edge directions,
//! each of its faces tagged with the vertex-edge or edge-vertex pair (contact cover) it
//! comes from.

mod aabb;
mod cut;
mod entrance;
mod error;
mod groups;
mod mass;
mod measures;
mod polygon;
pub mod shapes;
#[cfg(feature = "test-support")]
pub mod test_support;

pub use self::aabb::Aabb;
pub use self::cut::{Cutting, JointSet, Line, Split, cut_by_joint_sets, cut_by_lines, split};
pub use self::entrance::{
    CoverSource, EntranceBlock, EntranceFace, SignedDistance, d_re, d_re1, for_each_face,
    signed_distance,
};
pub use self::error::{JointSetError, PolygonError};
pub use self::groups::Groups;
pub use self::mass::{Joint, JointFamily, MassCutting, Outline, Piece, cut_mass};
pub use self::measures::{
    ContactSubregion, VertexEdge, contact_region, entrance_filter, node_distances, normal_distance,
    outward_normal, projection_ratio,
};
pub use self::polygon::{
    ConvexPolygon, DEFAULT_REL_TOL, Moments, Motion, PolygonOptions, Repairs, check_displacement,
    displace_point, separation,
};

/// 2D vector type used throughout (glam's `DVec2`, f64).
pub use glam::DVec2;
