//! One module per subcommand. Shared argument parsing lives in `args`.

#[allow(dead_code)] // until every subcommand that uses them has landed
pub mod args;
pub mod bake;
pub mod bench;
pub mod color;
pub mod demo;
pub mod eval;
pub mod info;
pub mod render;
pub mod validate;
