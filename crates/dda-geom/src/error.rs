//! Errors of the geometry layer: each names the offending vertex or joint set and why.

use std::fmt;

/// Why a list of vertices is not a valid convex polygon. Vertex numbers are 0-based
/// positions in the input list.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum PolygonError {
    /// Fewer than three vertices were given.
    TooFewVertices {
        /// How many were given.
        count: usize,
    },
    /// A coordinate is NaN or infinite.
    NonFinite {
        /// The vertex holding it.
        vertex: usize,
    },
    /// Two vertices coincide (closer than the relative tolerance times the polygon size).
    DuplicateVertex {
        /// The later vertex.
        vertex: usize,
        /// The earlier vertex it coincides with.
        of: usize,
    },
    /// A vertex lies on the line through its neighbours and merging was not allowed.
    CollinearVertex {
        /// The collinear vertex.
        vertex: usize,
    },
    /// The vertices run clockwise and reversing them was not allowed.
    Clockwise,
    /// The polygon turns the wrong way (or doubles back) at a vertex.
    NotConvex {
        /// The vertex at which it turns the wrong way.
        vertex: usize,
    },
    /// Two edges cross each other.
    SelfIntersecting {
        /// First edge (from vertex `edge_a` to the next one).
        edge_a: usize,
        /// Second edge.
        edge_b: usize,
    },
    /// The enclosed area is zero (all vertices on one line) within the tolerance.
    ZeroArea,
    /// A displacement would turn the polygon inside out (Jacobian determinant <= 0).
    Inverted,
}

impl fmt::Display for PolygonError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooFewVertices { count } => {
                write!(f, "a polygon needs at least 3 vertices, got {count}")
            }
            Self::NonFinite { vertex } => {
                write!(f, "vertex {vertex} has a NaN or infinite coordinate")
            }
            Self::DuplicateVertex { vertex, of } => {
                write!(f, "vertex {vertex} coincides with vertex {of}")
            }
            Self::CollinearVertex { vertex } => write!(
                f,
                "vertex {vertex} lies on the line through its neighbours (collinear)"
            ),
            Self::Clockwise => write!(f, "vertices run clockwise; counter-clockwise expected"),
            Self::NotConvex { vertex } => {
                write!(
                    f,
                    "polygon is not convex: it turns the wrong way at vertex {vertex}"
                )
            }
            Self::SelfIntersecting { edge_a, edge_b } => write!(
                f,
                "polygon intersects itself: edge {edge_a} crosses edge {edge_b}"
            ),
            Self::ZeroArea => write!(f, "polygon has zero area (its vertices are collinear)"),
            Self::Inverted => write!(f, "displacement turns the polygon inside out"),
        }
    }
}

impl std::error::Error for PolygonError {}

/// Why a joint set cannot cut a region.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum JointSetError {
    /// Spacing must be finite and positive.
    Spacing {
        /// Index of the joint set.
        set: usize,
        /// The spacing given.
        spacing: f64,
    },
    /// Dip angle or offset is NaN or infinite.
    NonFinite {
        /// Index of the joint set.
        set: usize,
    },
    /// A piece cut by this set failed validation (a numerical defect of the cut).
    Piece {
        /// Index of the joint set.
        set: usize,
        /// What was wrong with the piece.
        error: PolygonError,
    },
    /// The set would make more joints than allowed (a spacing in the wrong unit).
    TooMany {
        /// Index of the joint set.
        set: usize,
        /// The most joints allowed.
        max: usize,
    },
    /// The sliver threshold must be finite and non-negative.
    MinArea {
        /// The threshold given.
        min_area: f64,
    },
}

impl fmt::Display for JointSetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Spacing { set, spacing } => {
                write!(
                    f,
                    "joint set {set}: spacing must be positive, got {spacing}"
                )
            }
            Self::NonFinite { set } => {
                write!(f, "joint set {set}: dip angle and offset must be finite")
            }
            Self::Piece { set, error } => {
                write!(f, "joint set {set} made an invalid piece: {error}")
            }
            Self::TooMany { set, max } => {
                write!(f, "joint set {set} would make more than {max} joints")
            }
            Self::MinArea { min_area } => {
                write!(
                    f,
                    "sliver area threshold must be finite and >= 0, got {min_area}"
                )
            }
        }
    }
}

impl std::error::Error for JointSetError {}
