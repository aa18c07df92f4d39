//! Stack files (TOML) and index tables (CSV): every accepted form, and an
//! error naming the file and the field for each kind of bad input.

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

mod common;

use std::path::Path;

use common::Scratch;
use irid::optics::{Dispersion, IndexTable, Stack, StackSpec};

fn parse(text: &str) -> irid::Result<Stack> {
    Stack::from_toml_str(text, Path::new("."), "test.toml")
}

fn parse_err(text: &str) -> String {
    match parse(text) {
        Ok(s) => panic!("accepted {text:?} as {s:?}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn the_issue_example_parses() {
    let stack = parse(
        r#"
ambient   = { n = 1.0 }                 # real shorthand
substrate = { material = "gold" }       # built-in, dispersive
[[layers]]
n = [1.5, 0.15]                         # [n, k], k > 0 absorbs
thickness_nm = 300.0
[[layers]]
material = "TiO2"
thickness_nm = 80.0
"#,
    )
    .unwrap();
    assert_eq!(
        stack.ambient.dispersion,
        Dispersion::Constant { n: 1.0, k: 0.0 }
    );
    assert_eq!(stack.layers.len(), 2);
    assert_eq!(
        stack.layers[0].material.dispersion,
        Dispersion::Constant { n: 1.5, k: 0.15 }
    );
    assert_eq!(stack.layers[0].thickness_nm, 300.0);
    assert_eq!(stack.layers[1].material.name, "TiO2");
    assert_eq!(stack.layers[1].thickness_nm, 80.0);
    assert_eq!(stack.substrate.name, "gold");
    assert!(matches!(stack.substrate.dispersion, Dispersion::Table(_)));
}

#[test]
fn every_index_form() {
    let dir = Scratch::new("stack-files-forms");
    std::fs::create_dir_all(dir.join("data")).unwrap();
    std::fs::write(
        dir.join("data/film.csv"),
        "wl,n,k\n0.4,1.6,0.01\n0.8,1.5,0.03\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("stack.toml"),
        r#"
ambient = { n = 1 }
substrate = { sellmeier = { b = [0.6961663, 0.4079426, 0.8974794], c = [0.00467914826, 0.0135120631, 97.9340025] } }
[[layers]]
name = "oil"
cauchy = [1.46, 0.0045]
thickness_nm = 300
[[layers]]
cauchy = [1.5, 0.004, 0.0001]
thickness_nm = 0
[[layers]]
sellmeier = { a = 2.0, b = [1.0], c = [0.04] }
thickness_nm = 10.5
[[layers]]
table = "data/film.csv"
thickness_nm = 5
[[layers]]
material = "Fused-Silica"
thickness_nm = 1e6
"#,
    )
    .unwrap();
    let stack = Stack::load(&dir.join("stack.toml")).unwrap();
    let at = |m: &irid::optics::Material, wl: f64| m.index_at(wl).unwrap();
    assert_eq!(at(&stack.ambient, 500.0).re, 1.0);
    // The substrate's Sellmeier is Malitson's silica written out: it must
    // match the built-in.
    let silica = &stack.layers[4].material;
    assert!((at(&stack.substrate, 550.0) - at(silica, 550.0)).norm() < 1e-9);
    assert_eq!(stack.layers[0].material.name, "oil");
    assert!((at(&stack.layers[0].material, 500.0).re - (1.46 + 0.0045 / 0.25)).abs() < 1e-15);
    let c3 = at(&stack.layers[1].material, 1000.0).re;
    assert!((c3 - 1.5041).abs() < 1e-12, "{c3}");
    let s = at(&stack.layers[2].material, 400.0).re;
    assert!((s * s - (2.0 + 0.16 / (0.16 - 0.04))).abs() < 1e-12, "{s}");
    let t = at(&stack.layers[3].material, 600.0);
    assert!(
        (t.re - 1.55).abs() < 1e-12 && (t.im - 0.02).abs() < 1e-12,
        "{t}"
    );
    assert_eq!(stack.layers[4].thickness_nm, 1e6);
}

#[test]
fn spec_round_trips_through_toml() {
    let text = r#"
ambient = { n = 1.0 }
substrate = { material = "silver" }
[[layers]]
n = [2.0, -0.1]
thickness_nm = 120.0
"#;
    let spec: StackSpec = toml::from_str(text).unwrap();
    let again: StackSpec = toml::from_str(&toml::to_string(&spec).unwrap()).unwrap();
    assert_eq!(spec, again);
    assert_eq!(spec.resolve(Path::new(".")).unwrap(), parse(text).unwrap());
}

#[test]
fn errors_name_the_file_and_the_field() {
    let base = "ambient = { n = 1.0 }\nsubstrate = { n = 1.5 }\n";
    let layer = |body: &str| format!("{base}[[layers]]\n{body}\n");
    let cases: Vec<(String, &[&str])> = vec![
        ("ambient = { n = }".into(), &["test.toml", "line 1"]),
        ("ambient = { n = 1.0 }".into(), &["test.toml", "substrate"]),
        (
            layer("material = \"unobtainium\"\nthickness_nm = 5"),
            &["layers[1].material", "unobtainium"],
        ),
        (
            layer("n = 1.4\nthickness_nm = -5"),
            &["layers[1].thickness_nm", "-5"],
        ),
        (
            layer("n = 1.4\nthickness_nm = nan"),
            &["layers[1].thickness_nm"],
        ),
        (
            layer("n = 1.4\nthickness_nm = inf"),
            &["layers[1].thickness_nm", "inf"],
        ),
        (layer("n = 1.4"), &["layers[1].thickness_nm", "missing"]),
        (
            layer("n = 1.4\nmaterial = \"gold\"\nthickness_nm = 5"),
            &["layers[1]", "exactly one", "n and material"],
        ),
        (layer("thickness_nm = 5"), &["layers[1]", "got none"]),
        (
            layer("n = 1.4\nthicknes_nm = 5"),
            &["test.toml", "line 5", "unknown field `thicknes_nm`"],
        ),
        (
            layer("n = [1.4, 0.1, 3]\nthickness_nm = 5"),
            &["test.toml", "line 4"],
        ),
        (
            layer("n = 0\nthickness_nm = 5"),
            &["layers[1]", "|n + ik| ≥ 1e-6"],
        ),
        (layer("n = -1.5\nthickness_nm = 5"), &["layers[1]", "0 ≤ n"]),
        (
            layer("n = [1.5, 1e7]\nthickness_nm = 5"),
            &["layers[1]", "|k| ≤ 1e6"],
        ),
        (
            layer("cauchy = [1.5]\nthickness_nm = 5"),
            &["layers[1].cauchy", "[A, B]"],
        ),
        (
            layer("sellmeier = { b = [1.0], c = [] }\nthickness_nm = 5"),
            &["layers[1]", "Sellmeier"],
        ),
        (
            layer("table = \"nope.csv\"\nthickness_nm = 5"),
            &["layers[1].table", "nope.csv"],
        ),
        (
            "ambient = { n = [1.0, 0.1] }\nsubstrate = { n = 1.5 }".into(),
            &["test.toml", "ambient", "lossless"],
        ),
        (
            "ambient = { material = \"gold\" }\nsubstrate = { n = 1.5 }".into(),
            &["ambient", "lossless"],
        ),
        (
            "ambient = { n = 1.0 }\nsubstrate = { n = [1.5, -0.1] }".into(),
            &["substrate", "gain"],
        ),
        (
            "ambient = { n = 1.0, thickness_nm = 3 }\nsubstrate = { n = 1.5 }".into(),
            &["ambient.thickness_nm"],
        ),
        (
            "ambient = { n = 1.0, coherent = false }\nsubstrate = { n = 1.5 }".into(),
            &[
                "test.toml",
                "ambient.coherent",
                "not allowed",
                "always incoherent",
            ],
        ),
        (
            "ambient = { n = 1.0 }\nsubstrate = { n = 1.5, coherent = true }".into(),
            &["test.toml", "substrate.coherent", "not allowed"],
        ),
        (
            layer("n = 1.4\nthickness_nm = 5\ncoherent = \"no\""),
            &["test.toml", "line 6", "expected a boolean"],
        ),
        (
            layer("n = 1.4\nthickness_nm = 5\ncoherent = 0"),
            &["test.toml", "line 6", "expected a boolean"],
        ),
    ];
    for (text, needles) in &cases {
        let err = parse_err(text);
        assert!(!err.contains('\n'), "one line: {err}");
        for needle in *needles {
            assert!(
                err.contains(needle),
                "{text:?}\n  gave {err:?}\n  which lacks {needle:?}"
            );
        }
    }
}

#[test]
fn a_layer_can_be_incoherent() {
    let stack = parse(
        "ambient = { n = 1.0 }\nsubstrate = { n = 1.0 }\n\
         [[layers]]\nn = 2.3\nthickness_nm = 80\n\
         [[layers]]\nmaterial = \"fused-silica\"\nthickness_nm = 1e6\ncoherent = false\n\
         [[layers]]\nn = 1.38\nthickness_nm = 100\ncoherent = true\n",
    )
    .unwrap();
    let flags: Vec<bool> = stack.layers.iter().map(|l| l.coherent).collect();
    assert_eq!(flags, [true, false, true]);
    assert_eq!(stack.coherence().incoherent_layers(), &[2]);
    assert_eq!(stack.reversed().coherence().incoherent_layers(), &[2]);
    // The flag is kept through JSON (a table header), and left out when
    // true, so a coherent stack serializes as it always has.
    let json = serde_json::to_string(&stack).unwrap();
    assert_eq!(json.matches("\"coherent\":false").count(), 1);
    assert!(!json.contains("\"coherent\":true"));
    assert_eq!(serde_json::from_str::<Stack>(&json).unwrap(), stack);
}

#[test]
fn missing_stack_file_is_named() {
    let err = Stack::load(Path::new("no/such/stack.toml"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("no/such/stack.toml"), "{err}");
}

#[test]
fn csv_tables() {
    // Three columns, micrometres, headers and comments skipped.
    let t = IndexTable::parse_csv(
        "# from somewhere\nwl,n,k\n0.4,1.5,0.1\n0.5,1.6,0.2\n0.6 1.7 0.3\n",
        "a.csv",
    )
    .unwrap();
    assert_eq!(t.wavelength_nm, vec![400.0, 500.0, 600.0]);
    assert_eq!(t.k, vec![0.1, 0.2, 0.3]);
    let mid = t.index_at(450.0).unwrap();
    assert!((mid.re - 1.55).abs() < 1e-12 && (mid.im - 0.15).abs() < 1e-12);
    assert!(t.index_at(399.0).is_none() && t.index_at(601.0).is_none());
    // Two columns: a lossless table.
    let t = IndexTable::parse_csv("wl,n\n0.3,1.4\n0.9,1.3\n", "b.csv").unwrap();
    assert_eq!(t.k, vec![0.0, 0.0]);
    // refractiveindex.info's two-block export: n, then k on another grid;
    // merged on the union of grids over the shared range.
    let t = IndexTable::parse_csv(
        "wl,n\n0.4,1.0\n0.6,2.0\n0.8,3.0\nwl,k\n0.5,0.5\n0.9,0.9\n",
        "c.csv",
    )
    .unwrap();
    assert_eq!(t.wavelength_nm, vec![500.0, 600.0, 800.0]);
    assert_eq!(t.n, vec![1.5, 2.0, 3.0]);
    assert!((t.k[1] - 0.6).abs() < 1e-12 && (t.k[2] - 0.8).abs() < 1e-12);
    // Bad tables name the file and the line.
    for (text, needle) in [
        ("wl,n,k\n0.4,1.5,x\n0.5,1.5,0\n", "line 2"),
        ("wl,n,k\n0.4,1.5,0,7\n", "line 2"),
        ("wl,n,k\n0.5,1.5,0\n0.4,1.5,0\n", "increase"),
        ("wl,n,k\n0.5,1.5,0\n", "at least 2"),
        ("", "at least 2"),
    ] {
        let err = IndexTable::parse_csv(text, "bad.csv")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("bad.csv") && err.contains(needle),
            "{text:?}: {err}"
        );
    }
}

#[test]
fn shipped_example_stacks_load() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("luts");
    for name in [
        "soap-film.toml",
        "oil-on-water.toml",
        "absorbing-film.toml",
        "gain-on-gold.toml",
        "two-layer.toml",
        "mirror-10.toml",
    ] {
        let stack = Stack::load(&dir.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        for wl in [380.0, 550.0, 780.0] {
            stack
                .response(wl, 0.7)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }
    let mirror = Stack::load(&dir.join("mirror-10.toml")).unwrap();
    assert_eq!(mirror.layers.len(), 10);
    assert!(mirror.response(550.0, 1.0).unwrap().r() > 0.98);
}

#[test]
fn a_stack_read_back_from_json_is_checked_not_trusted() {
    // The LUT header embeds the stack as JSON; a damaged one must fail
    // validation with a message, not panic in the solver.
    let stack =
        Stack::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("luts/two-layer.toml")).unwrap();
    let json = serde_json::to_string(&stack).unwrap();
    let back: Stack = serde_json::from_str(&json).unwrap();
    assert_eq!(back, stack);
    back.validate().unwrap();
    let mut damaged = back.clone();
    if let Dispersion::Table(t) = &mut damaged.substrate.dispersion {
        t.k.pop();
    }
    let err = damaged.validate().unwrap_err().to_string();
    assert!(
        err.contains("substrate") && err.contains("unequal"),
        "{err}"
    );
    assert!(damaged.response(500.0, 1.0).is_err());
    let mut empty = back;
    if let Dispersion::Table(t) = &mut empty.substrate.dispersion {
        t.wavelength_nm.clear();
        t.n.clear();
        t.k.clear();
    }
    assert!(empty.validate().is_err());
    assert!(empty.response(500.0, 1.0).is_err());
}
