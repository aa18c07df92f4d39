//! `irid validate LUT.exr`: the table against the solver at random points.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use irid::lut::{validate, Lut, Validation};

#[derive(clap::Args)]
pub struct Args {
    /// A table written by `irid bake`.
    pub lut: PathBuf,
    /// Random off-grid points to evaluate directly.
    #[arg(long, default_value_t = 20_000)]
    pub points: usize,
    /// Seed of the point stream (PCG64).
    #[arg(long, default_value_t = irid::lut::VALIDATION_SEED)]
    pub seed: u64,
    /// Exit with code 1 when any channel's largest absolute error exceeds this.
    #[arg(long)]
    pub max_error: Option<f64>,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: Args) -> Result<ExitCode> {
    if let Some(e) = args.max_error {
        anyhow::ensure!(e >= 0.0, "--max-error {e}: must be ≥ 0");
    }
    if irid::lut::rough::is_rough_table(&args.lut) {
        return run_rough(&args);
    }
    let lut = Lut::load(&args.lut)?;
    let stats = validate(&lut, args.points, args.seed)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&stats)?);
    } else {
        println!("{}: {}", args.lut.display(), points_and_seed(&stats));
        print_stats(&stats);
    }
    // An atlas table's target applies above its aliased strip.
    let worst = match stats.regions.iter().find(|r| r.name == "resolved") {
        Some(r) => r.max_abs,
        None => stats.figures.max_all(),
    };
    match args.max_error {
        Some(e) if worst > e || stats.figures.max_abs.iter().any(|v| v.is_nan()) => {
            eprintln!("irid: max abs error {worst:.3e} exceeds --max-error {e:e}");
            Ok(ExitCode::from(1))
        }
        _ => Ok(ExitCode::SUCCESS),
    }
}

/// `irid validate` on a rough table: re-measured against irid's rough
/// reflectance at random points (its own draw: --points is not used; the
/// count is the measurement's, see docs/lut-format.md).
fn run_rough(args: &Args) -> Result<ExitCode> {
    let rough = irid::lut::RoughLut::load(&args.lut)?;
    let (measured, grazing) = rough.validate(args.seed)?;
    let grazing_cos = rough.header().error.grazing_cos;
    if args.json {
        let value = serde_json::json!({"seed": args.seed, "grazing_cos": grazing_cos,
            "measured": measured, "grazing": grazing});
        println!("{}", serde_json::to_string_pretty(&value)?);
    } else {
        let mut out = String::new();
        super::say!(
            out,
            "{}: rough table, seed {}",
            args.lut.display(),
            args.seed
        );
        super::info::say_slice_error(&mut out, &format!("cos θ ≥ {grazing_cos}"), &measured);
        super::info::say_slice_error(&mut out, &format!("cos θ < {grazing_cos}"), &grazing);
        super::print_escaped(&out);
    }
    let worst = measured.max_all();
    match args.max_error {
        Some(e) if worst > e || worst.is_nan() => {
            eprintln!("irid: max abs error {worst:.3e} exceeds --max-error {e:e}");
            Ok(ExitCode::from(1))
        }
        _ => Ok(ExitCode::SUCCESS),
    }
}

/// "N random points (seed S)": how the validation drew its points.
pub fn points_and_seed(v: &Validation) -> String {
    let f = &v.figures;
    match f.seed {
        Some(seed) => format!("{} random points (seed {seed})", f.points),
        None => format!("{} random points (seed not recorded)", f.points),
    }
}

/// The validation figures as an indented table.
pub fn print_stats(s: &Validation) {
    let f = &s.figures;
    let mut out = String::new();
    super::say!(
        out,
        "  {:<16} {:>10} {:>10} {:>10}",
        "channel",
        "max abs",
        "mean abs",
        "p99 abs"
    );
    for (k, name) in s.channels.iter().enumerate() {
        super::say!(
            out,
            "  {:<16} {:>10.3e} {:>10.3e} {:>10.3e}",
            name,
            f.max_abs[k],
            f.mean_abs[k],
            f.p99_abs[k]
        );
    }
    if let (Some(max), Some(mean)) = (f.max_delta_e00, f.mean_delta_e00) {
        super::say!(out,
            "  CIEDE2000        reflectance max {:.4} mean {:.4}; transmittance max {:.4} mean {:.4}",
            max[0], mean[0], max[1], mean[1]
        );
    }
    let [t, c, w] = f.worst_point;
    super::say!(
        out,
        "  worst point      thickness {t:.3} nm, cos θ {c:.5} ({:.2}°){}",
        c.clamp(-1.0, 1.0).acos().to_degrees(),
        if w > 0.0 {
            format!(", {w:.1} nm")
        } else {
            String::new()
        }
    );
    for r in &s.regions {
        super::say!(
            out,
            "  region {:<13} {:>6} points  max abs {:.3e}  mean {:.3e}  ({})",
            r.name,
            r.points,
            r.max_abs,
            r.mean_abs,
            r.description
        );
    }
    super::print_escaped(&out);
}
