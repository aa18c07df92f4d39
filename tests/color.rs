//! Colour: CIE integration, sampling strategies, Lab and CIEDE2000.

// Not an API: a test crate has no public API to document.
#![allow(missing_docs)]

mod common;

#[cfg(feature = "cli")]
use common::{irid, Scratch};
use irid::atlas::Film;
use irid::color::refine::{Refinement, MAX_SUB_STEPS};
use irid::color::{
    delta_e2000, delta_e2000_rgb, linear_srgb_to_xyz, stack_colors, white_xyz, xyz_to_lab,
    xyz_to_linear_srgb, Sampling, SpectralIntegrator, White,
};
use irid::optics::{Layer, Material, Response, Stack, StackGrid};

fn all_samplings() -> Vec<Sampling> {
    let mut s = vec![Sampling::Rgb3, Sampling::Exact];
    s.extend([2, 3, 9, 41, 81, 100, 401].map(Sampling::Uniform));
    s
}

fn close(a: [f64; 3], b: [f64; 3], tol: f64) -> bool {
    a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= tol)
}

#[test]
fn perfect_reflector_is_d65_white() {
    let exact = SpectralIntegrator::new(Sampling::Exact);
    let one = vec![1.0; exact.wavelengths_nm().len()];
    let xyz = exact.xyz(&one);
    // CIE 015 gives the D65 white as (95.047, 100, 108.883) from the 5 nm table;
    // at 1 nm with linear interpolation it agrees to 4 digits.
    assert!(close(xyz, [0.9505, 1.0, 1.0888], 5e-5), "{xyz:?}");
    assert!((xyz[1] - 1.0).abs() < 1e-14, "{xyz:?}");
    assert!(close(xyz, white_xyz(), 1e-14));
    // numpy: np.interp of the 5 nm D65 to 1 nm, times the CMFs, summed.
    assert!(close(
        xyz,
        [0.9504707022400521, 1.0, 1.0888284599770484],
        1e-12
    ));
    let lab = xyz_to_lab(xyz);
    assert!(close(lab, [100.0, 0.0, 0.0], 1e-12), "{lab:?}");
    for s in all_samplings() {
        let integ = SpectralIntegrator::new(s);
        let one = vec![1.0; integ.wavelengths_nm().len()];
        let rgb = integ.rgb(&one);
        assert!(close(rgb, [1.0; 3], 1e-12), "{s}: {rgb:?}");
        let xyz = integ.xyz(&one);
        assert!(close(xyz, white_xyz(), 1e-12), "{s}: {xyz:?}");
    }
}

#[test]
fn zero_is_black_and_flat_maps_to_its_value() {
    for s in all_samplings() {
        let integ = SpectralIntegrator::new(s);
        let n = integ.wavelengths_nm().len();
        assert_eq!(integ.rgb(&vec![0.0; n]), [0.0; 3], "{s}");
        assert_eq!(integ.xyz(&vec![0.0; n]), [0.0; 3], "{s}");
        for v in [0.25, 0.5, 0.8] {
            let rgb = integ.rgb(&vec![v; n]);
            assert!(close(rgb, [v; 3], 1e-12), "{s} {v}: {rgb:?}");
        }
    }
}

#[test]
fn strategies_sample_where_they_say() {
    let rgb3 = SpectralIntegrator::new(Sampling::Rgb3);
    assert_eq!(rgb3.wavelengths_nm(), &[475.0, 510.0, 650.0]);
    // Ascending wavelengths: B, G, R.
    assert!(close(rgb3.rgb(&[0.1, 0.2, 0.3]), [0.3, 0.2, 0.1], 1e-15));
    let xyz = rgb3.xyz(&[0.1, 0.2, 0.3]);
    assert!(close(xyz, linear_srgb_to_xyz([0.3, 0.2, 0.1]), 1e-15));

    let u9 = SpectralIntegrator::new(Sampling::Uniform(9));
    let w = u9.wavelengths_nm();
    assert_eq!((w.len(), w[0], w[1], w[8]), (9, 380.0, 430.0, 780.0));
    let u100 = SpectralIntegrator::new(Sampling::Uniform(100));
    let w = u100.wavelengths_nm();
    assert!((w[1] - w[0] - 400.0 / 99.0).abs() < 1e-12 && w[99] == 780.0);

    // A spectrum that is 1 only in 540-560 nm is green in every integrating
    // strategy, and a pure 600 nm spike lands in the red-orange.
    let exact = SpectralIntegrator::new(Sampling::Exact);
    let band: Vec<f64> = exact
        .wavelengths_nm()
        .iter()
        .map(|&l| f64::from((540.0..=560.0).contains(&l)))
        .collect();
    let g = exact.rgb(&band);
    assert!(g[1] > 4.0 * g[0].abs() && g[1] > 4.0 * g[2].abs(), "{g:?}");
    let xyz = exact.xyz(&band);
    assert!(close(xyz_to_linear_srgb(xyz), g, 1e-15));
}

#[test]
fn lab_of_the_srgb_primaries() {
    // colour-science 0.4.7: normalised_primary_matrix(IEC primaries, xy of the
    // tables' white (0.950471, 1, 1.088828)), then XYZ_to_Lab with that white.
    for (rgb, want) in [
        ([1.0, 0.0, 0.0], [53.2409, 80.0925, 67.2032]),
        ([0.0, 1.0, 0.0], [87.7347, -86.1828, 83.1792]),
        ([0.0, 0.0, 1.0], [32.2970, 79.1874, -107.8602]),
        ([0.2, 0.5, 0.1], [69.9883, -38.2150, 43.0482]),
    ] {
        let lab = xyz_to_lab(linear_srgb_to_xyz(rgb));
        assert!(close(lab, want, 1e-4), "{rgb:?}: {lab:?}");
    }
}

/// Sharma, G., Wu, W., Dalal, E. N. (2005). The CIEDE2000 color-difference
/// formula: implementation notes, supplementary test data, and mathematical
/// observations. Color Research & Application 30(1), 21–30, Table 1:
/// L1, a1, b1, L2, a2, b2, ΔE00.
#[rustfmt::skip]
const SHARMA_2005: [[f64; 7]; 34] = [
    [50.0000, 2.6772, -79.7751, 50.0000, 0.0000, -82.7485, 2.0425],
    [50.0000, 3.1571, -77.2803, 50.0000, 0.0000, -82.7485, 2.8615],
    [50.0000, 2.8361, -74.0200, 50.0000, 0.0000, -82.7485, 3.4412],
    [50.0000, -1.3802, -84.2814, 50.0000, 0.0000, -82.7485, 1.0000],
    [50.0000, -1.1848, -84.8006, 50.0000, 0.0000, -82.7485, 1.0000],
    [50.0000, -0.9009, -85.5211, 50.0000, 0.0000, -82.7485, 1.0000],
    [50.0000, 0.0000, 0.0000, 50.0000, -1.0000, 2.0000, 2.3669],
    [50.0000, -1.0000, 2.0000, 50.0000, 0.0000, 0.0000, 2.3669],
    [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0009, 7.1792],
    [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0010, 7.1792],
    [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0011, 7.2195],
    [50.0000, 2.4900, -0.0010, 50.0000, -2.4900, 0.0012, 7.2195],
    [50.0000, -0.0010, 2.4900, 50.0000, 0.0009, -2.4900, 4.8045],
    [50.0000, -0.0010, 2.4900, 50.0000, 0.0010, -2.4900, 4.8045],
    [50.0000, -0.0010, 2.4900, 50.0000, 0.0011, -2.4900, 4.7461],
    [50.0000, 2.5000, 0.0000, 50.0000, 0.0000, -2.5000, 4.3065],
    [50.0000, 2.5000, 0.0000, 73.0000, 25.0000, -18.0000, 27.1492],
    [50.0000, 2.5000, 0.0000, 61.0000, -5.0000, 29.0000, 22.8977],
    [50.0000, 2.5000, 0.0000, 56.0000, -27.0000, -3.0000, 31.9030],
    [50.0000, 2.5000, 0.0000, 58.0000, 24.0000, 15.0000, 19.4535],
    [50.0000, 2.5000, 0.0000, 50.0000, 3.1736, 0.5854, 1.0000],
    [50.0000, 2.5000, 0.0000, 50.0000, 3.2972, 0.0000, 1.0000],
    [50.0000, 2.5000, 0.0000, 50.0000, 1.8634, 0.5757, 1.0000],
    [50.0000, 2.5000, 0.0000, 50.0000, 3.2592, 0.3350, 1.0000],
    [60.2574, -34.0099, 36.2677, 60.4626, -34.1751, 39.4387, 1.2644],
    [63.0109, -31.0961, -5.8663, 62.8187, -29.7946, -4.0864, 1.2630],
    [61.2901, 3.7196, -5.3901, 61.4292, 2.2480, -4.9620, 1.8731],
    [35.0831, -44.1164, 3.7933, 35.0232, -40.0716, 1.5901, 1.8645],
    [22.7233, 20.0904, -46.6940, 23.0331, 14.9730, -42.5619, 2.0373],
    [36.4612, 47.8580, 18.3852, 36.2715, 50.5065, 21.2231, 1.4146],
    [90.8027, -2.0831, 1.4410, 91.1528, -1.6435, 0.0447, 1.4441],
    [90.9257, -0.5406, -0.9208, 88.6381, -0.8985, -0.7239, 1.5381],
    [6.7747, -0.2908, -2.4247, 5.8714, -0.0985, -2.2286, 0.6377],
    [2.0776, 0.0795, -1.1350, 0.9033, -0.0636, -0.5514, 0.9082],
];

#[test]
fn ciede2000_matches_sharma_2005() {
    for (i, p) in SHARMA_2005.iter().enumerate() {
        let (a, b) = ([p[0], p[1], p[2]], [p[3], p[4], p[5]]);
        for (x, y) in [(a, b), (b, a)] {
            let de = delta_e2000(x, y);
            assert!((de - p[6]).abs() < 1e-4, "pair {}: {de} vs {}", i + 1, p[6]);
        }
    }
    assert_eq!(delta_e2000([40.0, 10.0, -5.0], [40.0, 10.0, -5.0]), 0.0);
    assert_eq!(delta_e2000_rgb([0.2, 0.3, 0.4], [0.2, 0.3, 0.4]), 0.0);
    // Black against white is the full lightness range.
    assert!((delta_e2000_rgb([0.0; 3], [1.0; 3]) - 100.0).abs() < 1e-9);
}

/// Reflected and transmitted linear sRGB of a free-standing soap film
/// (n = 1.33 in air) under one sampling strategy, thickness-major.
fn soap_film_colors(
    integ: &SpectralIntegrator,
    thicknesses_nm: &[f64],
    angles_deg: &[f64],
) -> Vec<([f64; 3], [f64; 3])> {
    let mut out = Vec::with_capacity(thicknesses_nm.len() * angles_deg.len());
    for &d in thicknesses_nm {
        let colors = stack_colors(&soap_film(d), integ, angles_deg).unwrap();
        out.extend(
            colors
                .iter()
                .map(|c| (c.reflectance_rgb, c.transmittance_rgb)),
        );
    }
    out
}

fn soap_film(thickness_nm: f64) -> Stack {
    Stack {
        ambient: Material::constant(1.0, 0.0),
        layers: vec![Layer::new(Material::constant(1.33, 0.0), thickness_nm)],
        substrate: Material::constant(1.0, 0.0),
    }
}

#[test]
fn stack_colors_of_a_bare_interface() {
    // Air on glass n = 1.5 at normal incidence: R = 0.04 and T = 0.96 at every
    // wavelength, so the colours are those greys in every strategy.
    let glass = Stack {
        ambient: Material::constant(1.0, 0.0),
        layers: vec![],
        substrate: Material::constant(1.5, 0.0),
    };
    for s in all_samplings() {
        let c = stack_colors(&glass, &SpectralIntegrator::new(s), &[0.0, 60.0]).unwrap();
        assert_eq!(c.len(), 2);
        assert!(close(c[0].reflectance_rgb, [0.04; 3], 1e-12), "{s}: {c:?}");
        assert!(
            close(c[0].transmittance_rgb, [0.96; 3], 1e-12),
            "{s}: {c:?}"
        );
        let y = c[0].reflectance_xyz[1] + c[0].transmittance_xyz[1];
        assert!((y - 1.0).abs() < 1e-12);
        // Brighter reflection towards grazing incidence.
        assert!(c[1].reflectance_rgb[1] > 0.04);
    }
    let exact = SpectralIntegrator::new(Sampling::Exact);
    for bad in [90.0, -1.0, f64::NAN] {
        let e = stack_colors(&glass, &exact, &[bad]).unwrap_err();
        assert!(e.to_string().contains("angle"), "{e}");
    }
}

#[derive(Debug, Clone, Copy)]
struct Stats {
    mean: f64,
    max: f64,
}

fn stats(errors: impl Iterator<Item = f64>) -> Stats {
    let (mut sum, mut max, mut n) = (0.0, 0.0f64, 0);
    for e in errors {
        sum += e;
        max = max.max(e);
        n += 1;
    }
    Stats {
        mean: sum / n as f64,
        max,
    }
}

/// The paper's cheaper strategies against the 1 nm reference on a soap film,
/// 0–1000 nm thick (2 nm steps), 0–80° (10° steps). Run with `--nocapture`
/// to see the table.
#[test]
fn sampling_error_on_a_soap_film() {
    let thicknesses_nm: Vec<f64> = (0..=500).map(|i| 2.0 * i as f64).collect();
    let angles_deg: Vec<f64> = (0..=8).map(|i| 10.0 * i as f64).collect();
    let reference = soap_film_colors(
        &SpectralIntegrator::new(Sampling::Exact),
        &thicknesses_nm,
        &angles_deg,
    );
    println!(
        "soap film n=1.33 in air, {} thicknesses 0-1000 nm x {} angles 0-80 deg; CIEDE2000 vs exact",
        thicknesses_nm.len(),
        angles_deg.len()
    );
    println!(
        "{:<12} {:>10} {:>10} {:>10} {:>10}",
        "sampling", "R mean", "R max", "T mean", "T max"
    );
    let mut results = Vec::new();
    for s in [
        Sampling::Rgb3,
        Sampling::Uniform(9),
        Sampling::Uniform(41),
        Sampling::Uniform(81),
    ] {
        let got = soap_film_colors(&SpectralIntegrator::new(s), &thicknesses_nm, &angles_deg);
        let pairs = || got.iter().zip(&reference);
        let r = stats(pairs().map(|(g, e)| delta_e2000_rgb(g.0, e.0)));
        let t = stats(pairs().map(|(g, e)| delta_e2000_rgb(g.1, e.1)));
        println!(
            "{:<12} {:>10.4} {:>10.4} {:>10.4} {:>10.4}",
            s.to_string(),
            r.mean,
            r.max,
            t.mean,
            t.max
        );
        results.push((s, r, t));
    }
    let (_, r81, t81) = results[3];
    assert!(r81.max < 1.0 && t81.max < 1.0, "uniform:81 {r81:?} {t81:?}");
    for w in results[1..].windows(2) {
        let ((a, ra, ta), (b, rb, tb)) = (w[0], w[1]);
        assert!(
            rb.mean < ra.mean && rb.max < ra.max && tb.mean < ta.mean && tb.max < ta.max,
            "{b} is not better than {a}: {rb:?} {tb:?} vs {ra:?} {ta:?}"
        );
    }
    // The paper's point: three wavelengths miss the integrated colour, on
    // average by more than even nine integrated samples do.
    let (_, r3, _) = results[0];
    assert!(r3.mean > results[1].1.mean, "rgb3 {r3:?}");
}

#[cfg(feature = "cli")]
const SOAP_500NM: &str = "ambient = { n = 1.0 }\nsubstrate = { n = 1.0 }\n\
                          [[layers]]\nn = 1.33\nthickness_nm = 500.0\n";

/// A stack file in a scratch folder (removed with it).
#[cfg(feature = "cli")]
fn stack_file(text: &str) -> (Scratch, String) {
    let dir = Scratch::new("color");
    let path = dir.write("stack.toml", text).to_str().unwrap().to_owned();
    (dir, path)
}

#[cfg(feature = "cli")]
#[test]
fn cli_json_matches_the_library() {
    let (_dir, path) = stack_file(SOAP_500NM);
    let out = irid([
        "color",
        &path,
        "--angles",
        "0:80:40",
        "--sampling",
        "uniform:81",
        "--json",
    ]);
    assert!(out.success(), "{}", out.stderr);
    let json: serde_json::Value = serde_json::from_str(&out.stdout).unwrap();
    let rows = json.as_array().unwrap();
    assert_eq!(rows.len(), 3);
    let want = stack_colors(
        &soap_film(500.0),
        &SpectralIntegrator::new(Sampling::Uniform(81)),
        &[0.0, 40.0, 80.0],
    )
    .unwrap();
    for (row, want) in rows.iter().zip(&want) {
        let obj = row.as_object().unwrap();
        let mut keys: Vec<&str> = obj.keys().map(String::as_str).collect();
        keys.sort_unstable();
        assert_eq!(
            keys,
            [
                "angle_deg",
                "reflectance_rgb",
                "reflectance_xyz",
                "transmittance_rgb",
                "transmittance_xyz"
            ]
        );
        assert_eq!(obj["angle_deg"].as_f64().unwrap(), want.angle_deg);
        // serde_json's default float parsing may be off by an ulp.
        let triple = |k: &str| -> [f64; 3] {
            let v = obj[k].as_array().unwrap();
            std::array::from_fn(|i| v[i].as_f64().unwrap())
        };
        assert!(close(
            triple("reflectance_rgb"),
            want.reflectance_rgb,
            1e-15
        ));
        assert!(close(
            triple("transmittance_rgb"),
            want.transmittance_rgb,
            1e-15
        ));
        assert!(close(
            triple("reflectance_xyz"),
            want.reflectance_xyz,
            1e-15
        ));
        assert!(close(
            triple("transmittance_xyz"),
            want.transmittance_xyz,
            1e-15
        ));
    }
}

#[cfg(feature = "cli")]
#[test]
fn cli_human_output_has_a_hex_swatch_per_angle() {
    let (_dir, path) = stack_file("ambient = { n = 1.0 }\nsubstrate = { n = 1.5 }\n");
    let out = irid(["color", &path, "--angles", "0,30"]);
    assert!(out.success(), "{}", out.stderr);
    let text = out.stdout;
    // Bare glass at normal incidence: R = 0.04 → sRGB 56 = #38, T = 0.96 → 250 = #fa.
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 4, "{text}");
    assert!(
        lines[2].contains("#383838") && lines[2].contains("#fafafa"),
        "{text}"
    );
    assert!(lines[3].trim_start().starts_with("30.00°"), "{text}");
}

#[cfg(feature = "cli")]
#[test]
fn cli_bad_input_is_one_line_and_exit_2() {
    let (_dir, path) = stack_file(SOAP_500NM);
    for (args, needle) in [
        (vec!["--sampling", "rgb4"], "--sampling 'rgb4'"),
        (vec!["--sampling", "uniform:1"], "N must be between 2"),
        (vec!["--sampling", "uniform:x"], "not a whole number"),
        (vec!["--angles", "0,90"], "outside [0, 90)"),
        (vec!["--angles=-5:10:5"], "outside [0, 90)"),
        (vec!["--angles", "10:0:5"], "--angles"),
    ] {
        let mut full = vec!["color", path.as_str()];
        full.extend(&args);
        let out = irid(&full);
        out.assert_one_line_error(&format!("{args:?}"), &[needle]);
        assert!(out.stdout.is_empty());
    }
    let out = irid(["color", "/nonexistent/stack.toml"]);
    assert_eq!(out.code, Some(2));
    assert!(out.stderr.contains("/nonexistent/stack.toml"));
}

/// The exact sampling's 1 nm sum, without refinement: the stack solved at
/// each wavelength and integrated.
fn one_nm_color(integ: &SpectralIntegrator, stack: &Stack, cos: f64) -> ([f64; 3], [f64; 3]) {
    let grid = StackGrid::new(stack, integ.wavelengths_nm()).unwrap();
    let mut resp = vec![Response::default(); integ.wavelengths_nm().len()];
    grid.solve(&[cos], &mut resp);
    let r: Vec<f64> = resp.iter().map(|x| x.r()).collect();
    let t: Vec<f64> = resp.iter().map(|x| x.t()).collect();
    (integ.rgb(&r), integ.rgb(&t))
}

fn max_diff(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max)
}

/// The refined integration stands each 1 nm weight for a hat around its
/// wavelength: a flat spectrum keeps its white and a linear one its 1 nm
/// colour (the hat's average of a line is its value at the centre) at
/// every density, in both white conventions.
#[test]
fn refined_integration_keeps_flat_and_linear_spectra() {
    for white in [White::D65, White::E] {
        let base = SpectralIntegrator::with_white(Sampling::Exact, white);
        for m in [2, 8, 64] {
            let fine = base.refined(m);
            assert_eq!(
                fine.wavelengths_nm().len(),
                (base.wavelengths_nm().len() - 1) * m + 1
            );
            // The half hats at 360 and 830 nm average a line's slope over a
            // third of a step, through weights below 1e-5.
            let flat = |_: f64| 1.0;
            let line = |l: f64| 0.2 + 1e-3 * (l - 360.0);
            for (spectrum, tol) in [(&flat as &dyn Fn(f64) -> f64, 1e-12), (&line, 1e-8)] {
                let s0: Vec<f64> = base.wavelengths_nm().iter().map(|&l| spectrum(l)).collect();
                let s1: Vec<f64> = fine.wavelengths_nm().iter().map(|&l| spectrum(l)).collect();
                let (a, b) = (base.rgb(&s0), fine.rgb(&s1));
                assert!(max_diff(a, b) < tol, "{white:?} m {m}: {a:?} {b:?}");
                assert!(max_diff(base.xyz(&s0), fine.xyz(&s1)) < tol);
            }
        }
        // Other samplings are not refined.
        let uniform = SpectralIntegrator::with_white(Sampling::Uniform(41), white);
        assert_eq!(
            uniform.refined(8).wavelengths_nm(),
            uniform.wavelengths_nm()
        );
    }
}

/// A free-standing film 100 µm thick at cos θ 0.05 has fringes 1.4 nm apart
/// and about 0.1 nm wide: the 1 nm sum steps over them, the converged
/// colour is their average, which for a non-dispersive film is the
/// incoherent (phase-averaged) slab in closed form, 2 R₁ / (1 + R₁) per
/// polarization with R₁ the interface's Fresnel reflectance, a grey.
#[test]
fn thick_film_at_grazing_converges_to_the_incoherent_limit() {
    let (n, d) = (1.33f64, 100_000.0);
    let integ = SpectralIntegrator::new(Sampling::Exact);
    let stack = soap_film(d);
    let grey = |cos: f64| {
        let sin2 = 1.0 - cos * cos;
        let q = (n * n - sin2).sqrt();
        let rs = ((cos - q) / (cos + q)).powi(2);
        let rp = ((n * n * cos - q) / (n * n * cos + q)).powi(2);
        0.5 * (2.0 * rs / (1.0 + rs) + 2.0 * rp / (1.0 + rp))
    };
    for cos in [0.05f64, 0.02] {
        let angle = cos.acos().to_degrees();
        let color = &stack_colors(&stack, &integ, &[angle]).unwrap()[0];
        let want = grey(angle.to_radians().cos());
        let (r1, t1) = one_nm_color(&integ, &stack, angle.to_radians().cos());
        let converged = max_diff(color.reflectance_rgb, [want; 3]);
        let aliased = max_diff(r1, [want; 3]);
        eprintln!("cos {cos}: converged {converged:.2e}, 1 nm {aliased:.2e} (R {want:.4})");
        assert!(
            converged < 2e-3,
            "{:?} against {want}",
            color.reflectance_rgb
        );
        assert!(aliased > 5.0 * converged, "{r1:?}");
        // Lossless: what is not reflected is transmitted.
        let sum: [f64; 3] =
            std::array::from_fn(|k| color.reflectance_rgb[k] + color.transmittance_rgb[k]);
        assert!(max_diff(sum, [1.0; 3]) < 1e-9, "{sum:?} {t1:?}");
    }
}

/// Where every fringe spans several nanometres the colour is the 1 nm sum,
/// bit for bit.
#[test]
fn colour_is_the_1nm_sum_where_fringes_are_resolved() {
    let integ = SpectralIntegrator::with_white(Sampling::Exact, White::E);
    for d in [0.0, 120.0, 480.0, 1000.0] {
        let stack = soap_film(d);
        let refinement = Refinement::new(&stack, Some(1), &integ).unwrap();
        let angles = [0.0, 30.0, 60.0, 80.0, 88.0];
        let colors = stack_colors(&stack, &integ, &angles).unwrap();
        for (c, a) in colors.iter().zip(angles) {
            let cos = a.to_radians().cos();
            assert_eq!(refinement.sub_steps(d, cos), 1, "{d} nm at {a}°");
            let (r, t) = one_nm_color(&integ, &stack, cos);
            assert_eq!(
                (c.reflectance_rgb, c.transmittance_rgb),
                (r, t),
                "{d} nm at {a}°"
            );
        }
    }
}

/// Near grazing incidence the baker's sweep (rows of nodes) and the
/// reference at scattered points integrate the same converged colour, which
/// differs from the 1 nm sum by up to a hundredth and from itself at twice
/// the density by far less.
#[test]
fn baker_and_reference_agree_on_the_converged_colour() {
    let integ = SpectralIntegrator::new(Sampling::Exact);
    let film = Film::new(&soap_film(500.0), 1, integ.clone()).unwrap();
    let refinement = film.refinement().expect("the exact sampling is refined");
    let nodes: Vec<f64> = (0..=40).map(|k| 25.0 * f64::from(k)).collect();
    let rows: Vec<(f64, Vec<f64>)> = [0.001, 0.004, 0.02]
        .iter()
        .map(|&c| (c, nodes.clone()))
        .collect();
    let swept = film.rows(&rows).unwrap();
    let points: Vec<(f64, f64)> = rows
        .iter()
        .flat_map(|(c, t)| t.iter().map(move |&d| (d, *c)))
        .collect();
    let exact = film.points(&points).unwrap();
    let (mut refined, mut moved, mut unsettled) = (0, 0.0f64, 0.0f64);
    for ((&(d, c), s), e) in points.iter().zip(&swept).zip(&exact) {
        for k in 0..6 {
            // The sweep and the solver agree to 1e-11 this close to grazing.
            assert!((s[k] - e[k]).abs() < 1e-9, "{d} nm cos {c}: {s:?} {e:?}");
        }
        let m = refinement.sub_steps(d, c);
        if m == 1 {
            continue;
        }
        refined += 1;
        let (r1, _) = one_nm_color(&integ, &soap_film(d), c);
        moved = moved.max(max_diff(r1, [e[0], e[1], e[2]]));
        let thick = vec![d];
        let level = |m: usize| {
            let l = refinement.level(m).unwrap();
            l.grid.weighted_spectrum(&thick, c, &l.weights).reflectance
        };
        unsettled = unsettled.max(max_diff(level(m), level((2 * m).min(MAX_SUB_STEPS))));
    }
    eprintln!("{refined} refined nodes: moved up to {moved:.2e}, m against 2m {unsettled:.2e}");
    assert!(refined > 20 && moved > 3e-3 && unsettled < 1e-5);
}
