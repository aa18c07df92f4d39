//! Report files: Markdown table, CSV, written atomically.

use std::path::Path;

use crate::error::{Error, Result};

use super::inverse::InverseFigures;
use super::machine::Machine;
use super::plot::{speed_vs_error_png, PlotPoint};
use super::renders::RenderRow;
use super::run::{Family, Method, Options, Row, Skipped};
use super::stacks::{descriptions, find, names};
use crate::color::Sampling;

/// Errors below this are drawn at it on the log axis (the exact method's
/// error is zero by construction).
pub const PLOT_FLOOR_DE: f64 = 1e-4;

/// One method's figures over the stacks it applies to (medians).
#[derive(Clone, Debug)]
pub struct Summary {
    /// The method summarized.
    pub method: Method,
    /// How many stacks it was measured on.
    pub stacks: usize,
    /// Median of [`Row::ns_per_eval`] over those stacks.
    pub ns_per_eval: f64,
    /// Median of [`Row::max_abs`] (largest linear-sRGB reflectance error).
    pub max_abs: f64,
    /// Median of [`Row::p99_abs`].
    pub p99_abs: f64,
    /// Median of [`Row::mean_de2000`].
    pub mean_de2000: f64,
    /// Median of [`Row::max_de2000`].
    pub max_de2000: f64,
    /// Non-finite results summed (not a median) over the stacks.
    pub nonfinite: usize,
}

/// Per method, in first-seen order: the median over the stacks it applies
/// to of each column. A median, because one stack (the gain film, whose
/// resonances reach reflectances in the thousands) would otherwise decide
/// every mean.
pub fn summarize(rows: &[Row]) -> Vec<Summary> {
    let mut methods: Vec<Method> = Vec::new();
    for r in rows {
        if !methods.contains(&r.method) {
            methods.push(r.method);
        }
    }
    methods
        .into_iter()
        .map(|method| {
            let of: Vec<&Row> = rows.iter().filter(|r| r.method == method).collect();
            let median = |f: fn(&Row) -> f64| {
                let mut v: Vec<f64> = of.iter().map(|r| f(r)).collect();
                v.sort_by(f64::total_cmp);
                let n = v.len();
                if n % 2 == 1 {
                    v[n / 2]
                } else {
                    0.5 * (v[n / 2 - 1] + v[n / 2])
                }
            };
            Summary {
                method,
                stacks: of.len(),
                ns_per_eval: median(|r| r.ns_per_eval),
                max_abs: median(|r| r.max_abs),
                p99_abs: median(|r| r.p99_abs),
                mean_de2000: median(|r| r.mean_de2000),
                max_de2000: median(|r| r.max_de2000),
                nonfinite: of.iter().map(|r| r.nonfinite).sum(),
            }
        })
        .collect()
}

/// The per-stack rows as CSV text with a header line: one line per
/// (stack, method), errors in scientific notation, an empty `setup_s` for
/// methods without one.
pub fn csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "stack,method,family,ns_per_eval,max_abs_r,p99_abs_r,mean_de2000,max_de2000,points,nonfinite,setup_s\n",
    );
    for r in rows {
        s.push_str(&format!(
            "{},{},{},{:.3},{:.6e},{:.6e},{:.6e},{:.6e},{},{},{}\n",
            r.stack,
            r.method.name(),
            r.method.family().label(),
            r.ns_per_eval,
            r.max_abs,
            r.p99_abs,
            r.mean_de2000,
            r.max_de2000,
            r.points,
            r.nonfinite,
            r.setup_s.map_or(String::new(), |v| format!("{v:.4}")),
        ));
    }
    s
}

/// The full-render rows as CSV text with a header line: one line per
/// (scene, mode), times in seconds.
pub fn renders_csv(rows: &[RenderRow]) -> String {
    let mut s = String::from(
        "scene,mode,width,height,prepare_s,render_s,mean_de2000,p99_de2000,max_de2000\n",
    );
    for r in rows {
        s.push_str(&format!(
            "{},{},{},{},{:.4},{:.4},{:.6e},{:.6e},{:.6e}\n",
            r.scene,
            r.mode,
            r.width,
            r.height,
            r.prepare_s,
            r.render_s,
            r.mean_de2000,
            r.p99_de2000,
            r.max_de2000
        ));
    }
    s
}

fn renders_markdown(rows: &[RenderRow], threads: usize) -> String {
    let mut s = format!(
        "\n## Full renders\n\nOne frame per film mode of each built-in scene, one sample per pixel, \
         rendered on {threads} thread(s); CIEDE2000 per pixel against the frame shaded by direct exact \
         evaluation. Preparing the films (baking the scene's tables and, for a noise film, its \
         thickness grid, on demand) is timed apart; the LUT frames' error includes the grid's \
         (at most 2 nm of thickness).\n\n\
         | scene | film mode | size | prepare (s) | render (ms) | vs exact | mean ΔE00 | p99 ΔE00 | max ΔE00 |\n\
         |---|---|---|---:|---:|---:|---:|---:|---:|\n",
    );
    for r in rows {
        let exact = rows
            .iter()
            .find(|e| e.scene == r.scene && e.mode == "direct exact")
            .map_or(f64::NAN, |e| e.render_s);
        s.push_str(&format!(
            "| {} | {} | {}x{} | {:.3} | {:.2} | {} | {} | {} | {} |\n",
            r.scene,
            r.mode,
            r.width,
            r.height,
            r.prepare_s,
            r.render_s * 1e3,
            fmt_ratio(exact / r.render_s),
            fmt_err(r.mean_de2000),
            fmt_err(r.p99_de2000),
            fmt_err(r.max_de2000),
        ));
    }
    s
}

fn table_header(with_bake: bool) -> String {
    let head = "| method | ns / eval | vs exact | max abs ΔR | p99 abs ΔR | mean ΔE00 | max ΔE00 |";
    let rule = "|---|---:|---:|---:|---:|---:|---:|";
    if with_bake {
        format!("{head} bake (s) |\n{rule}---:|\n")
    } else {
        format!("{head}\n{rule}\n")
    }
}

/// A speed ratio with two or three significant digits: 0.51x, 6.1x, 201x.
fn fmt_ratio(v: f64) -> String {
    if v >= 100.0 {
        format!("{v:.0}x")
    } else if v >= 10.0 {
        format!("{v:.1}x")
    } else {
        format!("{v:.2}x")
    }
}

fn fmt_err(v: f64) -> String {
    if v == 0.0 {
        "0".to_string()
    } else {
        format!("{v:.2e}")
    }
}

/// The Markdown report: header (date, machine, command), the summary table,
/// then one table per stack.
pub fn markdown(
    rows: &[Row],
    skipped: &[Skipped],
    sections: &Sections<'_>,
    options: &Options,
    machine: &Machine,
    command: &str,
) -> String {
    let mut s = preamble_markdown(options, machine, command);
    s.push_str(&summary_markdown(rows));
    for (name, description) in descriptions() {
        s.push_str(&stack_markdown(name, description, rows, skipped));
    }
    if !sections.renders.is_empty() {
        s.push_str(&renders_markdown(sections.renders, machine.threads));
    }
    if let Some(inverse) = sections.inverse {
        s.push_str(&super::inverse::markdown(inverse));
    }
    s
}

/// The report's sections after the per-stack tables, each left out when
/// empty.
#[derive(Clone, Copy, Debug, Default)]
pub struct Sections<'a> {
    /// Full renders with each table mode.
    pub renders: &'a [RenderRow],
    /// Inverse design's speed ([`super::inverse`]).
    pub inverse: Option<&'a InverseFigures>,
}

fn is_exact(method: &Method) -> bool {
    matches!(method, Method::Direct(Sampling::Exact))
}

/// " (n stacks)" for a method measured on fewer than all stacks: its median
/// is then not comparable with the others' at a glance.
fn fewer_stacks_note(m: &Summary) -> String {
    if m.stacks < names().len() {
        format!(" ({} stacks)", m.stacks)
    } else {
        String::new()
    }
}

/// The title and the bullet list saying how the figures were measured.
fn preamble_markdown(options: &Options, machine: &Machine, command: &str) -> String {
    let mut s = String::new();
    s.push_str("# irid bench: speed against error\n\n");
    s.push_str(&format!("- Date: {} UTC\n", machine.date_utc));
    s.push_str(&format!(
        "- Machine: {} logical cores, CPU {}\n",
        machine.cores, machine.cpu_model
    ));
    s.push_str(&format!(
        "- Threads: {} (table bakes and full renders run in parallel on them)\n",
        machine.threads
    ));
    s.push_str(&format!("- Command: `{command}`\n"));
    s.push_str(&format!(
        "- Points: {} random (thickness, cos θ) per stack, uniform over the stack's thickness range \
         and cos θ ∈ [0, 1], seed {}\n",
        options.points, options.seed
    ));
    s.push_str(
        "- Reference: direct TMM integrated at 1 nm over 360–830 nm (CIE 1931 2°, D65), linear sRGB \
         reflectance; `direct exact` is that reference, so its error is 0 by construction\n",
    );
    s.push_str(
        "- Time: one shading evaluation (one thickness, one angle, to linear sRGB) on one thread, \
         from one loop over all points divided by their count; compare methods by ratio within this run\n",
    );
    s.push_str(
        "- LUTs: rgb tables baked with 1 nm integration over thickness × cos θ, sampled bilinearly; \
         bake time in the last column (an f16 table is the f32 one rounded: its bake and the rounding)\n",
    );
    s.push_str(
        "- Analytic: the single-film model of Belcour & Barla (2017) (exact Fresnel, 3 terms) and the \
         glTF `KHR_materials_iridescence` reference (Schlick, 2 terms), on the one-film stacks only\n\n",
    );
    s
}

/// The "All stacks" section: the table of medians and the plot under it.
fn summary_markdown(rows: &[Row]) -> String {
    let summary = summarize(rows);
    let mut s = String::from(
        "## All stacks\n\nMedians over the stacks each method applies to (one stack, the gain film, \
         would decide every mean), of each column.\n\n",
    );
    s.push_str(&table_header(false));
    let all_exact = summary
        .iter()
        .find(|m| is_exact(&m.method))
        .map_or(f64::NAN, |m| m.ns_per_eval);
    for m in &summary {
        s.push_str(&format!(
            "| {}{}{} | {:.1} | {} | {} | {} | {} | {} |\n",
            m.method.name(),
            fewer_stacks_note(m),
            if m.nonfinite > 0 {
                format!(" ({} non-finite, left out)", m.nonfinite)
            } else {
                String::new()
            },
            m.ns_per_eval,
            fmt_ratio(all_exact / m.ns_per_eval),
            fmt_err(m.max_abs),
            fmt_err(m.p99_abs),
            fmt_err(m.mean_de2000),
            fmt_err(m.max_de2000),
        ));
    }
    s.push_str(&format!(
        "\n![speed vs error](speed-vs-error.png)\n\nIn the plot, errors below {PLOT_FLOOR_DE:e} \
         (the exact method's 0) are drawn at {PLOT_FLOOR_DE:e}.\n"
    ));
    s
}

/// One stack's section: its largest reference reflectance, its table (speed
/// relative to that stack's exact evaluation), and the methods the baker
/// refused for it.
fn stack_markdown(name: &str, description: &str, rows: &[Row], skipped: &[Skipped]) -> String {
    let mut s = format!("\n## {name}: {description}\n\n");
    if let Some(r) = rows.iter().find(|r| r.stack == name) {
        let gain = find(name)
            .ok()
            .flatten()
            .is_some_and(|b| b.stack.layers.iter().any(|l| l.material.has_gain()));
        s.push_str(&format!(
            "Largest reference reflectance channel over the points: {:.3}{}.\n\n",
            r.reference_max,
            if gain {
                " (a gain layer: near its resonances reflectance exceeds 1 by far, so absolute \
                 errors there are large)"
            } else {
                ""
            }
        ));
    }
    s.push_str(&table_header(true));
    let exact = rows
        .iter()
        .find(|r| r.stack == name && is_exact(&r.method))
        .map_or(f64::NAN, |r| r.ns_per_eval);
    for r in rows.iter().filter(|r| r.stack == name) {
        s.push_str(&format!(
            "| {}{} | {:.1} | {} | {} | {} | {} | {} | {} |\n",
            r.method.name(),
            if r.nonfinite > 0 {
                format!(
                    " ({} of {} points non-finite, left out)",
                    r.nonfinite, r.points
                )
            } else {
                String::new()
            },
            r.ns_per_eval,
            fmt_ratio(exact / r.ns_per_eval),
            fmt_err(r.max_abs),
            fmt_err(r.p99_abs),
            fmt_err(r.mean_de2000),
            fmt_err(r.max_de2000),
            r.setup_s.map_or(String::new(), |v| format!("{v:.3}")),
        ));
    }
    for k in skipped.iter().filter(|k| k.stack == name) {
        s.push_str(&format!(
            "\n{} not measured: the baker refuses it ({}).\n",
            k.method.name(),
            k.why
        ));
    }
    s
}

/// Writes report.md, results.csv, renders.csv (when there are renders) and
/// speed-vs-error.png into `dir`.
pub fn write_all(
    dir: &Path,
    rows: &[Row],
    skipped: &[Skipped],
    sections: &Sections<'_>,
    options: &Options,
    machine: &Machine,
    command: &str,
) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    crate::atomic::write(&dir.join("results.csv"), csv(rows).as_bytes())?;
    if !sections.renders.is_empty() {
        crate::atomic::write(
            &dir.join("renders.csv"),
            renders_csv(sections.renders).as_bytes(),
        )?;
    }
    let points: Vec<PlotPoint> = summarize(rows)
        .iter()
        .map(|m| PlotPoint {
            // A median over fewer stacks is not comparable with the others
            // at a glance: say so on the plot as in the table.
            label: format!(
                "{}{}{}",
                m.method.name(),
                fewer_stacks_note(m),
                if m.mean_de2000 < PLOT_FLOOR_DE {
                    " (error 0, at floor)"
                } else {
                    ""
                }
            ),
            family: m.method.family().index(),
            ns_per_eval: m.ns_per_eval,
            mean_de2000: m.mean_de2000,
        })
        .collect();
    let families: Vec<&str> = Family::ALL.iter().map(|f| f.label()).collect();
    let caption = format!(
        "irid bench: time vs mean CIEDE2000, medians over stacks ({}, {})",
        machine.cpu_model, machine.date_utc
    );
    speed_vs_error_png(
        &dir.join("speed-vs-error.png"),
        &points,
        &families,
        PLOT_FLOOR_DE,
        &caption,
    )?;
    crate::atomic::write(
        &dir.join("report.md"),
        markdown(rows, skipped, sections, options, machine, command).as_bytes(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_method_the_baker_refused_is_named_under_its_stack() {
        let skipped = [Skipped {
            stack: "gain-on-gold".into(),
            method: Method::Lut {
                thickness_nodes: 256,
                angle_nodes: 32,
                half: true,
            },
            why: "reflectance.R exceeds f16's largest value".into(),
        }];
        let text = markdown(
            &[],
            &skipped,
            &Sections::default(),
            &Options::quick(),
            &Machine::current(),
            "irid bench",
        );
        let section = &text[text.find("## gain-on-gold").expect("the stack's section")..];
        assert!(
            section.contains("LUT 256x32 f16 not measured: the baker refuses it (reflectance.R exceeds f16's largest value)"),
            "{section}"
        );
        assert!(!text[..text.find("## gain-on-gold").unwrap()].contains("not measured"));
    }
}
