//! Optimisation: initialisation, the coarse orientation search, the parameters'
//! tangent-space updates and the optimisers (Adam; Gauss–Newton/LM).

pub mod adam;
pub mod init;
pub mod lm;
pub mod params;
pub mod search;
