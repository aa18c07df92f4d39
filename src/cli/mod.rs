//! One module per subcommand. Shared argument parsing lives in `args`.

/// Appends one formatted line to a String, its control characters escaped:
/// names and descriptions come from files and must not reach the terminal
/// raw (nor split a line).
macro_rules! say {
    ($out:expr, $($t:tt)*) => {{
        $out.push_str(&irid::error::escape(&format!($($t)*)));
        $out.push('\n');
    }};
}
pub(crate) use say;

/// Prints lines gathered by [`say`].
pub fn print_escaped(text: &str) {
    print!("{text}");
}

pub mod args;
pub mod bake;
pub mod bench;
pub mod color;
pub mod demo;
pub mod eval;
pub mod export;
pub mod fit;
pub mod info;
pub mod logger;
pub mod preview;
pub mod render;
pub mod validate;
