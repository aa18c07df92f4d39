//! `irid eval`: R and T of a stack over a wavelength × angle grid.
// Placeholder owned by the optics work (issue 2); replaced before landing.

use std::process::ExitCode;

#[derive(clap::Args)]
pub struct Args {
    pub stack: std::path::PathBuf,
}

pub fn run(_args: Args) -> anyhow::Result<ExitCode> {
    anyhow::bail!("eval: not built yet")
}
