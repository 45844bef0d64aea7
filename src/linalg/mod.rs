//! Sparse linear algebra over 3 × 3 blocks, knowing nothing of bars or cables: the
//! symbolic pattern, the scalar block `L D Lᵀ` factor and the side-by-side lanes that
//! factor identical uncoupled chains at once. [`crate::model::reactions`] assembles the
//! reaction matrix into them.

pub(crate) mod block_cholesky;
pub(crate) mod block_lanes;
pub(crate) mod pattern;
pub(crate) mod symmetric;
