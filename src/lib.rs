//! `irid`: exact thin-film iridescence by the transfer-matrix method, baked
//! into OpenEXR lookup tables and sampled by a lightweight tracer.
//!
//! Modules follow the data flow: [`optics`] (materials, stacks, solver) →
//! [`color`] (spectra to colour) → [`lut`] (bake, file, sample, validate) →
//! [`render`] (the tracer); [`rough`] pre-integrates a film's reflectance
//! over a GGX microfacet lobe.

pub mod analytic;
pub mod atlas;
pub mod atomic;
#[cfg(feature = "bench")]
pub mod bench;
pub mod cancel;
pub mod color;
pub mod error;
pub mod export;
pub mod fit;
pub mod limits;
pub mod lut;
pub mod optics;
pub mod render;
pub mod rough;
mod simd;
pub mod stats;
pub mod sweep;
pub mod web;

pub use error::{Error, Result};

/// The README's Rust examples, compiled and run as doctests so that the
/// front page cannot drift from the library.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
