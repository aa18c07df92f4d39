//! One module per subcommand. Shared argument parsing lives in `args`.

pub mod args;
pub mod bake;
pub mod bench;
pub mod color;
pub mod demo;
pub mod eval;
pub mod export;
pub mod info;
pub mod render;
pub mod validate;
