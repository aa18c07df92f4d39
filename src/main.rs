//! The `irid` command line: a thin shell over the library. Each subcommand
//! lives in `src/cli/`, parses its arguments, calls the library and prints.
//! Any error is printed once, as one line, and the process exits with 2.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod cli;

#[derive(Parser)]
#[command(
    name = "irid",
    version,
    about = "Exact thin-film iridescence: bake, sample, validate, render"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Reflectance and transmittance of a stack over wavelengths and angles.
    Eval(cli::eval::Args),
    /// Speed against error of every method; `--grid` times one stack for the peers.
    Bench(cli::bench::Args),
    /// Reflected and transmitted colour of a stack under D65, per angle.
    Color(cli::color::Args),
    /// Bake a stack's response into an OpenEXR lookup table.
    Bake(cli::bake::Args),
    /// Print a lookup table's header.
    Info(cli::info::Args),
    /// Measure a lookup table's error against the solver.
    Validate(cli::validate::Args),
    /// Render a scene (a file or a built-in name) with baked or direct film shading.
    Render(cli::render::Args),
    /// Bake, render every built-in scene into out/, and report times and colour error.
    Demo(cli::demo::Args),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            // --help and --version are not errors.
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    let result = match cli.command {
        Command::Eval(args) => cli::eval::run(args),
        Command::Bench(args) => cli::bench::run(args),
        Command::Color(args) => cli::color::run(args),
        Command::Bake(args) => cli::bake::run(args),
        Command::Info(args) => cli::info::run(args),
        Command::Validate(args) => cli::validate::run(args),
        Command::Render(args) => cli::render::run(args),
        Command::Demo(args) => cli::demo::run(args),
    };
    match result {
        Ok(code) => code,
        // A closed pipe (`irid eval ... | head`) means the reader has all
        // it wants: stop quietly, as other Unix tools do.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("irid: {}", one_line(&e));
            ExitCode::from(2)
        }
    }
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// The error and its causes joined on one line. A cause that the message
/// so far already ends with (an error whose text includes its source) is
/// not repeated.
fn one_line(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if line.ends_with(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line.replace('\n', " ")
}
