//! Contact geometry, knowing no dynamics: terrain shapes as signed distances
//! ([`shape`]), the contacts of a bar's capsule with one of them ([`capsule`]), and the
//! penalty force of one contact point ([`law`]) with friction that sticks ([`grip`]), the
//! closest points of two bars with the broad phase that finds the pairs worth testing
//! ([`segments`]), and the marks that skip terrain contacts too far to begin soon
//! ([`proximity`]). The model builds these once from the scene; the dynamics stage in
//! `dynamics::terrain` runs them.

pub mod capsule;
pub mod grip;
pub mod law;
pub mod proximity;
pub mod segments;
pub mod shape;

pub use capsule::{capsule_contacts, interior_excess, Contact};
pub use grip::Grip;
pub use law::Penalty;
pub use proximity::Proximity;
pub use shape::{Grid, Shape};
