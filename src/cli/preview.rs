//! `irid preview`: a ready-to-open browser preview of one or more exports.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;

#[derive(clap::Args)]
pub struct Args {
    /// Export folders (written by `irid export`); the page offers each.
    #[arg(required = true)]
    pub exports: Vec<PathBuf>,
    /// The preview folder to write: new, empty, or an earlier preview.
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: Args) -> Result<ExitCode> {
    let preview = irid::web::write_preview(&args.exports, &args.output)?;
    println!(
        "wrote {} ({}): open it in a browser with WebGL2",
        preview.index.display(),
        preview.exports.join(", ")
    );
    Ok(ExitCode::SUCCESS)
}
