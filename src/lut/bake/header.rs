//! The header a baked table carries: its axes, channels, stack and the
//! bake check's figures.

use super::check::Check;
use crate::lut::axis::Axis;
use crate::lut::header::{
    version_for, BakeCheck, Channel, ColorInfo, ErrorInfo, Header, TableAtlas, ATLAS_AXIS,
    BAKE_CHECK_METRIC, COS_AXIS, FORMAT_NAME, THICKNESS_AXIS, WAVELENGTH_AXIS,
};
use crate::lut::sample::channel_names;
use crate::lut::{BakeSpec, Kind};
use crate::sweep::Grid;
use crate::sweep::Prepared;

pub(super) fn header(
    spec: &BakeSpec,
    prep: &Prepared,
    coarse: &Grid,
    check: Option<&Check>,
    target: Option<f64>,
) -> Header {
    let mut axes = vec![
        axis(THICKNESS_AXIS, "nm", coarse.axes[0].nodes.clone()),
        axis(COS_AXIS, "1", coarse.axes[1].nodes.clone()),
    ];
    if spec.kind == Kind::Spectral {
        axes.push(axis(WAVELENGTH_AXIS, "nm", coarse.axes[2].nodes.clone()));
    }
    let names = channel_names(spec.kind);
    Header {
        version: version_for(spec.white, false),
        x_axis: THICKNESS_AXIS.into(),
        y_axis: COS_AXIS.into(),
        axes,
        channels: channels(names),
        layer: if spec.stack.layers.is_empty() {
            0
        } else {
            prep.layer
        },
        error: ErrorInfo {
            target_max_abs: target,
            bake_check: check.map(|check| BakeCheck {
                metric: BAKE_CHECK_METRIC.into(),
                points: check.points,
                max_abs: check.max_channel.clone(),
                max_abs_all: check.max_all,
            }),
            validation: None,
        },
        ..common(spec)
    }
}

/// What every table of `spec` records, whatever its layout: the fields
/// the layout-specific headers do not set are placeholders.
fn common(spec: &BakeSpec) -> Header {
    Header {
        format: FORMAT_NAME.into(),
        version: 0,
        kind: spec.kind,
        x_axis: String::new(),
        y_axis: String::new(),
        y_blocks: (spec.kind == Kind::Spectral).then(|| WAVELENGTH_AXIS.into()),
        axes: Vec::new(),
        channels: Vec::new(),
        precision: if spec.half { "f16" } else { "f32" }.into(),
        stack: spec.stack.clone(),
        layer: if spec.stack.layers.is_empty() {
            0
        } else {
            spec.layer
        },
        color: ColorInfo {
            white: spec.white,
            illuminant: spec.white.illuminant().into(),
            observer: "CIE 1931 2°".into(),
            space: "linear sRGB (ITU-R BT.709 primaries, D65 white)".into(),
            sampling: spec.sampling.to_string(),
        },
        error: ErrorInfo {
            target_max_abs: None,
            bake_check: None,
            validation: None,
        },
        tool: format!("irid {}", env!("CARGO_PKG_VERSION")),
        cache_key: spec.cache_key(),
        atlas: None,
    }
}

fn axis(name: &str, unit: &str, nodes: Vec<f64>) -> Axis {
    Axis {
        name: name.into(),
        unit: unit.into(),
        nodes,
    }
}

/// The header's channel list for these names.
fn channels(names: &[&str]) -> Vec<Channel> {
    names
        .iter()
        .map(|n| Channel {
            name: (*n).into(),
            meaning: channel_meaning(n),
        })
        .collect()
}

fn channel_meaning(name: &str) -> String {
    let (quantity, rest) = name.split_once('.').unwrap_or((name, ""));
    let what = if quantity == "reflectance" {
        "unpolarized reflectance"
    } else {
        "unpolarized transmittance (power into the substrate)"
    };
    match rest {
        "" => format!("{what} at the node's wavelength"),
        c => format!("{what}, linear sRGB {c} under D65 (a perfect reflector is 1)"),
    }
}

/// The metric of an atlas table's bake check.
const ATLAS_CHECK_METRIC: &str = "largest absolute difference (relative to the exact value where \
    that exceeds 1 in magnitude: |table - exact| / max(1, |exact|)), per channel, between the table \
    (bilinear in each chart's coordinates, f32 weights) and irid's solver at the bake's random \
    points where its target applies (cos θ at or above atlas.aliased_below_cos and outside \
    atlas.critical_band_cos)";

/// The header of an atlas table of `spec` (layer `layer` of the evaluated
/// stack), with the charts of `built` and their measurement; a spectral
/// table's texels hold `wavelengths_nm`.
pub(super) fn atlas_header(
    spec: &BakeSpec,
    layer: usize,
    built: &crate::atlas::search::Built,
    lossless_white: Option<[f64; 3]>,
    wavelengths_nm: &[f64],
) -> Header {
    let (t0, t1) = spec.thickness_nm;
    let (c0, c1) = spec.cos_theta;
    let ends = |a: f64, b: f64| if b > a { vec![a, b] } else { vec![a] };
    let mut axes = vec![
        axis(THICKNESS_AXIS, "nm", ends(t0, t1)),
        axis(COS_AXIS, "1", ends(c0, c1)),
    ];
    if spec.kind == Kind::Spectral {
        axes.push(axis(WAVELENGTH_AXIS, "nm", wavelengths_nm.to_vec()));
    }
    let mut header = Header {
        version: version_for(spec.white, true),
        x_axis: ATLAS_AXIS.into(),
        y_axis: ATLAS_AXIS.into(),
        axes,
        layer: if spec.stack.layers.is_empty() {
            0
        } else {
            layer
        },
        atlas: Some(TableAtlas {
            atlas: built.atlas.clone(),
            aliased_below_cos: built.sides.first().map_or(0.0, |s| s.aliased_below),
            critical_band_cos: built
                .sides
                .first()
                .and_then(|s| s.unsought_band)
                .map(|(a, b)| [a, b]),
            lossless_white,
        }),
        ..common(spec)
    };
    header.channels = channels(header.channel_names());
    let measured = built.measured.first().map(|m| &m.resolved);
    // A spectral texel's channels are R at each wavelength, then T: the
    // table's two channels take the largest of each half.
    let per_channel = |max_abs: &[f64]| -> Vec<f64> {
        if spec.kind != Kind::Spectral {
            return max_abs.to_vec();
        }
        let half = max_abs.len() / 2;
        let max = |v: &[f64]| v.iter().fold(0.0f64, |a, &b| a.max(b));
        vec![max(&max_abs[..half]), max(&max_abs[half..])]
    };
    header.error = ErrorInfo {
        target_max_abs: match spec.resolution {
            crate::lut::Resolution::MaxError(e) if e.is_finite() => Some(e),
            _ => None,
        },
        bake_check: measured.map(|m| BakeCheck {
            metric: ATLAS_CHECK_METRIC.into(),
            points: m.points,
            max_abs_all: m.max_all(),
            max_abs: per_channel(&m.max_abs),
        }),
        validation: None,
    };
    header
}
