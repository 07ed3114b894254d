//! Helpers shared by the unit tests of the detectors.

use crate::neighbour::NeighbourPair;
use crate::shape::BlockShape;
use dda_geom::ConvexPolygon;

/// The pair of blocks 0 and 1.
pub const IDS: NeighbourPair = NeighbourPair { a: 0, b: 1 };

/// The shape of a test polygon given by `[x, y]` vertices.
pub fn shape(c: &[[f64; 2]]) -> BlockShape {
    BlockShape::new(&ConvexPolygon::from_coords(c).expect("valid test polygon"))
}
