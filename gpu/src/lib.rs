//! Generates the GLSL and HLSL forms of `shaders/irid_film.wgsl`.
pub mod generate;
