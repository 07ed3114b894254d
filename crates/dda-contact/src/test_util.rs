//! Helpers shared by the unit tests of the detectors.

use crate::contact::{Contact, ContactKey, ContactSet, PairContacts};
use crate::neighbour::NeighbourPair;
use crate::shape::BlockShape;
use dda_geom::ConvexPolygon;

/// The pair of blocks 0 and 1.
pub const IDS: NeighbourPair = NeighbourPair { a: 0, b: 1 };

/// The shape of a test polygon given by `[x, y]` vertices.
pub fn shape(c: &[[f64; 2]]) -> BlockShape {
    BlockShape::new(&ConvexPolygon::from_coords(c).expect("valid test polygon"))
}

/// A key as (vertex block, vertex, edge block, edge), for compact assertions.
pub fn tuple(k: ContactKey) -> (u32, u32, u32, u32) {
    (k.vertex_block, k.vertex, k.edge_block, k.edge)
}

/// A previous step's contact set: pair [`IDS`] holding `contacts` (sorted by key).
pub fn pair_set(contacts: Vec<Contact>) -> ContactSet {
    ContactSet {
        pairs: vec![PairContacts {
            pair: IDS,
            start: 0,
            end: contacts.len() as u32,
            deep: false,
        }],
        contacts,
    }
}
