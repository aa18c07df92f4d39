//! `irid bench`: speed against error, and the grid workload the Python peers
//! (`tools/bench/bench_peers.py`) are timed against.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use irid::bench::machine::Machine;
use irid::bench::{grid, renders, report, run, stacks};

use super::args::{check_angles, check_count, check_grid, parse_list};
use super::render::{check_threads, with_threads};

#[derive(clap::Args)]
pub struct Args {
    /// Fewer points and LUT resolutions: a smoke test, not a measurement.
    #[arg(long)]
    pub quick: bool,
    /// Directory for report.md, results.csv, renders.csv, speed-vs-error.png
    /// and SETUP.md [default: benches/results/DATE-MACHINE, one per run, as
    /// in benches/results/].
    #[arg(short = 'o', long = "out")]
    pub out: Option<PathBuf>,
    /// Random points per stack (default 10000, or 200 with --quick).
    #[arg(long)]
    pub points: Option<usize>,
    /// Grid mode: evaluate one of the fixed stacks over a wavelength × angle
    /// (× thickness) grid, print JSON with the wall time, and write no report.
    #[arg(long, value_name = "STACK")]
    pub grid: Option<String>,
    /// Wavelengths in nm: a,b,c or start:end:step.
    #[arg(long, default_value = "380:780:1")]
    pub wavelengths: String,
    /// Incidence angles in degrees: a,b,c or start:end:step.
    #[arg(long, default_value = "0:89:1")]
    pub angles: String,
    /// Thicknesses in nm of the stack's varying layer (default: its own thickness).
    #[arg(long)]
    pub thicknesses: Option<String>,
    /// Worker threads: the grid's evaluation, or the report's table bakes
    /// and full renders (its per-evaluation times are single-threaded).
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Repetitions; the fastest is reported.
    #[arg(long, default_value_t = 3)]
    pub repeat: usize,
    /// With --grid: time baking an rgb table of T×A nodes (thickness × angle)
    /// with the baker, with and without its error check (`irid bake
    /// --no-check`), then sweep the same nodes at the integration's
    /// wavelengths (replaces --wavelengths, --angles, --thicknesses).
    #[arg(long, value_name = "T,A")]
    pub bake_nodes: Option<String>,
    /// With --grid: time the rough engine (F_eff, as `irid color
    /// --roughness` computes it) over T×A×R nodes (thickness × cos θ ×
    /// roughness, evenly spaced over the stack's range, [0, 1] and [0, 1])
    /// and print its wall time as JSON instead of evaluating a grid.
    #[arg(long, value_name = "T,A,R", conflicts_with = "bake_nodes")]
    pub rough_nodes: Option<String>,
    /// Tables mode: bake every bench stack's rgb (to 1e-3) and spectral (to
    /// 1e-2, 360-830 nm) tables over every angle in the grid layout and in
    /// the atlas, and write their nodes, bytes, build time and measured
    /// error to tables.md in the run directory (no other report).
    #[arg(long, conflicts_with_all = ["grid", "quick"])]
    pub tables: bool,
    /// Bake each bench stack's rgb atlas and then its rough table
    /// (`irid bake --rough`, 2e-3) in the same run and write their times and
    /// the rough table's measured error to rough.md in the run directory
    /// (no other report).
    #[arg(long, conflicts_with_all = ["grid", "quick", "tables"])]
    pub rough: bool,
    /// Time only the inverse-design workloads (the gradient against the
    /// forward solve, a 3-layer fit, the batched fit), each the fastest of
    /// --repeat runs, and write them to inverse.md in the run directory (the
    /// full report has the same section).
    #[arg(long, conflicts_with_all = ["grid", "quick", "tables", "rough"])]
    pub inverse: bool,
    /// Write R then T as little-endian f64 arrays, [angle][thickness][wavelength],
    /// to this file instead of printing them in the JSON.
    #[arg(long, value_name = "PATH")]
    pub raw: Option<PathBuf>,
}

pub fn run(args: Args) -> Result<ExitCode> {
    check_threads(args.threads)?;
    if args.rough {
        with_threads(Some(args.threads), || run_rough_tables(&args))??;
        return Ok(ExitCode::SUCCESS);
    }
    if args.tables {
        with_threads(Some(args.threads), || run_tables(&args))??;
        return Ok(ExitCode::SUCCESS);
    }
    if args.inverse {
        check_count("--repeat", args.repeat, MAX_REPEAT)?;
        with_threads(Some(args.threads), || run_inverse(&args))??;
        return Ok(ExitCode::SUCCESS);
    }
    match &args.grid {
        Some(name) => run_grid(name, &args)?,
        // The grid builds its own pool; the report's bakes and renders run
        // on this one, so --threads holds for everything it times.
        None => with_threads(Some(args.threads), || run_report(&args))??,
    }
    Ok(ExitCode::SUCCESS)
}

/// The command line as run, this machine, and the run's folder (`--out`,
/// else a dated one under the results folder).
fn run_setting(args: &Args) -> (String, Machine, std::path::PathBuf) {
    let command = std::iter::once("irid".to_string())
        .chain(std::env::args().skip(1))
        .collect::<Vec<_>>()
        .join(" ");
    let machine = Machine::current();
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| Path::new(RESULTS_DIR).join(run_dir_name(&machine)));
    (command, machine, out)
}

fn run_tables(args: &Args) -> Result<()> {
    let points = args.points.unwrap_or(20_000);
    check_count("--points", points, irid::lut::MAX_VALIDATION_POINTS)?;
    let (command, machine, out) = run_setting(args);
    eprintln!(
        "irid bench --tables: {points} points per table on {}",
        machine.summary()
    );
    let scratch = std::env::temp_dir().join(format!("irid-bench-tables-{}", std::process::id()));
    let rows = irid::bench::tables::run(&stacks::fixed_stacks()?, points, 7, &scratch, &|line| {
        eprintln!("{line}")
    });
    let _ = std::fs::remove_dir_all(&scratch);
    let rows = rows?;
    let doc = format!(
        "# Tables: grid against atlas\n\n`{command}` on {}, {} threads.\n\n{}",
        machine.summary(),
        args.threads,
        irid::bench::tables::markdown(&rows, points)
    );
    std::fs::create_dir_all(&out).with_context(|| out.display().to_string())?;
    irid::atomic::write(&out.join("tables.md"), doc.as_bytes())?;
    print!("{doc}");
    Ok(())
}

fn run_rough_tables(args: &Args) -> Result<()> {
    let (command, machine, out) = run_setting(args);
    eprintln!("irid bench --rough on {}", machine.summary());
    let rows = irid::bench::rough::run(&stacks::fixed_stacks()?, &|line| eprintln!("{line}"))?;
    let doc = format!(
        "# Rough tables beside smooth ones\n\n`{command}` on {}, {} threads.\n\n{}",
        machine.summary(),
        args.threads,
        irid::bench::rough::markdown(&rows)
    );
    std::fs::create_dir_all(&out).with_context(|| out.display().to_string())?;
    irid::atomic::write(&out.join("rough.md"), doc.as_bytes())?;
    print!("{doc}");
    Ok(())
}

fn run_inverse(args: &Args) -> Result<()> {
    let (command, machine, out) = run_setting(args);
    eprintln!("irid bench --inverse on {}", machine.summary());
    let figures = irid::bench::inverse::run(args.repeat)?;
    let doc = format!(
        "# irid bench --inverse\n\n`{command}` on {}, {} threads.\n{}",
        machine.summary(),
        args.threads,
        irid::bench::inverse::markdown(&figures)
    );
    std::fs::create_dir_all(&out).with_context(|| out.display().to_string())?;
    irid::atomic::write(&out.join("inverse.md"), doc.as_bytes())?;
    print!("{doc}");
    Ok(())
}

fn run_report(args: &Args) -> Result<()> {
    let mut options = if args.quick {
        run::Options::quick()
    } else {
        run::Options::full()
    };
    if let Some(points) = args.points {
        check_count("--points", points, irid::lut::MAX_VALIDATION_POINTS)?;
        options.points = points;
    }
    let (command, machine, out) = run_setting(args);
    eprintln!(
        "irid bench: {} points per stack on {}",
        options.points,
        machine.summary()
    );
    let (rows, skipped) = run::run(&options)?;
    // The renders bake their tables into a private cache, removed afterwards.
    let cache = std::env::temp_dir().join(format!("irid-bench-luts-{}", std::process::id()));
    let (width, height) = options.render_size;
    let renders = renders::run(&options.render_scenes, width, height, &cache);
    let _ = std::fs::remove_dir_all(&cache);
    let renders = renders?;
    let inverse = irid::bench::inverse::run(options.inverse_repeat)?;
    let sections = report::Sections {
        renders: &renders,
        inverse: Some(&inverse),
    };
    report::write_all(
        &out, &rows, &skipped, &sections, &options, &machine, &command,
    )?;
    irid::atomic::write(
        &out.join("SETUP.md"),
        setup_note(&machine, &command, &out).as_bytes(),
    )?;
    for s in report::summarize(&rows) {
        eprintln!(
            "  {:28} {:>12.1} ns/eval   mean ΔE00 {:.2e}",
            s.method.name(),
            s.ns_per_eval,
            s.mean_de2000
        );
    }
    for k in &skipped {
        eprintln!(
            "  {:28} not measured on {}: {}",
            k.method.name(),
            k.stack,
            k.why
        );
    }
    for r in &renders {
        eprintln!(
            "  render {:17} {:22} {:>8.3} s   mean ΔE00 {:.2e}",
            r.scene, r.mode, r.render_s, r.mean_de2000
        );
    }
    eprintln!(
        "  gradient of 20 layers × 401 × 3: {:.2}× the forward; 3-layer fit {:.1} ms; batched fit {:.0} spectra/s",
        inverse.gradient_ratio(),
        inverse.fit_s * 1e3,
        inverse.spectra_per_second()
    );
    eprintln!("wrote {}", out.join("report.md").display());
    Ok(())
}

/// Where dated runs live: one directory per run, named by [`run_dir_name`].
const RESULTS_DIR: &str = "benches/results";

/// `YYYY-MM-DD-cpu-model-Ncore`: the run's UTC date and a name for the
/// machine from what the report header records about it, so runs on one
/// machine sort by date and runs on different machines do not collide.
fn run_dir_name(machine: &Machine) -> String {
    let date = machine.date_utc.get(..10).unwrap_or("undated");
    let mut cpu = String::new();
    for c in machine.cpu_model.chars() {
        if c.is_ascii_alphanumeric() {
            cpu.push(c.to_ascii_lowercase());
        } else if !cpu.is_empty() && !cpu.ends_with('-') {
            cpu.push('-');
        }
    }
    let cpu = cpu.trim_end_matches('-');
    let cpu = if cpu.is_empty() { "cpu" } else { cpu };
    format!("{date}-{cpu}-{}core", machine.cores)
}

/// The run's SETUP.md: the machine, the source it was built from and the
/// commands, so a reader can tell what the figures beside it measured.
fn setup_note(machine: &Machine, command: &str, out: &Path) -> String {
    let commit = std::process::Command::new("git")
        .args(["describe", "--always", "--dirty", "--abbrev=12"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "unknown (not run from a git checkout)".to_string());
    format!(
        "# Bench run {name}\n\n\
         - Machine: {cores} logical cores, CPU {cpu}; {threads} worker thread(s)\n\
         - Date: {date} UTC\n\
         - Source: git {commit}, irid {version}\n\
         - Command: `{command}`\n\n\
         The peers' timings (peers.md) come from a second command, run after this one:\n\n\
         ```sh\n\
         OMP_NUM_THREADS=2 IRID_BIN=target/release/irid .venv/bin/python tools/bench/bench_peers.py -o {out}\n\
         ```\n",
        date = machine.date_utc,
        name = run_dir_name(machine),
        cores = machine.cores,
        cpu = machine.cpu_model,
        threads = machine.threads,
        version = env!("CARGO_PKG_VERSION"),
        out = out.display(),
    )
}

/// More repetitions than this only make the run look hung.
const MAX_REPEAT: usize = 1000;

fn run_grid(name: &str, args: &Args) -> Result<()> {
    let bench = stacks::find(name)?.with_context(|| {
        format!(
            "--grid '{name}': unknown stack (known: {})",
            stacks::grid_names().join(", ")
        )
    })?;
    let requested = requested_grid(args)?;
    check_count("--repeat", args.repeat, MAX_REPEAT)?;
    if let Some(spec) = &args.rough_nodes {
        return run_rough(&bench, spec, args);
    }
    let (bake, g) = match &args.bake_nodes {
        Some(spec) => {
            let (t, a) = parse_bake_nodes(spec)?;
            let (s, g) = grid::time_bake(&bench, t, a, args.threads, args.repeat)?;
            (Some(s), g)
        }
        None => (None, requested),
    };
    let out = grid::evaluate(
        &bench.stack,
        bench.varying_layer,
        &g,
        args.threads,
        args.repeat,
    )?;
    let mut doc = grid_json(&bench, &g, &out, args.threads, bake);
    match &args.raw {
        Some(path) => {
            write_raw(path, &out.r, &out.t)?;
            doc["raw"] = serde_json::json!(path);
        }
        None => {
            doc["r"] = serde_json::json!(out.r);
            doc["t"] = serde_json::json!(out.t);
        }
    }
    let mut stdout = std::io::stdout().lock();
    serde_json::to_writer(&mut stdout, &doc)?;
    writeln!(stdout)?;
    Ok(())
}

/// The grid `--wavelengths`, `--angles` and `--thicknesses` give. Its
/// values are checked even under `--bake-nodes`, which replaces it; its
/// size only when it is the grid evaluated.
fn requested_grid(args: &Args) -> Result<grid::Grid> {
    let wavelengths_nm = parse_list("--wavelengths", &args.wavelengths)?;
    let angles_deg = parse_list("--angles", &args.angles)?;
    check_angles("--angles", &angles_deg)?;
    let thicknesses_nm = match &args.thicknesses {
        Some(spec) => {
            let t = parse_list("--thicknesses", spec)?;
            let max = irid::optics::MAX_THICKNESS_NM;
            if let Some(bad) = t.iter().find(|t| !(0.0..=max).contains(*t)) {
                anyhow::bail!("--thicknesses: {bad} is outside [0, {max:e}] nm");
            }
            Some(t)
        }
        None => None,
    };
    if args.bake_nodes.is_none() {
        let t = thicknesses_nm.as_ref().map_or(1, Vec::len);
        check_grid(
            "--wavelengths × --angles × --thicknesses",
            &[wavelengths_nm.len(), angles_deg.len(), t],
        )?;
    }
    Ok(grid::Grid {
        wavelengths_nm,
        angles_deg,
        thicknesses_nm,
    })
}

/// `--rough-nodes`: the rough engine's wall time, as one line of JSON.
fn run_rough(bench: &stacks::BenchStack, spec: &str, args: &Args) -> Result<()> {
    let nodes = parse_list("--rough-nodes", spec)?;
    let [t, a, r] = nodes[..] else {
        anyhow::bail!("--rough-nodes '{spec}': expected three node counts, T,A,R");
    };
    if [t, a, r].iter().any(|n| *n < 1.0 || n.fract() != 0.0) {
        anyhow::bail!("--rough-nodes '{spec}': need whole numbers ≥ 1");
    }
    let nodes = [t as usize, a as usize, r as usize];
    check_grid("--rough-nodes", &nodes)?;
    let times = grid::time_rough(bench, nodes, args.threads, args.repeat)?;
    let doc = serde_json::json!({
        "stack": bench.name,
        "rough_nodes": times.nodes,
        "mu_nodes": times.mu_nodes,
        "threads": args.threads,
        "repeat": args.repeat,
        "seconds": times.seconds,
    });
    println!("{doc}");
    Ok(())
}

/// `--bake-nodes T,A`: thickness and angle node counts.
fn parse_bake_nodes(spec: &str) -> Result<(usize, usize)> {
    let nodes = parse_list("--bake-nodes", spec)?;
    let [t, a] = nodes[..] else {
        anyhow::bail!("--bake-nodes '{spec}': expected two node counts, T,A");
    };
    if t < 1.0 || a < 2.0 || t.fract() != 0.0 || a.fract() != 0.0 {
        anyhow::bail!("--bake-nodes '{spec}': need whole numbers, T ≥ 1 and A ≥ 2");
    }
    Ok((t as usize, a as usize))
}

/// The grid run's JSON, without R and T (printed in it or written raw).
fn grid_json(
    bench: &stacks::BenchStack,
    g: &grid::Grid,
    out: &grid::GridOutput,
    threads: usize,
    bake: Option<grid::BakeTimes>,
) -> serde_json::Value {
    let (indices_re, indices_im): (Vec<Vec<f64>>, Vec<Vec<f64>>) = out
        .indices
        .chunks(out.media)
        .map(|c| {
            (
                c.iter().map(|z| z.re).collect(),
                c.iter().map(|z| z.im).collect(),
            )
        })
        .unzip();
    serde_json::json!({
        "stack": bench.name,
        "description": bench.description,
        "layer_thicknesses_nm": bench.stack.thicknesses_nm(),
        // Per layer: false for an incoherent one (a peer calls its
        // incoherent solver then).
        "coherent": bench.stack.layers.iter().map(|l| l.coherent).collect::<Vec<_>>(),
        "varying_layer": bench.varying_layer,
        "wavelengths_nm": g.wavelengths_nm,
        "angles_deg": g.angles_deg,
        "thicknesses_nm": g.thicknesses_nm,
        "indices_re": indices_re,
        "indices_im": indices_im,
        "threads": threads,
        "points": g.points(),
        "seconds": out.seconds,
        // The default bake, which also evaluates the grid with every
        // interval halved to measure the table's error, and the bake of the
        // table's nodes only (`--no-check`), with the points each evaluated.
        "bake_seconds": bake.map(|b| b.checked_s),
        "bake_points": bake.map(|b| b.checked_points),
        "bake_table_seconds": bake.map(|b| b.table_s),
        "bake_table_points": bake.map(|b| b.table_points),
        "layout": ["angle", "thickness", "wavelength"],
    })
}

/// R then T as little-endian f64, written atomically.
fn write_raw(path: &Path, r: &[f64], t: &[f64]) -> Result<()> {
    let mut bytes = Vec::with_capacity(16 * r.len());
    for v in r.iter().chain(t) {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    Ok(irid::atomic::write(path, &bytes)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn machine(cpu_model: &str) -> Machine {
        Machine {
            cpu_model: cpu_model.to_string(),
            cores: 2,
            threads: 2,
            date_utc: "2026-11-29 06:01".to_string(),
        }
    }

    #[test]
    fn run_directories_are_named_by_date_and_machine() {
        assert_eq!(
            run_dir_name(&machine("AMD EPYC")),
            "2026-11-29-amd-epyc-2core"
        );
        assert_eq!(
            run_dir_name(&machine("Intel(R) Core(TM) i7-8550U CPU @ 1.80GHz")),
            "2026-11-29-intel-r-core-tm-i7-8550u-cpu-1-80ghz-2core"
        );
        assert_eq!(run_dir_name(&machine("")), "2026-11-29-cpu-2core");
        assert!(
            setup_note(&machine("AMD EPYC"), "irid bench", Path::new("d"))
                .contains("- Command: `irid bench`")
        );
    }
}
