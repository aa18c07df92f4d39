//! `irid bench --quick` end to end: the report files exist and have the
//! promised structure, every figure is a number, and the LUT's error falls
//! as its resolution rises on every stack.

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

mod common;

use std::collections::BTreeMap;

use common::{irid, Scratch};

#[test]
fn quick_bench_writes_a_consistent_report() {
    let dir = Scratch::new("bench");
    let out = irid([
        "bench",
        "--quick",
        "--threads",
        "1",
        "-o",
        dir.path().to_str().unwrap(),
    ]);
    assert!(out.success(), "{}", out.stderr);

    let report = std::fs::read_to_string(dir.path().join("report.md")).unwrap();
    for needle in [
        "# irid bench: speed against error",
        "- Date: ",
        "- Machine: ",
        "logical cores, CPU ",
        // The whole report runs on the pool --threads asks for.
        "- Threads: 1 (",
        "rendered on 1 thread(s)",
        "- Command: `irid bench --quick --threads 1 -o ",
        "| method | ns / eval | vs exact | max abs ΔR | p99 abs ΔR | mean ΔE00 | max ΔE00 |",
        "| method | ns / eval | vs exact | max abs ΔR | p99 abs ΔR | mean ΔE00 | max ΔE00 | bake (s) |",
        "![speed vs error](speed-vs-error.png)",
        "## Inverse design",
        "| the same with ∂R, ∂T (s, p) by all 20 thicknesses | ",
        "| 3-layer fit to one 401-wavelength spectrum (bounds ±50 %) | ",
        " spectra/s | reported |",
    ] {
        assert!(report.contains(needle), "report.md lacks {needle:?}");
    }

    let csv = std::fs::read_to_string(dir.path().join("results.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "stack,method,family,ns_per_eval,max_abs_r,p99_abs_r,mean_de2000,max_de2000,points,nonfinite,setup_s"
    );
    // stack -> method -> mean ΔE00
    let mut de: BTreeMap<String, BTreeMap<String, f64>> = BTreeMap::new();
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f.len(), 11, "{line}");
        let ns: f64 = f[3].parse().unwrap();
        assert!(ns > 0.0 && ns.is_finite(), "{line}");
        for v in &f[4..8] {
            let v: f64 = v.parse().unwrap();
            assert!(v >= 0.0 && v.is_finite(), "{line}");
        }
        de.entry(f[0].to_string())
            .or_default()
            .insert(f[1].to_string(), f[6].parse().unwrap());
    }
    assert_eq!(de.len(), 6, "one block per fixed stack: {:?}", de.keys());
    for (stack, methods) in &de {
        assert_eq!(
            methods["direct exact"], 0.0,
            "{stack}: the reference itself"
        );
        for m in [
            "direct rgb3",
            "direct uniform:9",
            "direct uniform:41",
            "direct uniform:81",
        ] {
            assert!(methods.contains_key(m), "{stack} lacks {m}");
        }
        // Uniform sampling converges on the reference.
        assert!(
            methods["direct uniform:81"] < methods["direct uniform:9"],
            "{stack}"
        );
        // LUT error falls as resolution rises, in both precisions.
        for precision in ["f32", "f16"] {
            let mut lut: Vec<(usize, f64)> = methods
                .iter()
                .filter_map(|(m, &e)| {
                    let res = m
                        .strip_prefix("LUT ")?
                        .strip_suffix(&format!(" {precision}"))?;
                    let (t, a) = res.split_once('x')?;
                    Some((t.parse::<usize>().ok()? * a.parse::<usize>().ok()?, e))
                })
                .collect();
            lut.sort_by_key(|&(nodes, _)| nodes);
            assert!(lut.len() >= 3, "{stack}: {precision} LUTs {lut:?}");
            assert!(
                lut.windows(2).all(|w| w[1].1 < w[0].1),
                "{stack} LUT {precision} mean ΔE00 not falling with resolution: {lut:?}"
            );
        }
        let one_film = ["soap", "absorbing", "gain-on-gold"].contains(&stack.as_str());
        assert_eq!(
            methods.contains_key("analytic Belcour-Barla"),
            one_film,
            "{stack}"
        );
    }

    // The full renders: every mode, the LUT close to exact.
    assert!(
        report.contains("## Full renders"),
        "report.md lacks the renders"
    );
    let renders = std::fs::read_to_string(dir.path().join("renders.csv")).unwrap();
    let mut rows = renders.lines();
    assert_eq!(
        rows.next().unwrap(),
        "scene,mode,width,height,prepare_s,render_s,mean_de2000,p99_de2000,max_de2000"
    );
    let rows: Vec<Vec<&str>> = rows.map(|l| l.split(',').collect()).collect();
    assert!(rows.len() >= 5, "{renders}");
    for r in &rows {
        let mean: f64 = r[6].parse().unwrap();
        assert!(mean.is_finite() && mean >= 0.0, "{r:?}");
        if r[1] == "direct exact" {
            assert_eq!(mean, 0.0, "{r:?}");
        }
        if r[1].starts_with("LUT") {
            assert!(mean < 2.0, "LUT render far from exact: {r:?}");
        }
    }

    let png = image::open(dir.path().join("speed-vs-error.png")).unwrap();
    assert!(png.width() > 500 && png.height() > 300);
}

/// `irid bench --grid soap --repeat 1 EXTRA...`, which must succeed: its JSON.
fn grid_json(extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["bench", "--grid", "soap", "--repeat", "1"];
    args.extend_from_slice(extra);
    let out = irid(&args);
    assert!(out.success(), "{}", out.stderr);
    serde_json::from_str(&out.stdout).unwrap()
}

#[test]
fn grid_mode_prints_json_and_rejects_bad_input() {
    let doc = grid_json(&["--wavelengths", "400,500", "--angles", "0,30"]);
    assert_eq!(doc["points"], 4);
    assert_eq!(doc["r"].as_array().unwrap().len(), 4);
    assert!(doc["seconds"].as_f64().unwrap() >= 0.0);

    // A bake timed with and without its check, over the same table nodes.
    let doc = grid_json(&["--bake-nodes", "6,4"]);
    let points = doc["points"].as_u64().unwrap();
    assert_eq!(doc["thicknesses_nm"].as_array().unwrap().len(), 6);
    assert_eq!(doc["angles_deg"].as_array().unwrap().len(), 4);
    assert_eq!(
        points,
        6 * 4 * doc["wavelengths_nm"].as_array().unwrap().len() as u64
    );
    assert_eq!(doc["bake_table_points"].as_u64(), Some(points));
    // Every interval halved: (2T − 1) × (2A − 1) nodes.
    assert_eq!(doc["bake_points"].as_u64(), Some(points / 24 * 11 * 7));
    for key in ["bake_seconds", "bake_table_seconds"] {
        assert!(doc[key].as_f64().unwrap() > 0.0, "{key}");
    }

    for bad in [
        vec!["bench", "--grid", "nope"],
        vec!["bench", "--grid", "soap", "--angles", "95"],
        vec!["bench", "--grid", "soap", "--threads", "0"],
        vec!["bench", "--quick", "--threads", "0"],
        vec!["bench", "--points", "0"],
        vec!["bench", "--grid", "soap", "--bake-nodes", "3"],
        vec![
            "bench",
            "--grid",
            "soap",
            "--raw",
            "/nonexistent-irid-dir/x.raw",
        ],
    ] {
        irid(&bad).assert_one_line_error(&format!("{bad:?}"), &[]);
    }
}

/// `--rough-nodes`: the rough engine's time over a whole grid, the work a
/// table with a roughness axis costs.
#[test]
fn rough_nodes_time_the_rough_engine() {
    let doc = grid_json(&["--rough-nodes", "3,4,2"]);
    assert_eq!(doc["stack"], "soap");
    assert_eq!(doc["rough_nodes"], serde_json::json!([3, 4, 2]));
    assert!(doc["seconds"].as_f64().unwrap() > 0.0);
    // The default quadrature's 128 μ intervals.
    assert!(doc["mu_nodes"].as_u64().unwrap() > 128);
    for bad in ["3,4", "3,4,0", "3,4,1.5", "a,b,c", "100000,100000,100000"] {
        irid(["bench", "--grid", "soap", "--rough-nodes", bad])
            .assert_one_line_error(bad, &["--rough-nodes"]);
    }
    irid([
        "bench",
        "--grid",
        "soap",
        "--rough-nodes",
        "3,4,2",
        "--bake-nodes",
        "6,4",
    ])
    .assert_one_line_error("both", &[]);
}

/// `--inverse`: the inverse-design section alone, in inverse.md and on
/// stdout; not with another mode.
#[test]
fn inverse_times_the_gradient_and_the_fits() {
    let dir = Scratch::new("bench-inverse");
    let out = irid([
        "bench",
        "--inverse",
        "--repeat",
        "1",
        "-o",
        dir.path().to_str().unwrap(),
    ]);
    assert!(out.success(), "{}", out.stderr);
    let doc = std::fs::read_to_string(dir.path().join("inverse.md")).unwrap();
    assert_eq!(doc, out.stdout);
    for needle in ["× the forward | ≤ 3×", "ms | | < 50 ms", " spectra/s | "] {
        assert!(doc.contains(needle), "inverse.md lacks {needle:?}:\n{doc}");
    }
    irid(["bench", "--inverse", "--tables"]).assert_one_line_error("both", &[]);
}
