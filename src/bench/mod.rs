//! Speed against error: every way `irid` (and the analytic model renderers
//! use) can turn a film into a colour, timed per shading evaluation and
//! measured against the exact reference, plus the grid workload the Python
//! peers are timed on and inverse design's gradient and fit speed.

pub mod grid;
pub mod inverse;
pub mod machine;
pub mod plot;
pub mod renders;
pub mod report;
pub mod rough;
pub mod run;
pub mod stacks;
pub mod tables;
