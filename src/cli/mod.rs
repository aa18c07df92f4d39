//! One module per subcommand. Shared argument parsing lives in `args`.

pub mod eval;
