//! Optimisation: initialisation, the coarse orientation search, the parameters'
//! tangent-space updates, the coarse-to-fine schedule and the optimisers (Adam;
//! Gauss–Newton/LM).

pub mod adam;
pub mod init;
pub mod lm;
pub mod params;
pub mod schedule;
pub mod search;
