//! Optics: materials, stacks and the transfer-matrix solver.

pub mod material;
pub mod solver;
pub mod stack;
pub mod twoport;

pub use material::{Dispersion, IndexTable, Material};
pub use solver::{normal_index, solve, solve_amplitudes, Amplitudes, Response};
pub use stack::{Layer, Stack};
