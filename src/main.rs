//! The `irid` command line: a thin shell over the library. Each subcommand
//! lives in `src/cli/`, parses its arguments, calls the library and prints.
//! Any error is printed once, as one line, and the process exits with 2.

use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

mod cli;

#[derive(Parser)]
#[command(
    name = "irid",
    version,
    about = "Exact thin-film iridescence: bake, sample, validate, render",
    after_help = "Environment: RUST_LOG=debug (or IRID_DEBUG=1) prints the library's diagnostics, such as each bake refinement round; IRID_CACHE_DIR sets where `irid render` keeps the tables it bakes."
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
    /// Reflected and transmitted colour of a stack (D65 or white E), per angle.
    Color(cli::color::Args),
    /// Bake a stack's response into an OpenEXR lookup table.
    Bake(cli::bake::Args),
    /// GPU-ready textures, film.json and shaders for any renderer.
    Export(cli::export::Args),
    /// Fit layer thicknesses to a measured spectrum or to colours at angles.
    Fit(cli::fit::Args),
    /// Print a lookup table's header.
    Info(cli::info::Args),
    /// Measure a lookup table's error against the solver.
    Validate(cli::validate::Args),
    /// Render a scene (a file or a built-in name) with baked or direct film shading.
    Render(cli::render::Args),
    /// Bake, render every built-in scene into out/, and report times and colour error.
    Demo(cli::demo::Args),
    /// Write a browser (WebGL2) preview of exports into a folder.
    Preview(cli::preview::Args),
}

fn main() -> ExitCode {
    restore_sigpipe();
    cli::logger::install();
    let cli = match parse() {
        Ok(cli) => cli,
        // --help and --version are not errors.
        Err(e) if !e.use_stderr() => {
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            eprintln!("irid: {}", irid::error::escape(&clap_line(&e)));
            return ExitCode::from(2);
        }
    };
    let result = match cli.command {
        Command::Eval(args) => cli::eval::run(args),
        Command::Bench(args) => cli::bench::run(args),
        Command::Color(args) => cli::color::run(args),
        Command::Bake(args) => cli::bake::run(args),
        Command::Export(args) => cli::export::run(args),
        Command::Fit(args) => cli::fit::run(args),
        Command::Info(args) => cli::info::run(args),
        Command::Validate(args) => cli::validate::run(args),
        Command::Render(args) => cli::render::run(args),
        Command::Demo(args) => cli::demo::run(args),
        Command::Preview(args) => cli::preview::run(args),
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

/// Rust ignores SIGPIPE, so a `println!` into a closed pipe (`irid info t.exr
/// | head -2`) panics. With the default action the process ends quietly, as
/// other Unix tools do.
fn restore_sigpipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in main, before any other thread exists;
    // SIG_DFL is a valid disposition for SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// Parses the command line. Option values may start with '-' (`--thickness
/// -5:600`, `--seed -1`) so that they reach the value checks, which name
/// the flag, instead of being taken for an unknown flag.
fn parse() -> Result<Cli, clap::Error> {
    let command = Cli::command().mut_subcommands(|sub| {
        sub.mut_args(|arg| {
            let takes_value = arg.get_action().takes_values() && !arg.is_positional();
            arg.allow_hyphen_values(takes_value)
        })
    });
    Cli::from_arg_matches_mut(&mut command.try_get_matches()?)
}

/// The first paragraph of a usage error on one line, without clap's
/// `error: ` prefix: the project prints every error as one line.
fn clap_line(e: &clap::Error) -> String {
    if e.kind() == clap::error::ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
        return "a subcommand is required (see irid --help)".to_string();
    }
    let text = e.render().to_string();
    let paragraph: Vec<&str> = text
        .trim_start()
        .lines()
        .take_while(|l| !l.trim().is_empty())
        .map(str::trim)
        .collect();
    paragraph
        .join(" ")
        .trim_start_matches("error: ")
        .to_string()
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
    // Messages of other libraries may span lines; names echoed from files
    // may hold any control character (escaped, never sent to the terminal).
    irid::error::escape(&line.replace('\n', " ")).into_owned()
}
