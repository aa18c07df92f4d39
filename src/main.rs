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
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("irid: {}", one_line(&e));
            ExitCode::from(2)
        }
    }
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
