//! Optics: materials, stacks and the transfer-matrix solver.

pub mod gradient;
pub mod incoherent;
pub mod lanes;
pub mod library;
#[rustfmt::skip]
mod library_data;
pub mod material;
pub mod points;
pub mod solver;
pub mod spec;
pub mod stack;
pub mod twoport;

pub use incoherent::{solve_incoherent, solve_mixed, Coherence, Diverged};
pub use material::{Dispersion, IndexTable, Material};
pub use points::{LayerThickness, PointSolver};
pub use solver::{
    normal_index, solve, solve_amplitudes, solve_amplitudes_beta, solve_batch, Amplitudes, Response,
};
pub use spec::{MediumSpec, StackSpec};
pub use stack::{Layer, Stack, StackGrid, MAX_THICKNESS_NM, WAVELENGTH_RANGE_NM};
