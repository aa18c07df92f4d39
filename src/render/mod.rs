//! The tracer: a Whitted-style renderer whose thin films are shaded through
//! one interface ([`film::FilmShading`]) with two implementations, baked
//! tables and the direct transfer-matrix solution.

pub mod camera;
pub mod environment;
pub mod film;
pub mod geometry;
pub mod image;
pub mod material;
pub mod mesh;
pub mod scene;
pub mod thickness;
pub mod tracer;
