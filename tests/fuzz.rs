//! A seeded, structure-aware mutation fuzzer over everything `irid` reads:
//! stack files, scene files, OBJ meshes, OpenEXR tables (damaged bytes, and
//! well-formed files whose `irid` header or pixels are evil), CSV index
//! tables, and the command line's numeric flags.
//!
//! Each case mutates a valid input (numbers swapped for extremes, tokens
//! inserted, deleted or duplicated, bytes flipped), feeds it to the
//! library's parser in-process (the command line through the binary) and
//! checks: no panic, no abort (allocations stay under a small memory budget),
//! no non-finite result reported as a success, no file left behind.
//!
//! `IRID_FUZZ_CASES` sets the number of in-process cases (default 600, a
//! few seconds in release), `IRID_FUZZ_CLI_CASES` the command-line runs
//! (default 40) and `IRID_FUZZ_SEED` the seed (default 1). A failure prints
//! the case's seed and input.

mod common;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, Layer, LayerAttributes,
    SmallVec, Text, WritableImage,
};
use irid::lut::{BakeSpec, Kind, Lut, Resolution};
use irid::optics::{IndexTable, Stack};
use irid::render::{FilmMode, RenderOptions, Scene};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

#[cfg(feature = "cli")]
use common::irid_in;
use common::Scratch;

fn env_count(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Numbers that have broken parsers and solvers before.
const EVIL_NUMBERS: &[&str] = &[
    "0",
    "-0",
    "-1",
    "1e-320",
    "1e-300",
    "1e-100",
    "1e-7",
    "1e-38",
    "4e-45",
    "1e38",
    "3.5e38",
    "1e39",
    "1e300",
    "1.8e308",
    "nan",
    "inf",
    "-inf",
    "65536",
    "65537",
    "4294967296",
    "18446744073709551615",
    "9223372036854775807",
    "2147483648",
    "1048577",
    "16777217",
    "67108865",
    "1e12",
    "1e13",
    "0.5",
    "1",
    "2",
    "3",
];

/// Tokens that change structure.
const EVIL_TOKENS: &[&str] = &[
    "[",
    "]",
    "{",
    "}",
    ",",
    "=",
    "\"",
    "\n",
    "[[layers]]\n",
    "[[objects]]\n",
    "\u{1b}[31m",
    "\0",
    "#",
    "f 1\n",
    "f 1 2\n",
    "v 0 0 0\n",
    "f 1 1 1\n",
    "f -1 -2 -3\n",
    "vn 0 0 0\n",
];

/// One mutation of `text`: a number replaced by an evil one, a token
/// inserted, a span deleted or duplicated, or a byte changed.
fn mutate(text: &[u8], rng: &mut Pcg64) -> Vec<u8> {
    let mut out = text.to_vec();
    let rounds = 1 + rng.random_range(0..3);
    for _ in 0..rounds {
        let len = out.len().max(1);
        match rng.random_range(0..6) {
            0 | 1 => {
                // Replace a number (a run of digits, sign, point, e).
                let starts: Vec<usize> = (0..out.len())
                    .filter(|&i| {
                        out[i].is_ascii_digit() && (i == 0 || !out[i - 1].is_ascii_alphanumeric())
                    })
                    .collect();
                if starts.is_empty() {
                    continue;
                }
                let s = starts[rng.random_range(0..starts.len())];
                let mut e = s;
                while e < out.len() && (out[e].is_ascii_alphanumeric() || b".-+".contains(&out[e]))
                {
                    e += 1;
                }
                let evil = EVIL_NUMBERS[rng.random_range(0..EVIL_NUMBERS.len())];
                out.splice(s..e, evil.bytes());
            }
            2 => {
                let at = rng.random_range(0..=out.len());
                let token = EVIL_TOKENS[rng.random_range(0..EVIL_TOKENS.len())];
                out.splice(at..at, token.bytes());
            }
            3 => {
                let a = rng.random_range(0..len);
                let b = (a + rng.random_range(0..32)).min(out.len());
                out.drain(a.min(out.len())..b);
            }
            4 => {
                let a = rng.random_range(0..len);
                let b = (a + rng.random_range(0..64)).min(out.len());
                let copy: Vec<u8> = out[a.min(out.len())..b].to_vec();
                let at = rng.random_range(0..=out.len());
                out.splice(at..at, copy);
            }
            _ => {
                if !out.is_empty() {
                    let i = rng.random_range(0..out.len());
                    out[i] = rng.random();
                }
            }
        }
    }
    out
}

const STACKS: &[&str] = &[
    "ambient = { n = 1.0 }\nsubstrate = { n = 1.0 }\n[[layers]]\nn = 1.33\nthickness_nm = 500.0\n",
    "ambient = { n = 1.0 }\nsubstrate = { n = 1.33 }\n[[layers]]\nn = 1.5\nthickness_nm = 300.0\n",
    "ambient = \"air\"\nsubstrate = \"gold\"\n[[layers]]\nmaterial = \"water\"\nthickness_nm = 250.0\n[[layers]]\nn = [1.2, -0.01]\nthickness_nm = 40.0\n",
    "ambient = { n = 1.0 }\nsubstrate = { table = \"m.csv\" }\n[[layers]]\ncauchy = { a = 1.45, b = 0.004, c = 0.0 }\nthickness_nm = 120.0\n",
];

const CSV: &str = "wl,n,k\n0.40,1.50,0.01\n0.50,1.45,0.02\n0.60,1.40,0.00\n0.80,1.38,0.00\n";

const OBJ: &str =
    "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n";

const SCENES: &[&str] = &[
    "name = \"f\"\n[render]\nwidth = 8\nheight = 8\nspp = 1\nmax_depth = 3\n[camera]\nposition = [0.0, 1.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_deg = 40.0\n[materials.grey]\nkind = \"diffuse\"\nalbedo = [0.8, 0.8, 0.8]\n[[objects]]\nshape = \"obj\"\nmaterial = \"grey\"\npath = \"m.obj\"\n[[objects]]\nshape = \"gem\"\nmaterial = \"grey\"\nradius = 0.5\n",
    "name = \"g\"\n[render]\nwidth = 8\nheight = 8\nspp = 1\nmax_depth = 3\n[camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_deg = 40.0\n[materials.grey]\nkind = \"diffuse\"\nalbedo = [0.8, 0.8, 0.8]\n[[objects]]\nshape = \"torus\"\nmaterial = \"grey\"\nmajor_radius = 1.0\nminor_radius = 0.25\n[[objects]]\nshape = \"sphere\"\nmaterial = \"grey\"\nradius = 0.5\ncenter = [0.0, 0.0, 0.0]\n",
];

/// What a case found wrong.
type Finding = String;

fn finite_all(values: &[f64]) -> bool {
    values.iter().all(|v| v.is_finite())
}

fn stack_case(text: &[u8], dir: &Path) -> Result<(), Finding> {
    let text = String::from_utf8_lossy(text);
    let Ok(stack) = Stack::from_toml_str(&text, dir, "stack") else {
        return Ok(());
    };
    if stack.validate().is_err() {
        return Ok(());
    }
    for (wl, cos) in [(500.0, 1.0), (400.0, 0.3), (700.0, 0.01)] {
        if let Ok(r) = stack.response(wl, cos) {
            if !finite_all(&[r.r(), r.t()]) {
                return Err(format!(
                    "response at {wl} nm, cos {cos}: R {} T {}",
                    r.r(),
                    r.t()
                ));
            }
        }
    }
    Ok(())
}

fn csv_case(text: &[u8]) -> Result<(), Finding> {
    let text = String::from_utf8_lossy(text);
    let Ok(table) = IndexTable::parse_csv(&text, "m.csv") else {
        return Ok(());
    };
    table
        .check()
        .map_err(|e| format!("parsed but fails its own check: {e}"))?;
    Ok(())
}

/// A render small enough for thousands of cases.
fn tiny_render(scene: &Scene) -> Result<(), Finding> {
    let mut opts = RenderOptions::new(FilmMode::Direct {
        sampling: "rgb3".parse().unwrap(),
    });
    opts.width = Some(4);
    opts.height = Some(4);
    opts.spp = Some(1);
    opts.max_depth = Some(2);
    if let Ok(image) = irid::render::render(scene, &opts) {
        if image.pixels.iter().flatten().any(|v| !v.is_finite()) {
            return Err("a rendered pixel is not finite".into());
        }
    }
    Ok(())
}

fn scene_case(text: &[u8], dir: &Path) -> Result<(), Finding> {
    let text = String::from_utf8_lossy(text);
    match Scene::from_toml_str(&text, dir, "scene") {
        Ok(scene) => tiny_render(&scene),
        Err(_) => Ok(()),
    }
}

fn obj_case(obj: &[u8], dir: &Path) -> Result<(), Finding> {
    std::fs::write(dir.join("m.obj"), obj).unwrap();
    scene_case(SCENES[0].as_bytes(), dir)
}

/// A table's pixels and header, to rewrite with evil changes.
struct TableParts {
    width: usize,
    height: usize,
    channels: Vec<(String, Vec<f32>)>,
    header: serde_json::Value,
}

fn table_parts(path: &Path) -> TableParts {
    let image = common::read_exr(path);
    let layer = &image.layer_data;
    let Some(AttributeValue::Text(text)) = layer.attributes.other.get(&Text::from("irid")) else {
        panic!("no irid header in {}", path.display());
    };
    let json: String = text.bytes().iter().map(|&b| b as char).collect();
    TableParts {
        width: layer.size.0,
        height: layer.size.1,
        channels: layer
            .channel_data
            .list
            .iter()
            .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
            .collect(),
        header: serde_json::from_str(&json).unwrap(),
    }
}

fn write_table(path: &Path, parts: &TableParts, header_text: &str) {
    let mut list: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
    for (name, values) in &parts.channels {
        list.push(AnyChannel::new(
            name.as_str(),
            FlatSamples::F32(values.clone()),
        ));
    }
    let mut attributes = LayerAttributes::default();
    attributes.other.insert(
        Text::from("irid"),
        AttributeValue::Text(Text::from(ascii_json(header_text).as_str())),
    );
    let layer = Layer::new(
        (parts.width, parts.height),
        attributes,
        Encoding::UNCOMPRESSED,
        AnyChannels::sort(list),
    );
    Image::from_layer(layer).write().to_file(path).unwrap();
}

/// JSON with every non-ASCII character as a \u escape: EXR text is bytes.
fn ascii_json(json: &str) -> String {
    let mut out = String::new();
    for c in json.chars() {
        if c.is_ascii() {
            out.push(c);
        } else {
            for unit in c.encode_utf16(&mut [0u16; 2]) {
                out.push_str(&format!("\\u{unit:04x}"));
            }
        }
    }
    out
}

/// Every leaf of a JSON value, as a path of keys and indices.
fn leaves(v: &serde_json::Value, at: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    match v {
        serde_json::Value::Object(m) => {
            for (k, x) in m {
                at.push(k.clone());
                leaves(x, at, out);
                at.pop();
            }
        }
        serde_json::Value::Array(a) => {
            out.push(at.clone());
            for (i, x) in a.iter().enumerate().take(8) {
                at.push(i.to_string());
                leaves(x, at, out);
                at.pop();
            }
        }
        _ => out.push(at.clone()),
    }
}

fn at_path<'a>(v: &'a mut serde_json::Value, path: &[String]) -> &'a mut serde_json::Value {
    path.iter().fold(v, |v, k| match v {
        serde_json::Value::Array(a) => &mut a[k.parse::<usize>().unwrap()],
        other => &mut other[k.as_str()],
    })
}

/// An evil header: one leaf replaced by an extreme number, an empty or
/// truncated or duplicated array, a string with control characters.
fn evil_header(parts: &TableParts, rng: &mut Pcg64) -> String {
    let mut header = parts.header.clone();
    for _ in 0..1 + rng.random_range(0..2) {
        let mut paths = Vec::new();
        leaves(&header, &mut Vec::new(), &mut paths);
        let path = &paths[rng.random_range(0..paths.len())];
        let leaf = at_path(&mut header, path);
        let evil: serde_json::Value = match (leaf.clone(), rng.random_range(0..6)) {
            (serde_json::Value::Array(mut a), k) if k < 3 && !a.is_empty() => {
                match k {
                    0 => a.truncate(rng.random_range(0..a.len())),
                    1 => {
                        let i = rng.random_range(0..a.len());
                        let x = a[i].clone();
                        a.insert(i, x);
                    }
                    _ => a.reverse(),
                }
                serde_json::Value::Array(a)
            }
            (_, 3) => serde_json::Value::String("x\u{1b}[2J\u{0}".into()),
            (_, 4) => {
                let shift = rng.random_range(0..63);
                serde_json::json!(rng.random_range(0..u64::MAX >> shift))
            }
            _ => {
                let n = EVIL_NUMBERS[rng.random_range(0..EVIL_NUMBERS.len())];
                serde_json::from_str(n).unwrap_or(serde_json::json!(1e300))
            }
        };
        *leaf = evil;
    }
    serde_json::to_string(&header).unwrap()
}

fn table_case(parts: &TableParts, base: &[u8], dir: &Path, rng: &mut Pcg64) -> Result<(), Finding> {
    let path = dir.join("t.exr");
    match rng.random_range(0..4) {
        0 => std::fs::write(&path, mutate(base, rng)).unwrap(),
        1 => {
            // Evil pixels under a correct header.
            let mut evil = TableParts {
                width: parts.width,
                height: parts.height,
                channels: parts.channels.clone(),
                header: parts.header.clone(),
            };
            let c = rng.random_range(0..evil.channels.len());
            let values = &mut evil.channels[c].1;
            let i = rng.random_range(0..values.len());
            values[i] =
                [f32::NAN, f32::INFINITY, -f32::INFINITY, 1e30, -1e30][rng.random_range(0..5)];
            write_table(&path, &evil, &serde_json::to_string(&evil.header).unwrap());
        }
        _ => write_table(&path, parts, &evil_header(parts, rng)),
    }
    let Ok(lut) = Lut::load(&path) else {
        return Ok(());
    };
    if lut.data().iter().any(|v| !v.is_finite()) {
        return Err("a table with non-finite values loaded".into());
    }
    let probes = [
        0.0f32,
        0.5,
        1.0,
        -1.0,
        1e30,
        f32::NAN,
        f32::INFINITY,
        350.0,
        550.0,
    ];
    for _ in 0..16 {
        let mut pick = || probes[rng.random_range(0..probes.len())];
        let (t, c, w) = (pick(), pick(), pick());
        match lut.kind() {
            Kind::Rgb => {
                let s = lut.sample_rgb(t, c);
                if s.reflectance
                    .iter()
                    .chain(&s.transmittance)
                    .any(|v| !v.is_finite())
                {
                    return Err(format!("sample_rgb({t}, {c}) is not finite: {s:?}"));
                }
            }
            Kind::Spectral => {
                let (r, tr) = lut.sample_spectral(t, c, w);
                if !(r.is_finite() && tr.is_finite()) {
                    return Err(format!("sample_spectral({t}, {c}, {w}) = ({r}, {tr})"));
                }
            }
        }
    }
    if let Ok(stats) = irid::lut::validate(&lut, 2, rng.random()) {
        if !finite_all(&stats.figures.max_abs) {
            return Err(format!(
                "validation succeeded with max_abs {:?}",
                stats.figures.max_abs
            ));
        }
    }
    Ok(())
}

/// A spec's checks with evil numbers: they must refuse or accept, never
/// panic, and an accepted fixed resolution must fit the budget.
fn spec_case(rng: &mut Pcg64) -> Result<(), Finding> {
    let stack = Stack::from_toml_str(STACKS[0], Path::new("."), "s").unwrap();
    let mut spec = BakeSpec::new(stack);
    let big = |rng: &mut Pcg64| -> usize {
        [0, 1, 2, 65536, 65537, usize::MAX, 1 << 32, 1 << 26][rng.random_range(0..8)]
    };
    spec.kind = if rng.random() {
        Kind::Spectral
    } else {
        Kind::Rgb
    };
    spec.check = rng.random();
    spec.half = rng.random();
    spec.resolution = if rng.random() {
        Resolution::Nodes {
            thickness: big(rng),
            angle: big(rng),
            wavelength: big(rng),
        }
    } else {
        let n = EVIL_NUMBERS[rng.random_range(0..EVIL_NUMBERS.len())];
        Resolution::MaxError(n.parse().unwrap_or(f64::NAN))
    };
    spec.validation_points = big(rng);
    let _ = spec.validate();
    Ok(())
}

#[test]
fn fuzz_parsers_in_process() {
    // Small enough that an unchecked input-driven allocation would be
    // refused long before the allocator could abort the test.
    irid::limits::set_memory_budget(Some(256 << 20));
    let cases = env_count("IRID_FUZZ_CASES", 600);
    let seed = env_count("IRID_FUZZ_SEED", 1);
    let luts = Path::new(env!("CARGO_MANIFEST_DIR")).join("luts");
    let rgb_path = luts.join("soap-film.exr");
    let rgb = (table_parts(&rgb_path), std::fs::read(&rgb_path).unwrap());
    let scratch = Scratch::new("fuzz-base");
    let spectral_path = scratch.path().join("spectral.exr");
    let mut spec = BakeSpec::new(Stack::from_toml_str(STACKS[1], Path::new("."), "s").unwrap());
    spec.kind = Kind::Spectral;
    spec.thickness_nm = (100.0, 400.0);
    spec.resolution = Resolution::Nodes {
        thickness: 5,
        angle: 4,
        wavelength: 6,
    };
    spec.check = false;
    irid::lut::bake(&spec)
        .unwrap()
        .write(&spectral_path)
        .unwrap();
    let spectral = (
        table_parts(&spectral_path),
        std::fs::read(&spectral_path).unwrap(),
    );

    let start = std::time::Instant::now();
    let mut failures = Vec::new();
    let mut per_target = [0u64; 7];
    for case in 0..cases {
        let case_seed = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ case;
        let mut rng = Pcg64::seed_from_u64(case_seed);
        let dir = Scratch::new("fuzz");
        std::fs::write(dir.path().join("m.csv"), CSV).unwrap();
        std::fs::write(dir.path().join("m.obj"), OBJ).unwrap();
        let target = rng.random_range(0..per_target.len());
        per_target[target] += 1;
        let mut input = Vec::new();
        let outcome = catch_unwind(AssertUnwindSafe(|| match target {
            0 => {
                input = mutate(
                    STACKS[rng.random_range(0..STACKS.len())].as_bytes(),
                    &mut rng,
                );
                stack_case(&input, dir.path())
            }
            1 => {
                input = mutate(
                    SCENES[rng.random_range(0..SCENES.len())].as_bytes(),
                    &mut rng,
                );
                scene_case(&input, dir.path())
            }
            2 => {
                input = mutate(OBJ.as_bytes(), &mut rng);
                obj_case(&input, dir.path())
            }
            3 => {
                input = mutate(CSV.as_bytes(), &mut rng);
                csv_case(&input)
            }
            4 => table_case(&rgb.0, &rgb.1, dir.path(), &mut rng),
            5 => table_case(&spectral.0, &spectral.1, dir.path(), &mut rng),
            _ => spec_case(&mut rng),
        }));
        let finding = match outcome {
            Ok(Ok(())) => None,
            Ok(Err(f)) => Some(f),
            Err(panic) => Some(format!(
                "panic: {}",
                panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default()
            )),
        };
        // Nothing but the inputs (and the table the case wrote) may remain.
        let left: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| !["m.csv", "m.obj", "t.exr"].contains(&n.as_str()))
            .collect();
        let finding =
            finding.or_else(|| (!left.is_empty()).then(|| format!("left files {left:?}")));
        if (case + 1) % 10_000 == 0 {
            eprintln!(
                "fuzz: {} cases in {:.0} s, {} findings so far",
                case + 1,
                start.elapsed().as_secs_f64(),
                failures.len()
            );
        }
        if let Some(f) = finding {
            failures.push(format!(
                "case {case} (seed {case_seed}, target {target}): {f}\n  input: {:?}",
                String::from_utf8_lossy(&input)
            ));
        }
    }
    irid::limits::set_memory_budget(None);
    eprintln!(
        "fuzz: {cases} cases (stack, scene, obj, csv, rgb table, spectral table, spec: {per_target:?}) in {:.2} s, {} findings",
        start.elapsed().as_secs_f64(),
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The command line with numeric flags at their extremes: exit 0, 1 or 2;
/// an error is one line; a success prints no NaN or infinity; nothing but
/// the named outputs is left behind.
#[cfg(feature = "cli")]
#[test]
fn fuzz_numeric_flags_through_the_binary() {
    let cases = env_count("IRID_FUZZ_CLI_CASES", 40);
    let seed = env_count("IRID_FUZZ_SEED", 1);
    let templates: &[&[&str]] = &[
        &["eval", "s.toml", "--wavelengths", "#", "--angles", "#"],
        &["eval", "s.toml", "--wavelengths", "#:#:#", "--json"],
        &["color", "s.toml", "--angles", "#"],
        &[
            "bake",
            "s.toml",
            "-o",
            "o.exr",
            "--resolution",
            "#,#",
            "--no-check",
        ],
        &[
            "bake",
            "s.toml",
            "-o",
            "o.exr",
            "--max-error",
            "#",
            "--thickness",
            "#:#",
        ],
        &[
            "bake",
            "s.toml",
            "-o",
            "o.exr",
            "--kind",
            "spectral",
            "--resolution",
            "#,#,#",
            "--no-check",
            "--validate-points",
            "#",
        ],
        &["validate", "t.exr", "--points", "#", "--seed", "#"],
        &[
            "render",
            "bubbles-uniform",
            "-o",
            "o.png",
            "--width",
            "#",
            "--height",
            "#",
            "--spp",
            "1",
            "--film",
            "direct",
            "--sampling",
            "rgb3",
        ],
        &[
            "render",
            "bubbles-uniform",
            "-o",
            "o.png",
            "--width",
            "8",
            "--height",
            "8",
            "--spp",
            "#",
            "--max-depth",
            "#",
            "--film",
            "direct",
            "--sampling",
            "uniform:#",
        ],
    ];
    let mut failures = Vec::new();
    for case in 0..cases {
        let mut rng = Pcg64::seed_from_u64(seed.wrapping_mul(31) ^ (case << 20));
        let dir = Scratch::new("fuzz-cli");
        dir.write("s.toml", STACKS[0]);
        std::fs::copy(
            Path::new(env!("CARGO_MANIFEST_DIR")).join("luts/soap-film.exr"),
            dir.path().join("t.exr"),
        )
        .unwrap();
        let template = templates[rng.random_range(0..templates.len())];
        let args: Vec<String> = template
            .iter()
            .map(|a| {
                a.split('#')
                    .collect::<Vec<_>>()
                    .join(EVIL_NUMBERS[rng.random_range(0..EVIL_NUMBERS.len())])
            })
            .collect();
        let run = irid_in(dir.path(), &args);
        let mut problems = Vec::new();
        match run.code {
            Some(0) | Some(1) => {
                for bad in ["NaN", "inf", "null"] {
                    if run.stdout.contains(bad) {
                        problems.push(format!("success printed {bad}"));
                    }
                }
            }
            Some(2) => {
                if run.stderr.lines().count() != 1 || !run.stderr.starts_with("irid: ") {
                    problems.push("exit 2 without exactly one 'irid: ' line".into());
                }
            }
            other => problems.push(format!("exit {other:?}")),
        }
        if run.stderr.contains("panicked") {
            problems.push("panic".into());
        }
        let left: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| !["s.toml", "t.exr", "o.exr", "o.png"].contains(&n.as_str()))
            .collect();
        if !left.is_empty() {
            problems.push(format!("left {left:?}"));
        }
        if !problems.is_empty() {
            failures.push(format!("{args:?}: {problems:?}\n{}", run.stderr));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
